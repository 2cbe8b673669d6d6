// The render work of one WebSocket session, on its own thread, decoupled from the network.
//
// Frames rendered ahead (docs/protocol.md, "Frames rendered ahead"): a second thread, at a lower
// priority (nice 10, a low-priority TBB arena), renders the session's current state at the steps
// after the one asked for, at still quality (the state's level, else level 0, its passes, full
// size), into the session's FrameCache, while playing and while paused. A state whose step has a
// finished frame there is answered with it at once ("cached": true); a still state's own finished
// frame goes in as well. It starts once the session moves in time (a step of playback, or a state of
// another step than the last), so that a session looking at one step costs only its own frames;
// while it has steps to render, a step of playback gets one pass (no refinement), leaving the cores
// to it. A bound of 0 bytes (--frame-cache 0) turns it off. Any change but the step (camera, transfer function, brushes, size,
// quality...) gives another key and drops the frames.
//
// The newest state wins: submit() replaces any state that has not started and cancels the pass in
// flight (the renderer checks the flag before every tile); states in between are dropped, never
// queued. An interactive state gets one pass at the finest level whose estimated pass time fits the
// state's time budget (from a throughput measured on earlier passes); a still state gets
// state.passes progressive passes at the state's level (level 0 when "auto"); a step of playback
// gets its level as an interactive state does and then progressive passes (FrameMode). Every pass
// is sent as one binary frame (protocol.h) through the sink.
//
// Thread safety: submit, cancel and stop may be called from any one thread (the network thread);
// the sink is called from the render thread and must hand the bytes over (e.g. post them).
#pragma once

#include "dataset/dataset.h"
#include "render/pathline_scene.h"
#include "render/state_renderer.h"
#include "render/volume_renderer.h"
#include "server/dataset_api.h"
#include "server/frame_cache.h"
#include "server/protocol.h"
#include "server/step_cache.h"

#include <atomic>
#include <chrono>
#include <condition_variable>
#include <functional>
#include <map>
#include <memory>
#include <mutex>
#include <optional>
#include <string>
#include <thread>

namespace raypc::server {

class RankPool;

// Shared by all sessions of a server.
struct RenderContext {
    std::shared_ptr<const dataset::Dataset> dataset;
    StepCache* cache = nullptr;
    PathlineCache* pathlines = nullptr;  // line windows shared by the sessions (each builds its own scene)
    FeatureLabelsCache* featureLabels = nullptr;  // the painted features' labels, shared with POST /api/features
    // Throughput of the machine in estimated samples (VolumeRenderer::estimateSamplesPerPass) per
    // second, all threads; updated from every pass, used to choose the interactive level.
    std::atomic<double> samplesPerSecond{0.0};
    // Seconds an interactive frame takes outside its pass (preparing it, its picture and JPEG): an
    // exponential average over the sessions' interactive frames, which their level choice leaves
    // room for (LevelPolicy::overheadSeconds).
    std::atomic<double> frameOverheadSeconds{0.0};
    RankPool* ranks = nullptr;  // a distributed server's (rank_pool.h): passes go to every rank
    // The second dataset of a pair (docs/compare.md): the first, whose states its sessions are sent
    // and draw through render::secondOfPair. nullptr: the first or only dataset.
    std::shared_ptr<const dataset::Dataset> pairFirst;
    // Each session's bound of frames rendered ahead (FrameCache; ServerLimits::frameCacheBytes).
    size_t frameCacheBytes = size_t(256) << 20;
    // The server's frame memory (`--session-memory`), which the kept frames count in; null: not counted.
    FrameBudget* frameBudget = nullptr;
};

// Throws raypc::Error when a resolved state's image is over what a session renders (4096 x 4096
// pixels, both eyes of a stereo pair counted; larger images are for POST /api/screenshot).
void checkSessionImage(const state::RenderState& state);

// Where a session's output goes, with the id of the state it answers (frames, and the errors of a
// state), so that the receiver need not parse it back out of the bytes.
struct SessionSink {
    std::function<void(std::string text, int64_t stateId)> sendText;
    std::function<void(std::string frame, int64_t stateId)> sendBinary;
};

class RenderSession {
public:
    RenderSession(RenderContext& context, SessionSink sink, std::string name);
    ~RenderSession();  // stop()
    RenderSession(const RenderSession&) = delete;
    RenderSession& operator=(const RenderSession&) = delete;

    // Validates the state against the dataset (throws raypc::Error naming the key; the previous
    // state stays in force) and makes it the newest request. A pair's second dataset takes the
    // first's state through render::secondOfPair.
    void submit(int64_t id, state::RenderState state, FrameMode mode);
    // Stops the current work; no more frames until the next submit.
    void cancel();
    // Cancels and joins the render thread. Idempotent.
    void stop();

