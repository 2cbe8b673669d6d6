// What every connection of one `raypc serve` shares: the options, the dataset and its caches, the
// thread pools the work runs on, the registry of render sessions, the linked state, and the
// accounting behind the limits of limits.h. Internal to the server library (Asio types are allowed
// here; nothing outside src/server includes this header).
//
// Thread safety: the options, dataset, caches, token, assets and API context are set before the first
// connection and only read after; the caches and the linked state are thread-safe; every other member
// guards itself.
#pragma once

#include "server/access.h"
#include "server/dataset_api.h"
#include "server/limits.h"
#include "server/render_session.h"
#include "server/server.h"
#include "server/step_cache.h"

#include <boost/asio/thread_pool.hpp>

#include <atomic>
#include <memory>
#include <mutex>
#include <optional>
#include <string>
#include <vector>

namespace raypc::server {

// A pool of threads for one kind of work, and how many jobs it holds (running or waiting).
class JobLane {
public:
    JobLane(const char* name, int threads, size_t maxJobs) : m_name(name), m_pool(size_t(threads)), m_maxJobs(maxJobs) {}
    const char* name() const { return m_name; }
    boost::asio::thread_pool& pool() { return m_pool; }
    // Counts a job in; false (nothing counted) when the lane already holds its maximum.
    bool tryEnter()
    {
        size_t n = m_jobs.load();
        do {
            if (n >= m_maxJobs)
                return false;
        } while (!m_jobs.compare_exchange_weak(n, n + 1));
        return true;
    }
    void leave() { --m_jobs; }
    size_t maxJobs() const { return m_maxJobs; }

private:
    const char* m_name;
    boost::asio::thread_pool m_pool;
    size_t m_maxJobs;
    std::atomic<size_t> m_jobs{0};
};

// The cancellation flags of the API jobs in flight, so that shutdown stops them all at once.
class JobRegistry {
public:
    // A flag for a new job; already set when the server is stopping.
    std::shared_ptr<std::atomic<bool>> add()
    {
        auto flag = std::make_shared<std::atomic<bool>>(false);
        std::lock_guard lock(m_mutex);
        std::erase_if(m_flags, [](const auto& w) { return w.expired(); });
        if (m_stopping)
            flag->store(true);
        m_flags.push_back(flag);
        return flag;
    }
    void cancelAll()
    {
        std::lock_guard lock(m_mutex);
        m_stopping = true;
        for (const auto& weak : m_flags)
            if (auto flag = weak.lock())
                flag->store(true);
    }

private:
    std::mutex m_mutex;
    bool m_stopping = false;
    std::vector<std::weak_ptr<std::atomic<bool>>> m_flags;
};

// The second dataset of a pair (ServerOptions::second): what the first has in ServerContext, its own.
struct SecondDataset {
    std::shared_ptr<const dataset::Dataset> dataset;
    std::unique_ptr<StepCache> cache;
    std::unique_ptr<PathlineCache> pathlines;
    std::unique_ptr<PersistenceCache> persistence;
    // Its kept analyses: their keys do not name the dataset, so the first's must not answer for it.
    SelectionCache selections;
    FeatureSeriesCache featureSeries{8};
    FeatureLabelsCache featureLabels;
    ApiContext api;
    RenderContext render;
};

struct ServerContext {
    explicit ServerContext(ServerOptions serverOptions)
        : options(std::move(serverOptions)),
          frameBudget(options.limits.sessionFrameBytes),
          screenshots("screenshots", 1, 1 + options.limits.maxWaitingJobs),
          statistics("statistics", 1, 1 + options.limits.maxWaitingJobs),
          slices("slices", 1, 1 + options.limits.maxWaitingJobs)
    {
    }

    ServerOptions options;
    FrameBudget frameBudget;
    std::shared_ptr<const dataset::Dataset> dataset;
    std::unique_ptr<StepCache> cache;
    std::unique_ptr<PathlineCache> pathlines;
    std::unique_ptr<PersistenceCache> persistence;
    SelectionCache selections;            // kept selection statistics per step; api.selections points here
    FeatureSeriesCache featureSeries{8};  // kept features answers; api.featureSeries points here
    FeatureLabelsCache featureLabels;     // painted features' labels; api.featureLabels, render.featureLabels
    ApiContext api;
    RenderContext render;
    LinkedState link;  // the state the UI shows, for programs (GET/POST /api/link); api.link points here
    JobProgress jobProgress;  // where long statistics requests are (GET /api/job-progress); api.jobs points here
    std::string token;  // empty on loopback
    SitePolicy site;
    std::optional<std::filesystem::path> assets;
    std::unique_ptr<SecondDataset> second;  // a pair's second dataset; nullptr: one dataset

    // How many datasets are served (1, or 2 for a pair), and the contexts of dataset `index` (checked
    // by datasetOfQuery, dataset_api.h).
    int datasetCount() const { return second ? 2 : 1; }
    const ApiContext& apiOf(int index) const { return index == 1 ? second->api : api; }
    RenderContext& renderOf(int index) { return index == 1 ? second->render : render; }

    // Where work runs besides the network thread (docs/reliability.md, Server): the quick API
    // requests; screenshots, statistics over time and map or section pictures one at a time each
    // (a 4096² Robinson map takes seconds), so that none can hold up the quick requests or the
    // others; the WebSocket messages (parsing, validation, hand-over to the render thread), which
    // never wait behind an API request.
    JobLane screenshots, statistics, slices;
    JobLane workers{"workers", 2, SIZE_MAX};
    boost::asio::thread_pool messages{1};
    JobRegistry jobs;

    std::atomic<size_t> openConnections{0}, openSessions{0};
    std::atomic<uint64_t> sessionCounter{0};
    // Every session's render work, so that shutdown can stop it before the io_context goes away.
    std::mutex sessionsMutex;
    std::vector<std::weak_ptr<RenderSession>> sessions;
};

}  // namespace raypc::server
