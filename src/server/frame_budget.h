// The frame memory of a server's sessions (`--session-memory`, ServerLimits::sessionFrameBytes):
// what each session's newest state reserves for its image (width x height x kFrameBytesPerPixel)
// and the finished frames its frame cache keeps (server/frame_cache.h), together within one limit.
//
// A state's image comes first: when it does not fit, the kept frames of every session are dropped
// (reclaimKeptFrames) and it is tried again, since a kept frame is only a copy that playback can
// render again; a kept frame is let in only while it fits beside the images.
//
// Thread safety: every member function may be called from any thread. Lock order: the list of
// frame caches, then a frame cache's own lock, then the budget's counters.
#pragma once

#include <cstddef>
#include <mutex>
#include <vector>

namespace raypc::server {

class FrameCache;

class FrameBudget {
public:
    explicit FrameBudget(size_t limitBytes) : m_limit(limitBytes) {}
    FrameBudget(const FrameBudget&) = delete;
    FrameBudget& operator=(const FrameBudget&) = delete;

    // Replaces a session's image reservation `held` by `wanted` bytes if the total stays within the
    // limit; otherwise returns false and leaves everything as it was. `othersBytes` receives what the
    // other sessions' images and every kept frame hold (for the error message).
    bool replace(size_t& held, size_t wanted, size_t& othersBytes)
    {
        std::lock_guard lock(m_mutex);
        othersBytes = m_used - held;
        if (othersBytes + wanted > m_limit)
            return false;
        m_used = othersBytes + wanted;
        held = wanted;
        return true;
    }
    void release(size_t& held)
    {
        std::lock_guard lock(m_mutex);
        m_used -= held;
        held = 0;
    }

    // A kept frame of `bytes`: taken when it fits (true), else nothing changes (false).
    bool takeKept(size_t bytes)
    {
        std::lock_guard lock(m_mutex);
        if (m_used + bytes > m_limit)
            return false;
        m_used += bytes;
        m_kept += bytes;
        return true;
    }
    // Whether a kept frame of `bytes` would fit now.
    bool fitsKept(size_t bytes) const
    {
        std::lock_guard lock(m_mutex);
        return m_used + bytes <= m_limit;
    }
    void returnKept(size_t bytes)
    {
        std::lock_guard lock(m_mutex);
        m_used -= bytes;
        m_kept -= bytes;
    }

    // Frame caches whose kept frames reclaimKeptFrames may drop; a cache registers for its lifetime
    // (FrameCache does so itself when given a budget).
    void addCache(FrameCache* cache);
    void removeCache(FrameCache* cache);
    // Drops the kept frames of every registered cache (so that an image fits); returns the bytes freed.
    size_t reclaimKeptFrames();

    size_t limit() const { return m_limit; }
    size_t usedBytes() const
    {
        std::lock_guard lock(m_mutex);
        return m_used;
    }
    size_t keptBytes() const
    {
        std::lock_guard lock(m_mutex);
        return m_kept;
    }

private:
    mutable std::mutex m_mutex;
    size_t m_limit, m_used = 0, m_kept = 0;
    std::mutex m_cachesMutex;
    std::vector<FrameCache*> m_caches;
};

}  // namespace raypc::server
