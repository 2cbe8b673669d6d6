// What the HTTP endpoints answer (docs/protocol.md; their shapes described once in
// server/protocol_schema.cpp), computed from the dataset and the caches without network types, so
// that each is tested on its own: the dataset's info, the presets, the selection over time, the
// pathline attributes' payload and the persistence diagram.
//
// Thread safety: reentrant.
#pragma once

#include "dataset/dataset.h"
#include "analysis/features.h"
#include "analysis/persistence.h"
#include "analysis/selection.h"
#include "server/analysis_caches.h"
#include "server/dataset_caches.h"
#include "server/limits.h"
#include "server/step_cache.h"

#include <nlohmann/json.hpp>

#include <atomic>
#include <functional>
#include <future>
#include <filesystem>
#include <optional>
#include <span>
#include <string>
#include <vector>

namespace raypc::server {

// GET /api/info: the dataset's variables, coordinates, steps, levels, sample shape, colour maps and
// default state (docs/protocol.md).
nlohmann::json infoJson(const dataset::Dataset& dataset, const ServerLimits& limits = {});

// GET /api/info's `pair` key when the server serves a pair (docs/compare.md, "Side by side"):
// `index` (which of the two this info is about, 0 or 1) and both datasets' names and step times.
nlohmann::json pairJson(int index, const dataset::Dataset& first, const dataset::Dataset& second);

// Every *.json in `dir` except demo.json, sorted by file name, as [{name, title, state}]: name is
// the file name without .json, title a short human title (the directory's titles.tsv; else the
// name with spaces), state the parsed document. A file that is not JSON is left out with a warning.
// With `dataset`, a preset that cannot be applied to it (its step clamped to the last, as the UI
// does) gets `unavailable`: why, from resolveState (e.g. a variable the dataset lacks), so that the
// UI shows it disabled with the reason. An empty array when `dir` is nullopt.
nlohmann::json presetsJson(const std::optional<std::filesystem::path>& dir, const dataset::Dataset* dataset = nullptr);

// The selected volume of every step and the depth profile of `profileStep`, at `level`
// ({level, steps: [{step, timeMyr, volumeKm3, fractionOfMantle}], profile: {step, radiusKm,
// depthKm, volumeKm3, shellVolumeKm3}}). Volumes come through `cache` without evicting what the
// renderers use. Throws raypc::Error for a level out of range, or when `cancel` becomes true (checked
// before every step computed). With `selections` each step's statistics come from that cache and
// are kept there (the same numbers, so the same bytes). With `allProfiles` also `profiles`: every
// step's {step, volumeKm3, shellVolumeKm3} per radius, so that a client follows the step without
// asking again. `computed`, when given, is increased by the steps computed (not taken from a cache).
nlohmann::json selectionStatsJson(const dataset::Dataset& dataset, StepCache& cache, std::span<const analysis::RangeFilter> filters,
                                  int level, int profileStep, const std::atomic<bool>* cancel = nullptr,
                                  SelectionCache* selections = nullptr, bool allProfiles = false, int* computed = nullptr);

// The other ranks of a distributed server (server/rank_pool.h) for a features request: `ranks`
// processes, this one the first; the steps are split into contiguous blocks as mpi::blockOf does.
struct FeatureRanks {
    int ranks = 1;
    // Hands a job to ranks 1..ranks-1, each answering featureBlockOfJob of its block; the future gives
    // their answers in rank order, or throws raypc::Error naming a rank that failed.
    std::function<std::shared_future<std::vector<std::string>>(nlohmann::json job)> shareOut;
};

// What rank `rank` of `ranks` answers a features job (featureSeriesJson's, through FeatureRanks):
// its block's steps (analysis::packBlockStep). Throws raypc::Error for a bad job or level, what the
// steps' features throw, and when `cancel` becomes true.
std::string featureBlockOfJob(const dataset::Dataset& dataset, StepCache& cache, const nlohmann::json& job, int rank,
                              int ranks, const std::atomic<bool>* cancel);

// POST /api/features (docs/protocol.md, FeatureSeries): the features of the selection `filters` in
// every step at `level` (extractFeatures with `options`), followed through the steps (FeatureSeries,
// links counting from `minOverlapShare`): every track with its points, stalls at the options' depths
// and events; the events in step order; and, when the dataset has a radial velocity, the flux across
// the shells at those depths (inside the grid) per step with the avalanche steps (`sigmas`).
// Volumes come through `cache` without evicting. Throws raypc::Error for no filters, a level out of
// range, a dataset without velocity, or when `cancel` becomes true (checked before every step).
// `progress` hears the steps done before each step and at the end; `labels`, when set, is shown
// each step's feature labels found by this process (to copy some for the painted features:
// FeatureLabelsCache). With `ranks`, the steps are shared out over them, and the answer is the same.
nlohmann::json featureSeriesJson(const dataset::Dataset& dataset, StepCache& cache, std::span<const analysis::RangeFilter> filters,
                                 const analysis::FeatureOptions& options, double minOverlapShare, analysis::StallMeasure stallBy,
                                 int level, double sigmas, const std::atomic<bool>* cancel = nullptr,
                                 const std::function<void(int done, int total)>& progress = {},
                                 const std::function<void(int step, const HugePageVector<int32_t>& labels)>& labels = {},
                                 const FeatureRanks* ranks = nullptr);

// The line attributes of a window as one binary answer: u32 little-endian header length, a UTF-8
// JSON header {step, window, lines, columns, units, sets: [{injectionStep, injectionTimeMyr, lines}]},
// then lines x columns float32 little-endian, row-major, lines in set order (oldest set first).
std::string pathlineAttributesPayload(const PathlineCache::Window& sets, int step, int window);

// GET /api/persistence (docs/protocol.md): the persistence diagram of `variable` at `step`, at most
// `top` pairs by decreasing persistence ({kind, birth, death, persistence, birthLat, birthLon,
// birthDepthKm, lat, lon, depthKm}: the lower end's position and the extremum's, degrees and km),
// the count and largest persistence of the rest, the count of each kind, the step's range; and
// `stored`: the threshold and rule the stored pathline set of the step was seeded with, its line count
// and whether its lines carry the "seed persistence" column, or null when the dataset has no
// pathlines or they were seeded on another variable.
nlohmann::json persistenceDiagramJson(const grid::SphericalGrid& grid, const std::vector<analysis::PersistencePair>& pairs, int step,
                                      const std::string& variable, const std::string& units, size_t top,
                                      const analysis::PathlineSet* stored);

}  // namespace raypc::server
