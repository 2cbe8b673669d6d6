// A session's frames rendered ahead: the finished frames of one state at many steps, so that
// playback shows steps from memory at full quality (docs/protocol.md, "Frames rendered ahead").
//
// The cache holds the frames of one key at a time: the state's document without its step and its
// time budget (frameCacheKey). A new key drops every frame (any change but the step invalidates);
// a frame that does not fit in the bound is refused, never let in by evicting another: playback
// loops over the steps, so the frames kept are as good as any (LRU would evict each frame just
// before it is shown again).
//
// The kept frames count in the server's frame memory (`--session-memory`, server/frame_budget.h)
// when the cache is given the budget: a frame that does not fit there is refused as well, and the
// budget may drop every kept frame to make room for a session's image.
//
// Thread safety: every member function may be called from any thread.
#pragma once

#include "server/frame_budget.h"

#include <nlohmann/json.hpp>

#include <cstddef>
#include <cstdint>
#include <map>
#include <memory>
#include <mutex>
#include <string>
#include <vector>

namespace raypc::server {

// The level most steps of playback reached, from how many reached each level (countsByLevel[l]):
// their median, a tie going to the finer level; -1 when there are none. The drafts rendered ahead
// are one level finer (RenderSession::draftLevel): the finest level reached instead would follow
// one step that happened to render finer (the first, on a throughput measured on a still) and make
// every draft too costly to render within a loop.
int typicalPlaybackLevel(const std::vector<int>& countsByLevel);

// A finished frame as the session sends it, before its per-request fields (id, mode) are set.
struct EncodedFrame {
    nlohmann::json header;  // the frame header (protocol_schema.cpp) without jpegBytes/depth sizes
    std::string jpeg;
    std::vector<float> depth;  // km, depthWidth x depthHeight
    int depthWidth = 0, depthHeight = 0;
    // Every pass of its state (or converged before): a still frame. False for a draft, the first
    // pass alone, rendered ahead while playing so that a loop has a level-0 frame of each step soon.
    bool finished = true;

    size_t bytes() const;  // what it costs to keep
};

// The key of a state's frames in the cache: its document (state::toJson) less `step` and
// `timeBudgetMs`, which do not change a still frame's pixels.
std::string frameCacheKey(const nlohmann::json& document);

class FrameCache {
public:
    // `budget` (may be null: no shared bound) must outlive the cache; the cache registers with it.
    explicit FrameCache(size_t maxBytes, FrameBudget* budget = nullptr);
    ~FrameCache();
    FrameCache(const FrameCache&) = delete;
    FrameCache& operator=(const FrameCache&) = delete;

    // Makes `key` the cache's key; a different one from before drops every frame.
    void setKey(const std::string& key);
    // The frame of `step` under `key`; nullptr when none (or `key` is not the current one), or when
    // the kept frame is a draft whose level (its header's) is coarser than `draftsUpToLevel` (-1: a
    // finished frame only).
    std::shared_ptr<const EncodedFrame> find(const std::string& key, int step, int draftsUpToLevel = -1);
    bool contains(const std::string& key, int step, bool finishedOnly = true) const;
    // Keeps the frame when `key` is the current key and it fits in the bound; returns whether it did.
    // A finished frame replaces a draft of its step; nothing else replaces a kept frame.
    bool insert(const std::string& key, int step, std::shared_ptr<const EncodedFrame> frame);
    // Whether one more frame of about `bytes` would still fit (in the cache's bound and the budget).
    bool hasRoomFor(size_t bytes) const;
    // Drops every frame (the key stays); returns the bytes freed. FrameBudget::reclaimKeptFrames.
    size_t clear();

    size_t bytes() const;
    size_t frames() const;
    uint64_t hits() const;  // frames found so far
    size_t maxBytes() const { return m_maxBytes; }

private:
    void dropLocked();

    size_t m_maxBytes;
    FrameBudget* m_budget;
    mutable std::mutex m_mutex;
    std::string m_key;
    std::map<int, std::shared_ptr<const EncodedFrame>> m_frames;  // by step
    size_t m_bytes = 0;
    uint64_t m_hits = 0;
};

}  // namespace raypc::server
