// The HTTP API of docs/protocol.md without network types: the route table {method, path, lane,
// handler} that the HTTP connection dispatches on. What the endpoints compute is in
// server/api_views.h, the caches they read in server/dataset_caches.h.
//
// Thread safety: the handlers are reentrant.
#pragma once

#include "dataset/dataset.h"
#include "server/analysis_caches.h"
#include "server/api_views.h"
#include "server/dataset_caches.h"
#include "server/limits.h"
#include "server/job_progress.h"
#include "server/linked_state.h"
#include "server/series_progress.h"
#include "server/step_cache.h"

#include <nlohmann/json.hpp>

#include <atomic>
#include <filesystem>
#include <memory>
#include <mutex>
#include <optional>
#include <span>
#include <string>
#include <string_view>
#include <vector>

namespace raypc::server {

class RankPool;

// What the handlers read: shared by every connection of a server, immutable after start (the caches
// and the linked state are thread-safe).

struct ApiContext {
    std::shared_ptr<const dataset::Dataset> dataset;
    StepCache* cache = nullptr;
    PathlineCache* pathlines = nullptr;
    PersistenceCache* persistence = nullptr;
    std::optional<std::filesystem::path> examples;  // presets directory (findExamplesDir)
    std::string infoJson;                           // GET /api/info, built once (infoJson())
    ServerLimits limits;
    std::shared_ptr<const SeriesProgress> series;   // GET /api/progress; nullptr: a complete dataset
    LinkedState* link = nullptr;                    // GET/POST /api/link (the server's, server_context.h)
    JobProgress* jobs = nullptr;                    // POST /api/features?job=, GET /api/job-progress
    // A pair (docs/compare.md, "Side by side"). The second dataset's context: the first, whose states
    // the endpoints taking a state are sent (render::secondOfPair makes them its own). The first's:
    // the second's context, which a screenshot of a state with `pair` draws at its right.
    std::shared_ptr<const dataset::Dataset> pairFirst;
    const ApiContext* pairSecond = nullptr;
    // Kept analyses (server/analysis_caches.h); nullptr: computed for each request.
    SelectionCache* selections = nullptr;       // POST /api/stats, /api/selection, /api/time-depth
    FeatureSeriesCache* featureSeries = nullptr;  // POST /api/features
    FeatureLabelsCache* featureLabels = nullptr;  // the painted features (POST /api/features puts its step's)
    // A distributed server's ranks (server/rank_pool.h), which POST /api/features shares its steps
    // out over; nullptr: one process.
    RankPool* ranks = nullptr;
};

// One API request as the handlers see it: the percent-encoded query, the body, and a flag that
// becomes true when the answer is no longer wanted (the client closed the connection, or the server
// is stopping); long handlers check it and throw.
struct ApiRequest {
    std::string_view query;
    std::string_view body;
    const std::atomic<bool>* cancel = nullptr;
};

struct ApiAnswer {
    std::string body;
    std::string contentType;
    // Answers over the steps: how many steps this request computed (0: all from the kept analyses),
    // sent as the header X-Raypc-Steps-Computed (docs/protocol.md); -1: no such header.
    int stepsComputed = -1;
};

enum class HttpMethod { Get, Post };

// Where a handler runs (server_context.h): on the network thread (only answers that are ready or take
// microseconds, without a body to parse), on the worker pool (quick requests), or one at a time in the
// lane of statistics over time or of screenshots (long requests, with a bounded queue).
enum class Lane { Network, Worker, Statistics, Screenshot, Slice };

// A handler throws raypc::Error for a bad request (the connection answers 400 with its message).
using ApiHandler = ApiAnswer (*)(const ApiContext&, const ApiRequest&);

struct Route {
    HttpMethod method;
    std::string_view path;
    Lane lane;
    ApiHandler handler;
    std::string_view parameters;  // the query parameters it takes, comma-separated (besides `token`)
    // Whether it answers about one dataset, so that it takes `dataset` (a pair's 0 or 1) too.
    bool perDataset = true;
};

// Every /api/ endpoint of docs/protocol.md.
std::span<const Route> apiRoutes();

// Throws raypc::Error (answered 400) for a query parameter `route` does not take or one given
// twice, naming it and the parameters the route takes, as unknown JSON keys are refused.
void checkQueryParameters(const Route& route, std::string_view query);

// The dataset a request is about: its `dataset` query parameter (0 when absent), or that of a /ws
// upgrade (`route` nullptr). Throws raypc::Error (answered 400) for a value other than an index of
// the `datasets` served, naming it and what the server serves.
int datasetOfQuery(const Route* route, std::string_view query, int datasets);

}  // namespace raypc::server
