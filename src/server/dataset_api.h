// What the HTTP endpoints /api/presets, /api/stats and /api/pathlines compute (docs/protocol.md),
// as functions without network types so that they are tested on their own.
//
// Thread safety: the free functions are reentrant; PathlineCache may be used from any thread.
#pragma once

#include "data/dataset.h"
#include "data/pathline_storage.h"
#include "data/selection.h"
#include "server/step_cache.h"

#include <nlohmann/json.hpp>

#include <filesystem>
#include <list>
#include <memory>
#include <mutex>
#include <optional>
#include <span>
#include <string>
#include <vector>

namespace raypc::server {

// The directory of example states: `explicitDir` if given (throws raypc::Error if it is not a
// directory), else $RAYPC_EXAMPLES, else the source tree's examples/ (compiled in), else
// <exe dir>/examples; nullopt when none exists.
std::optional<std::filesystem::path> findExamplesDir(const std::optional<std::filesystem::path>& explicitDir);

// Every *.json in `dir` except demo.json, sorted by file name, as [{name, title, state}]: name is
// the file name without .json, title a short human title (a table of the known presets; else the
// name with spaces), state the parsed document. A file that is not JSON is left out with a warning.
// An empty array when `dir` is nullopt.
nlohmann::json presetsJson(const std::optional<std::filesystem::path>& dir);

// The selected volume of every step and the depth profile of `profileStep`, at `level`
// ({level, steps: [{step, timeMyr, volumeKm3, fractionOfMantle}], profile: {step, radiusKm,
// depthKm, volumeKm3, shellVolumeKm3}}). Volumes come through `cache` without evicting what the
// renderers use. Throws raypc::Error for a level out of range.
nlohmann::json selectionStatsJson(const Dataset& dataset, StepCache& cache, std::span<const RangeFilter> filters,
                                  int level, int profileStep);

// A bounded cache of pathline windows (loadPathlineWindow) by (step, window), least recently used
// out. get() throws raypc::Error like loadPathlineWindow (e.g. a dataset without pathlines).
class PathlineCache {
public:
    using Window = std::vector<PathlineSet>;
    PathlineCache(std::filesystem::path datasetDir, size_t maxEntries = 4);
    std::shared_ptr<const Window> get(int step, int window);

private:
    struct Entry {
        int step, window;
        std::shared_ptr<const Window> sets;
    };
    std::filesystem::path m_dir;
    size_t m_maxEntries;
    std::mutex m_mutex;
    std::list<Entry> m_lru;
};

// The line attributes of a window as one binary answer: u32 little-endian header length, a UTF-8
// JSON header {step, window, lines, columns, units, sets: [{injectionStep, injectionTimeMyr, lines}]},
// then lines x columns float32 little-endian, row-major, lines in set order (oldest set first).
std::string pathlineAttributesPayload(const PathlineCache::Window& sets, int step, int window);

}  // namespace raypc::server
