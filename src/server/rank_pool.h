// The ranks of a distributed server (`mpirun -np N raypc serve`, docs/scaling.md): every pass of
// every session is split into tiles over all N ranks — rank r renders the tiles t with t mod N = r,
// as `raypc render --time T` does under mpirun — and the sums of the other ranks' tiles are gathered
// on rank 0, so a session's frame equals the frame one process renders, bit for bit.
//
// Rank 0 serves HTTP and WebSocket as alone. Its session threads call RankPool::renderPass, which
// renders rank 0's own tiles on the calling thread while the main thread — the only thread that
// calls MPI (core/mpi.h: MPI_THREAD_FUNNELED) — runs RankPool::run: it sends the pass to the other
// ranks, collects their tiles, and sends a cancel when the session's state changes mid-pass (the
// ranks stop between tiles, as the renderer stops for its own cancel flag). Passes of several
// sessions take turns on the ranks (one at a time). Ranks 1..N-1 run WorkerRank::run: one
// StateRenderer per session, kept until the session closes, so a pass after the first reuses the
// mapped volume and the accumulated frame as a lone process does.
//
// Jobs besides passes (a features request's blocks of steps: server/api_views.h FeatureRanks) go to
// every other rank at once and are answered when each is done, while passes go on: a rank works on
// a job on a thread of its own and sends its answer without waiting for rank 0 to take it
// (mpi::PendingSend), and rank 0's main thread takes answers between passes.
//
// Messages (tagged byte strings): a pass is JSON (the state document, the level and size divisor
// rank 0 chose, the pass number), and so is a frame to prepare ahead of its first pass (the same
// without the pass number; no answer); a worker answers every pass exactly once with a JSON header
// (statistics, "cancelled", or "error" with its message) followed by its tiles'
// FrameBuffer::packTiles floats, one block per view.
//
// A rank that dies: under Open MPI's mpirun the whole job ends (the launcher sends SIGTERM to the
// other ranks and prints which rank exited); rank 0 then stops serving as on Ctrl-C. A rank that
// stops answering without dying: after a cancel, or when the server stops, rank 0 waits at most
// kAnswerTimeoutSeconds, then fails the session's pass naming the rank, stops serving and exits
// with an error (Open MPI cannot continue without a rank).
#pragma once

#include "core/mpi.h"
#include "render/state_renderer.h"
#include "server/dataset_api.h"
#include "server/server.h"
#include "server/step_cache.h"

#include <atomic>
#include <chrono>
#include <condition_variable>
#include <cstdint>
#include <deque>
#include <filesystem>
#include <functional>
#include <future>
#include <map>
#include <memory>
#include <mutex>
#include <optional>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

namespace raypc::server {

inline constexpr double kAnswerTimeoutSeconds = 10.0;

// Rank 0's side. Thread safety: openSession, closeSession, renderPass and stop from any thread;
// run on the main thread only.
class RankPool {
public:
    RankPool();  // on rank 0 of a distributed run (mpi::distributed())
    ~RankPool();
    RankPool(const RankPool&) = delete;
    RankPool& operator=(const RankPool&) = delete;

    int ranks() const { return m_ranks; }

    // A new session's id for renderPass; closeSession lets the other ranks drop its frames.
    uint64_t openSession();
    void closeSession(uint64_t session);

    // Lets the other ranks prepare frame `frame` of `resolved` at `choice` now, while rank 0 prepares
    // it too, rather than when its first pass arrives (the preparation of a full-resolution still
    // took about as long as its pass). Optional: renderPass prepares what was not. Never throws for
    // a rank's failure: that rank reports it with the first pass.
    void prepare(uint64_t session, uint64_t frame, const render::ResolvedState& resolved,
                 render::LevelChoice choice);