    const std::string& name() const { return m_name; }
    // The frames rendered ahead (tests, the log).
    const FrameCache& frameCache() const { return m_frameCache; }

private:
    struct Request {
        int64_t id = 0;
        render::ResolvedState resolved;
        nlohmann::json pair;  // a pair's second dataset: the frame header's `pair` (its notes); else null
        FrameMode mode = FrameMode::still;
        std::chrono::steady_clock::time_point received;  // for the log: waiting and preparation time
    };
    // One request's frames: what every frame of it shares.
    struct Job {
        const Request& request;
        nlohmann::json document;  // the state as the document says it: the frames' camera, the selection's key
        nlohmann::json shellKey;  // the reference shells drawn, as the pictures' legend names them
        bool interactive = false;
        int passes = 1;
        int ranks = 1;
        double encodeMs = 0;  // all frames' encoding so far
    };
    void loop();
    // The thread that renders ahead (the class comment): the steps after m_ahead's, not yet kept.
    void aheadLoop();
    // Renders `request`'s state as a still frame (its level, full size) with `renderer`, all its
    // passes or at most `maxPasses` (a draft when that stops it early); nullptr when cancelled.
    std::shared_ptr<const EncodedFrame> renderFinished(render::StateRenderer& renderer, const Request& request,
                                                       const std::atomic<bool>& cancel, int maxPasses);
    // The level of a draft rendered ahead while playing (draftLevel in render_session.cpp).
    int draftLevel(const state::RenderState& state) const;
    // Tells the ahead thread what the session shows now: the state (its key) and its step.
    void planAhead(const Request& request, const std::string& key);
    // Sends a kept frame as the answer to `request`.
    void sendKept(const EncodedFrame& kept, const Request& request);
    // Prepares the request's state (a preview first where it helps), renders its passes and sends
    // each frame the client should see.
    void render(const Request& request);
    // One pass of `prepared` into `frames`, on every rank of a distributed server; a pass that
    // rendered every pixel updates the shared throughput measure.
    render::PassStats renderPass(const Job& job, uint64_t frameNumber, int pass,
                                 const render::StateRenderer::Prepared& prepared, render::ViewFrames& frames);
    // The accumulation of a pass as a frame (its header, JPEG and depth), drawn by `renderer`.
    std::shared_ptr<EncodedFrame> makeFrame(const render::StateRenderer& renderer, Job& job,
                                            const render::ViewFrames& frames,
                                            const render::StateRenderer::Prepared& prepared,
                                            const render::PassStats& stats, int pass, bool last, bool preview,
                                            const nlohmann::json& selection) const;
    // Encodes a frame as one binary frame (protocol.h) and sends it.
    void send(const EncodedFrame& frame, int64_t id);
    // makeFrame, then send; returns the frame.
    std::shared_ptr<EncodedFrame> sendFrame(Job& job, const render::ViewFrames& frames,
                                            const render::StateRenderer::Prepared& prepared,
                                            const render::PassStats& stats, int pass, bool last, bool preview,
                                            const nlohmann::json& selection);
    // The selection's statistics of the prepared state's brushes on `level` of `step`, unless `key`
    // (step, level, brushes) says they are the last ones computed.
    void updateSelection(const std::string& key, int step, int level, const render::StateRenderer::Prepared& prepared);

    RenderContext& m_context;
    SessionSink m_sink;
    std::string m_name;

    std::mutex m_mutex;
    std::condition_variable m_cv;
    std::optional<Request> m_pending;
    bool m_stopping = false;
    std::atomic<bool> m_cancel{false};

    // Render thread only.
    render::StateRenderer m_renderer;
    int m_lastStep = -1;
    bool m_renderAhead = false;  // the session has moved in time: its states are rendered ahead
    uint64_t m_rankSession = 0;  // this session's id in m_context.ranks
    uint64_t m_frames = 0;       // frames started (a distributed pass names its frame)
    std::string m_selectionKey;
    nlohmann::json m_selection;

    // Rendering ahead: the newest state shown (its key and step), guarded by m_aheadMutex; the
    // ahead thread's own renderer.
    struct AheadPlan {
        std::string key;
        Request request;
    };
    FrameCache m_frameCache;
    std::mutex m_aheadMutex;
    std::condition_variable m_aheadCv;
    std::optional<AheadPlan> m_ahead;
    bool m_aheadChanged = false;
    std::atomic<bool> m_aheadStop{false};
    std::atomic<bool> m_aheadBusy{false};  // the ahead thread has steps to render
    // The level most steps of playback of this frame key rendered here reached
    // (typicalPlaybackLevel), -1 before any; and how many reached each level (session thread only).
    std::atomic<int> m_playbackLevel{-1};
    std::vector<int> m_playbackLevelCounts;
    std::string m_playbackKey;  // session thread only
    std::atomic<bool> m_aheadCancel{false};
    render::StateRenderer m_aheadRenderer;
    std::thread m_aheadThread;

    std::thread m_thread;  // last member: starts after everything above exists
};

}  // namespace raypc::server
