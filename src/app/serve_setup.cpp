#include "app/serve_setup.h"

#include "core/clock.h"
#include "core/error.h"
#include "core/install_paths.h"
#include "core/mpi.h"
#include "core/system_memory.h"
#include "dataset/dataset_format.h"
#include "server/rank_pool.h"
#include "server/series_progress.h"
#include "server/step_cache.h"
#include "server/server.h"

#include <fmt/format.h>
#include <spdlog/spdlog.h>

#include <tbb/task_arena.h>

#include <atomic>
#include <chrono>
#include <condition_variable>
#include <cstdio>
#include <cstdlib>
#include <exception>
#include <functional>
#include <map>
#include <memory>
#include <mutex>
#include <optional>
#include <thread>

namespace raypc::app {

namespace {
std::optional<std::filesystem::path> given(const std::string& text)
{
    return text.empty() ? std::nullopt : std::optional<std::filesystem::path>(text);
}
}  // namespace

void ServeFlags::add(CLI::App& cmd)
{
    cmd.add_option("--port", port, "TCP port; 0 picks a free one (printed at start)")
        ->capture_default_str()
        ->check(CLI::Range(0, 65535));
    cmd.add_option("--host", host, "Address to listen on; anything but 127.0.0.1 and ::1 requires the access token printed at start")
        ->capture_default_str();
    cmd.add_option("--assets", assets, "Directory of the built UI (default: $RAYPC_ASSETS, web/dist, ...)");
    cmd.add_option("--examples", examples,
                   "Directory of example states offered as presets (default: $RAYPC_EXAMPLES, the source tree's examples/)");
    cmd.add_option("--allow-origin", allowOrigins,
                   "Origin of another page allowed to use the server, e.g. http://viz.lab:8080 (repeatable); "
                   "its host is also accepted as Host on loopback");
    cmd.add_option("--max-sessions", limits.maxSessions, "Open WebSocket sessions (browser tabs) at most")
        ->capture_default_str()
        ->check(CLI::Range(1, 4096));
    cmd.add_option("--max-connections", limits.maxConnections, "Open connections (HTTP and WebSocket) at most")
        ->capture_default_str()
        ->check(CLI::Range(2, 100000));
    cmd.add_option("--session-memory", sessionMemoryMiB,
                   fmt::format("Frame memory of all sessions together, MiB (a session's image costs width x height x {} "
                               "bytes)",
                               server::kFrameBytesPerPixel))
        ->capture_default_str()
        ->check(CLI::Range(1, 1 << 24));
    cmd.add_option("--step-cache", stepCache,
                   "Memory for the steps in use (their levels and decoded variables, shared by all sessions), "
                   "e.g. 8G or 512M (default: half of the memory available at start)");
    cmd.add_option("--frame-cache", frameCache,
                   fmt::format("Memory for each session's frames rendered ahead (playback from memory), e.g. 256M; "
                               "0: none rendered ahead (default: {}M)",
                               server::ServerLimits{}.frameCacheBytes >> 20));
}

namespace {

server::ServerOptions serverOptions(const std::filesystem::path& dataset, const ServeFlags& flags)
{
    server::ServerOptions options;
    options.dataset = dataset;
    options.host = flags.host;
    options.port = uint16_t(flags.port);
    options.assets = findAssetDir(given(flags.assets));
    options.examples = findExamplesDir(given(flags.examples));
    options.allowedOrigins = flags.allowOrigins;
    options.limits = flags.limits;
    options.limits.sessionFrameBytes = flags.sessionMemoryMiB << 20;
    options.cacheBytes = flags.stepCache.empty() ? server::StepCache::defaultBytes()
                                                 : size_t(parseMemorySize(flags.stepCache, "--step-cache"));
    if (flags.frameCache == "0")
        options.limits.frameCacheBytes = 0;  // no frames rendered ahead
    else if (!flags.frameCache.empty())
        options.limits.frameCacheBytes = size_t(parseMemorySize(flags.frameCache, "--frame-cache"));
    spdlog::info("step cache: {}{}; frames rendered ahead: {} a session", formatBytes(options.cacheBytes),
                 flags.stepCache.empty() ? " (half of the memory available)" : "",
                 formatBytes(options.limits.frameCacheBytes));
    return options;
}

// Where the UI and presets come from, then the one parseable line "raypc: serving URL" (serve_setup.h).
void announce(const server::ServerOptions& options, const server::Server& srv)
{
    if (options.assets)
        spdlog::info("serving the UI from {}", options.assets->string());
    else
        spdlog::warn("the browser UI is not built (no web/dist found); serving a placeholder page and the API");
    if (options.examples)
        spdlog::info("presets from {}", options.examples->string());
    fmt::print("raypc: serving {}\n", srv.url());
    std::fflush(stdout);
}

// `raypc serve` on every rank of the job (one process: just the Server): rank 0 builds the Server
// (with a RankPool when there are other ranks) and serves until SIGINT/SIGTERM; the other ranks run
// WorkerRank. Opening the dataset and binding the port are agreed on by all ranks, so a bad dataset
// or a busy port stops every rank with one message. `onServing` runs on rank 0 once the port is
// bound (to print the URL). MPI stays on the calling (main) thread; the network runs on another.
// Throws raypc::Error as Server's constructor does, and when a rank stopped answering.
void serveOnRanks(server::ServerOptions options, const std::function<void(const server::Server&)>& onServing)
{
    std::optional<server::RankPool> pool;
    std::unique_ptr<server::Server> srv;
    std::unique_ptr<server::WorkerRank> worker;
    mpi::together([&] {
        if (!mpi::isRoot()) {
            worker = std::make_unique<server::WorkerRank>(options.dataset, options.cacheBytes, options.cacheEntries);
            return;
        }
        if (mpi::distributed())
            options.ranks = &pool.emplace();
        srv = std::make_unique<server::Server>(options);
    });
    if (worker) {
        worker->run();
        return;
    }
    if (pool)
        spdlog::info("distributed: every pass is shared out over {} ranks", pool->ranks());
    onServing(*srv);
    if (!pool) {
        srv->run();
        return;
    }
    // MPI calls stay on this (the main) thread (core/mpi.h): the network runs on another, and the
    // server, whose sessions may wait on the pool, is destroyed there before the pool stops.
    std::exception_ptr failure;
    std::mutex serverMutex;  // srv: reset on the network thread, stopped from this one
    std::thread network([&] {
        try {
            srv->run();
        } catch (...) {
            failure = std::current_exception();
        }
        {
            std::lock_guard lock(serverMutex);
            srv.reset();
        }
        pool->stop();
    });
    std::string broken;
    const bool clean = pool->run([&](const std::string& why) {
        broken = why;
        std::lock_guard lock(serverMutex);
        if (srv)
            srv->stop();
    });
    network.join();
    if (failure)
        std::rethrow_exception(failure);
    if (!clean)
        fail("{}", broken);
}

// Test hook (docs/protocol.md, GET /api/progress): with RAYPC_TEST_HOLD_SERIES=FILE set, the
// background run goes on after step 0 only once FILE exists, so that a test sees step 0 served alone.
void holdForTest(const std::atomic<bool>& cancel)
{
    const char* file = std::getenv("RAYPC_TEST_HOLD_SERIES");
    if (!file || std::filesystem::exists(file))
        return;
    spdlog::info("test hook RAYPC_TEST_HOLD_SERIES: waiting for {}", file);
    while (!cancel && !std::filesystem::exists(file))
        std::this_thread::sleep_for(std::chrono::milliseconds(50));
}

}  // namespace

void serveDataset(const std::filesystem::path& dataset, const ServeFlags& flags,
                  const std::optional<std::filesystem::path>& second)
{
    if (second)
        mpi::together([] {
            if (mpi::distributed())
                fail("serving a pair of datasets is for one process; under mpirun serve one dataset");
        });
    keepLargeBlocksForReuse();  // frame buffers come and go with every state
    server::ServerOptions options = serverOptions(dataset, flags);
    options.second = second;
    serveOnRanks(options, [&](const server::Server& srv) { announce(options, srv); });
}

void serveSeries(const SeriesInputs& inputs, const preprocess::PreprocessOptions& preprocessOptions, const ServeFlags& flags)
{
    if (!inputs.fromFiles()) {
        serveDataset(inputs.dataset, flags);
        return;
    }
    mpi::together([] {
        if (mpi::distributed())
            fail("serving netCDF files is for one process; under mpirun preprocess them first (mpirun raypc "
                 "preprocess FILES -o DATASET), then mpirun raypc serve DATASET");
    });
    const size_t steps = inputs.files.size();
    if (datasetOfFiles(inputs.dataset, inputs.files) || steps == 1) {
        // Complete (the run only checks the settings), or one step: nothing to show before it.
        spdlog::info("{}: the dataset of {} netCDF file{}", inputs.dataset.string(), steps, steps == 1 ? "" : "s");
        prepareSeries(inputs, preprocessOptions);
        serveDataset(inputs.dataset, flags);
        return;
    }
    keepLargeBlocksForReuseOnEveryThread();  // the series' arrays are made on the background thread
    const auto start = std::chrono::steady_clock::now();
    auto progress = std::make_shared<server::SeriesProgress>(inputs.dataset, int(steps));

    // The whole series in the background from the start. Once its step 0 is written, the background
    // thread makes the preview of it (hard links: preparePreview) before it reads on, and that step
    // alone is served; when the series is complete the server is replaced by one of the whole series
    // on the same port (and token): open pages reload (docs/protocol.md, /api/progress). The
    // background thread's share of the machine: every core, in a task arena of low priority (oneTBB
    // gives its threads to the renderer's arena first whenever that has work), the thread itself at
    // a lower priority than the renderer's (nice + 10) once it has started the thread that reads the
    // steps ahead, which keeps the renderer's: reading is the series' critical path.
    std::atomic<bool> cancel{false};
    std::mutex mutex;  // guards the five below
    std::condition_variable changed;
    bool previewMade = false, ended = false, succeeded = false, switching = false;
    std::exception_ptr previewFailure;
    std::unique_ptr<server::Server> srv;  // the preview's: stopped from the background thread once the series is ready
    const std::filesystem::path firstStepManifest = dataset::format::stepDir(inputs.dataset, 0) / dataset::format::kStepManifest;
    auto makePreview = [&] {
        const double seconds = preparePreview(inputs, preprocessOptions);
        spdlog::info("{}: step 0 ready in {:.1f} s (its preview in {:.2f} s); the other {} steps follow in the "
                     "background into {}",
                     inputs.files.front().filename().string(), secondsSince(start), seconds, steps - 1,
                     inputs.dataset.string());
    };
    std::thread background([&] {
        preprocess::PreprocessOptions o = preprocessOptions;
        o.quiet = true;
        o.cancel = &cancel;
        o.niceIncrement = 10;
        std::map<std::string, int> loggedTenth;  // by phase: the steps' and the pathlines' alternate
        bool previewTried = false;
        o.onProgress = [&](const preprocess::PreprocessProgress& p) {
            progress->update(p);
            const int tenth = p.total > 0 ? 10 * p.done / p.total : 10;
            if (const auto [it, isNew] = loggedTenth.try_emplace(p.phase, tenth); isNew || it->second != tenth) {
                it->second = tenth;
                if (p.done > 0)
                    spdlog::info("background preprocessing: {} {} of {}", p.phase, p.done, p.total);
            }
            // Called once the finished steps are known, then after each step: step 0 is there to show.
            if (previewTried || p.phase != "steps" || !std::filesystem::exists(firstStepManifest))
                return;
            previewTried = true;
            std::exception_ptr failure;
            try {
                makePreview();
            } catch (...) {
                failure = std::current_exception();
            }
            {
                std::lock_guard lock(mutex);
                previewMade = !failure;
                previewFailure = failure;
            }
            changed.notify_all();
            holdForTest(cancel);
        };
        bool ok = false;
        try {
            tbb::task_arena(tbb::task_arena::automatic, 1, tbb::task_arena::priority::low).execute([&] {
                prepareSeries(inputs, o, true);  // the preview is served until the server of the series replaces it
            });
            progress->finished();
            ok = true;
        } catch (const std::exception& e) {
            if (!cancel) {
                spdlog::error("background preprocessing stopped: {}; serving step 0 only", e.what());
                progress->failed(e.what());
            }
        }
        std::lock_guard lock(mutex);
        ended = true;
        succeeded = ok;
        changed.notify_all();
        if (ok && srv && !cancel) {
            switching = true;
            srv->stop();
        }
    });
    // The background run is stopped and joined however this thread leaves (a first file that cannot
    // be read, a port in use).
    struct StopOnExit {
        std::thread& thread;
        std::atomic<bool>& cancel;
        ~StopOnExit()
        {
            cancel = true;
            if (thread.joinable())
                thread.join();
        }
    } stopOnExit{background, cancel};

    server::ServerOptions options = serverOptions(inputs.previewDir(), flags);
    options.series = progress;
    {
        std::unique_lock lock(mutex);
        changed.wait(lock, [&] { return previewMade || previewFailure || ended; });
        if (previewFailure)
            std::rethrow_exception(previewFailure);
        if (!previewMade && !succeeded) {
            // The series stopped before its step 0 (a later file it cannot read): the first file alone.
            lock.unlock();
            makePreview();
            lock.lock();
        }
        if (!succeeded)  // else the series was finished before a preview was served: it is served at once
            srv = std::make_unique<server::Server>(options);
    }
    if (srv) {
        announce(options, *srv);
        srv->run();
        {
            std::lock_guard lock(mutex);
            if (!switching) {
                cancel = true;
                spdlog::info("stopping the background preprocessing (finished steps stay in {}; the next run resumes)",
                             inputs.dataset.string());
            }
        }
        background.join();
        if (succeeded)
            removePreview(inputs);  // served no more: the first server has stopped
        if (!switching)
            return;
        options.port = srv->port();
        options.token = srv->token();
        srv.reset();
        options.dataset = inputs.dataset;
        options.series = nullptr;
        srv = std::make_unique<server::Server>(options);
        spdlog::info("{}: all {} steps are ready; serving them at the same address", inputs.dataset.string(), steps);
        srv->run();
        return;
    }
    background.join();
    removePreview(inputs);
    spdlog::info("{}: all {} steps are ready", inputs.dataset.string(), steps);
    serveDataset(inputs.dataset, flags);
}

}  // namespace raypc::app