    // One pass of `prepared` (prepared for `resolved` on rank 0) into `frames`, on every rank.
    // `frame` numbers the session's frames: a new number (with pass 1) makes the other ranks prepare
    // the state anew; later passes of the same frame continue their accumulated tiles. Blocks until
    // every rank has answered; stops early (PassStats::cancelled) when `cancel` becomes true. The
    // statistics are every rank's, the time is the pass's wall time. Throws raypc::Error naming the
    // rank when a rank failed (e.g. could not read the data) or stopped answering.
    render::PassStats renderPass(uint64_t session, uint64_t frame, int pass, const render::ResolvedState& resolved,
                                 const render::StateRenderer::Prepared& prepared, render::ViewFrames& frames,
                                 const std::atomic<bool>* cancel);

    // Hands `job` (JSON, given a "seq") to ranks 1..N-1, each answering it with WorkerRank's job
    // handler (featureBlockOfJob); the future gives their answers in rank order, or an Error naming
    // a rank that failed or did not answer within kAnswerTimeoutSeconds of a cancel (`cancel`
    // becoming true, or the server stopping), or saying that the job was cancelled. `cancel` is
    // read until the future is ready: the caller keeps it alive that long.
    std::shared_future<std::vector<std::string>> shareOut(nlohmann::json job, const std::atomic<bool>* cancel);

    // The main thread: hands out passes until stop(), then tells the other ranks to stop. Returns
    // false when a rank stopped answering (after calling `onBroken`, which should stop the server).
    bool run(const std::function<void(const std::string& why)>& onBroken);
    void stop();

private:
    struct Task {
        uint64_t seq = 0;
        int tag = 0;
        std::string bytes;
        const std::atomic<bool>* cancel = nullptr;  // passes only
        std::promise<std::vector<std::string>> answers;  // passes only: ranks 1..N-1's, in rank order
    };
    std::vector<std::string> collect(const Task& task, bool& broken, std::string& why);
    // Jobs handed out and not yet answered by every rank.
    struct Job {
        std::unique_ptr<Task> task;
        std::vector<std::optional<std::string>> answers;  // ranks 1..N-1
        std::optional<std::chrono::steady_clock::time_point> cancelledAt;
    };
    void takeJobAnswers();  // receives what has arrived, ends the jobs answered, cancelled or silent
    std::map<uint64_t, Job> m_jobs;  // by seq; the main thread's

    int m_ranks;
    std::mutex m_mutex;
    std::condition_variable m_cv;
    std::deque<std::unique_ptr<Task>> m_queue;
    bool m_stopping = false;
    std::string m_broken;  // set when a rank stopped answering: every later pass fails with it
    uint64_t m_nextSession = 1, m_nextSeq = 1;
};

// Ranks 1..N-1. Thread safety: one thread (the main thread).
class WorkerRank {
public:
    // Opens the dataset (throws raypc::Error as Dataset::open does).
    WorkerRank(const std::filesystem::path& dataset, size_t cacheBytes, size_t cacheEntries);
    ~WorkerRank();
    // Renders the passes rank 0 hands out until it says stop.
    void run();

private:
    struct Session;
    Session& session(uint64_t id);  // created on first use
    void prepare(Session& s, const nlohmann::json& job);  // frame `job.frame` at its level and divisor
    void prepareAhead(const std::string& job);
    std::string renderPass(const std::string& job);
    void startJob(const std::string& job);
    void noteCancel(const std::string& seq);  // a pass's (renderPass polls for it) or a job's
    void sendFinishedJobs();
    void endJobs();  // cancels what runs, waits for it and for the answers sent

    DatasetCaches m_caches;
    struct RunningJob {
        std::atomic<bool> cancel{false};
        std::future<std::string> answer;
    };
    std::map<uint64_t, std::unique_ptr<RunningJob>> m_jobs;  // by seq
    std::vector<std::unique_ptr<mpi::PendingSend>> m_sent;
    std::map<uint64_t, std::unique_ptr<Session>> m_sessions;
};

}  // namespace raypc::server

