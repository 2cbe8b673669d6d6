// The server's shared reading of a dataset (docs/protocol.md): the bounded caches of pathline
// windows and persistence pairs beside the step cache (server/step_cache.h), as the sources of the
// renderers, and the set of them every process of a server opens.
//
// Thread safety: the caches may be used from any thread.
#pragma once

#include "core/lru_cache.h"
#include "dataset/dataset.h"
#include "analysis/pathline_storage.h"
#include "analysis/persistence.h"
#include "render/state_renderer.h"
#include "server/analysis_caches.h"
#include "server/step_cache.h"

#include <filesystem>
#include <memory>
#include <utility>
#include <vector>

namespace raypc::server {

// A bounded cache of pathline windows (loadPathlineWindow) by (step, window), least recently used
// out. get() throws raypc::Error like loadPathlineWindow (e.g. a dataset without pathlines).
class PathlineCache {
public:
    using Window = std::vector<analysis::PathlineSet>;
    PathlineCache(std::filesystem::path datasetDir, size_t maxEntries = 4);
    std::shared_ptr<const Window> get(int step, int window);

private:
    std::filesystem::path m_dir;
    LruCache<std::pair<int, int>, Window> m_cache;  // by (step, window)
};

// The persistence pairs (analysis/persistence.h) of one step's variable at level 0, computed once per
// (step, variable) and kept for the last `maxEntries`, least recently used out: a full-resolution
// step takes seconds (docs/persistence.md). get() throws raypc::Error like the volume loader.
class PersistenceCache {
public:
    using Pairs = std::vector<analysis::PersistencePair>;
    PersistenceCache(StepCache* volumes, size_t maxEntries = 4);
    std::shared_ptr<const Pairs> get(int step, int variable);

private:
    StepCache* m_volumes;
    LruCache<std::pair<int, int>, Pairs> m_cache;  // by (step, variable)
};

// The server's shared caches as the sources of a render::StateRenderer (valid while they live);
// without `labels` the renderer extracts the painted features' labels itself.
render::StateSources cacheSources(StepCache* volumes, PathlineCache* lines, FeatureLabelsCache* labels = nullptr);

// What a server process reads a dataset through: the dataset and its volume and pathline caches,
// built alike by the Server and by every other rank of a distributed server (rank_pool.h).
struct DatasetCaches {
    std::shared_ptr<const dataset::Dataset> dataset;
    std::unique_ptr<StepCache> volumes;
    std::unique_ptr<PathlineCache> pathlines;
};
// Opens `dir` (throws raypc::Error as Dataset::open does); the volume cache holds at most
// `cacheBytes` and `cacheEntries` volumes.
DatasetCaches openDatasetCaches(const std::filesystem::path& dir, size_t cacheBytes, size_t cacheEntries);

}  // namespace raypc::server
