// The HTTP API of docs/protocol.md without network types: the route table {method, path, lane,
// handler} that the HTTP connection dispatches on, and what the endpoints compute, as functions that
// are tested on their own.
//
// Thread safety: the free functions and the handlers are reentrant; PathlineCache may be used from
// any thread.
#pragma once

#include "core/lru_cache.h"
#include "data/dataset.h"
#include "data/pathline_storage.h"
#include "data/persistence.h"
#include "data/selection.h"
#include "render/state_renderer.h"
#include "server/limits.h"
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

// The directory of example states: `explicitDir` if given (throws raypc::Error if it is not a
// directory), else $RAYPC_EXAMPLES, else the source tree's examples/ (compiled in), else
// <exe dir>/examples; nullopt when none exists.
std::optional<std::filesystem::path> findExamplesDir(const std::optional<std::filesystem::path>& explicitDir);

// Every *.json in `dir` except demo.json, sorted by file name, as [{name, title, state}]: name is
// the file name without .json, title a short human title (a table of the known presets; else the
// name with spaces), state the parsed document. A file that is not JSON is left out with a warning.
// With `dataset`, a preset that cannot be applied to it (its step clamped to the last, as the UI
// does) gets `unavailable`: why, from resolveState (e.g. a variable the dataset lacks), so that the
// UI shows it disabled with the reason. An empty array when `dir` is nullopt.
nlohmann::json presetsJson(const std::optional<std::filesystem::path>& dir, const Dataset* dataset = nullptr);

// The selected volume of every step and the depth profile of `profileStep`, at `level`
// ({level, steps: [{step, timeMyr, volumeKm3, fractionOfMantle}], profile: {step, radiusKm,
// depthKm, volumeKm3, shellVolumeKm3}}). Volumes come through `cache` without evicting what the
// renderers use. Throws raypc::Error for a level out of range, or when `cancel` becomes true (checked
// before every step).
nlohmann::json selectionStatsJson(const Dataset& dataset, StepCache& cache, std::span<const RangeFilter> filters,
                                  int level, int profileStep, const std::atomic<bool>* cancel = nullptr);

// A bounded cache of pathline windows (loadPathlineWindow) by (step, window), least recently used
// out. get() throws raypc::Error like loadPathlineWindow (e.g. a dataset without pathlines).
class PathlineCache {
public:
    using Window = std::vector<PathlineSet>;
    PathlineCache(std::filesystem::path datasetDir, size_t maxEntries = 4);
    std::shared_ptr<const Window> get(int step, int window);

private:
    std::filesystem::path m_dir;
    LruCache<std::pair<int, int>, Window> m_cache;  // by (step, window)
};

// The line attributes of a window as one binary answer: u32 little-endian header length, a UTF-8
// JSON header {step, window, lines, columns, units, sets: [{injectionStep, injectionTimeMyr, lines}]},
// then lines x columns float32 little-endian, row-major, lines in set order (oldest set first).
std::string pathlineAttributesPayload(const PathlineCache::Window& sets, int step, int window);

// The persistence pairs (data/persistence.h) of one step's variable at level 0, computed once per
// (step, variable) and kept for the last `maxEntries`, least recently used out: a full-resolution
// step takes about 2 s (docs/persistence.md). get() throws raypc::Error like the volume loader.
class PersistenceCache {
public:
    using Pairs = std::vector<PersistencePair>;
    PersistenceCache(StepCache* volumes, size_t maxEntries = 4);
    std::shared_ptr<const Pairs> get(int step, int variable);

private:
    StepCache* m_volumes;
    LruCache<std::pair<int, int>, Pairs> m_cache;  // by (step, variable)
};

// GET /api/persistence (docs/protocol.md): the persistence diagram of `variable` at `step`, at most
// `top` pairs by decreasing persistence ({kind, birth, death, persistence, birthLat, birthLon,
// birthDepthKm, lat, lon, depthKm}: the lower end's position and the extremum's, degrees and km),
// the count and largest persistence of the rest, the count of each kind, the step's range; and
// `stored`: the threshold and rule the stored pathline set of the step was seeded with, its line count
// and whether its lines carry the "seed persistence" column, or null when the dataset has no
// pathlines or they were seeded on another variable.
nlohmann::json persistenceDiagramJson(const SphericalGrid& grid, const std::vector<PersistencePair>& pairs, int step,
                                      const std::string& variable, const std::string& units, size_t top,
                                      const PathlineSet* stored);

// The server's shared caches as the sources of a render::StateRenderer (valid while they live).
render::StateSources cacheSources(StepCache* volumes, PathlineCache* lines);

// What a server process reads a dataset through: the dataset and its volume and pathline caches,
// built alike by the Server and by every other rank of a distributed server (rank_pool.h).
struct DatasetCaches {
    std::shared_ptr<const Dataset> dataset;
    std::unique_ptr<StepCache> volumes;
    std::unique_ptr<PathlineCache> pathlines;
};
// Opens `dir` (throws raypc::Error as Dataset::open does); the volume cache holds at most
// `cacheBytes` and `cacheEntries` volumes.
DatasetCaches openDatasetCaches(const std::filesystem::path& dir, size_t cacheBytes, size_t cacheEntries);

// What the handlers read: shared by every connection of a server, immutable after start (the caches
// and the linked state are thread-safe).

struct ApiContext {
    std::shared_ptr<const Dataset> dataset;
    StepCache* cache = nullptr;
    PathlineCache* pathlines = nullptr;
    PersistenceCache* persistence = nullptr;
    std::optional<std::filesystem::path> examples;  // presets directory (findExamplesDir)
    std::string infoJson;                           // GET /api/info, built once (infoJson())
    ServerLimits limits;
    std::shared_ptr<const SeriesProgress> series;   // GET /api/progress; nullptr: a complete dataset
    LinkedState* link = nullptr;                    // GET/POST /api/link (the server's, server_context.h)
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
};

enum class HttpMethod { Get, Post };

// Where a handler runs (server_context.h): on the network thread (only answers that are ready or take
// microseconds, without a body to parse), on the worker pool (quick requests), or one at a time in the
// lane of statistics over time or of screenshots (long requests, with a bounded queue).
enum class Lane { Network, Worker, Statistics, Screenshot };

// A handler throws raypc::Error for a bad request (the connection answers 400 with its message).
using ApiHandler = ApiAnswer (*)(const ApiContext&, const ApiRequest&);

struct Route {
    HttpMethod method;
    std::string_view path;
    Lane lane;
    ApiHandler handler;
};

// Every /api/ endpoint of docs/protocol.md.
std::span<const Route> apiRoutes();

// GET /api/info: the dataset's variables, coordinates, steps, levels, sample shape, colour maps and
// default state (docs/protocol.md).
nlohmann::json infoJson(const Dataset& dataset, const ServerLimits& limits = {});

}  // namespace raypc::server
