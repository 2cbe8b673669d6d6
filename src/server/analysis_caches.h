// The server's kept analyses (docs/scaling.md, "Analyses over a series"): the selection statistics of
// each step and the answers of feature series, so that asking again for a brush, or for a brush over
// all steps after only the step changed, costs only what was never computed.
//
// Thread safety: every member function from any thread; concurrent requests of one key share one
// computation (core/lru_cache.h).
#pragma once

#include "core/huge_pages.h"
#include "core/lru_cache.h"
#include "dataset/dataset.h"
#include "analysis/features.h"
#include "analysis/selection.h"
#include "server/step_cache.h"

#include <atomic>
#include <compare>
#include <functional>
#include <memory>
#include <optional>
#include <span>
#include <string>
#include <vector>

namespace raypc::server {

// The selection statistics of single steps (analysis::selectedVolume of one step's volume) by
// (level, step, mean variable, analysis::selectionKey of the filters), the least recently used out
// beyond `maxEntries` steps. An entry holds a few arrays of one number per radius (a few kB).
class SelectionCache {
public:
    struct Key {
        int level = 0, step = 0;
        int meanVariable = -1;  // -1: none
        std::string selection;  // analysis::selectionKey
        auto operator<=>(const Key&) const = default;
    };
    using Cache = LruCache<Key, analysis::StepSelection>;

    explicit SelectionCache(size_t maxEntries = 8192) : m_cache(maxEntries) {}

    // What analysis::selectionOverTime answers for [firstStep, lastStep] at `level` (the same
    // numbers), each step taken from the cache or computed from its volume through `volumes` (without
    // evicting what the renderers use) and kept. `computed`, when given, is increased by the steps
    // this call computed. Throws raypc::Error for a step or level out of range, or when `cancel`
    // becomes true (checked before every step computed).
    std::vector<analysis::StepSelection> overTime(const dataset::Dataset& dataset, StepCache& volumes,
                                                  std::span<const analysis::RangeFilter> filters, int level, int firstStep,
                                                  int lastStep, std::optional<size_t> meanVariable = std::nullopt,
                                                  const std::atomic<bool>* cancel = nullptr, int* computed = nullptr);

    Cache::Counts counts() const { return m_cache.counts(); }

private:
    Cache m_cache;
};

// The feature labels (analysis::StepFeatures::labels: each grid point's feature id at the level)
// of one step's selection, by (step, level, selection, the options' minimum volume), the least
// recently used out beyond `maxEntries` (a step's labels are 4 bytes a grid point: 52 MB at full
// resolution). What the painted features of the renderers (render/feature_paint.h) are made from;
// a features request puts those of its state's step, which the UI then paints.
class FeatureLabelsCache {
public:
    using Labels = HugePageVector<int32_t>;
    explicit FeatureLabelsCache(size_t maxEntries = 4) : m_cache(maxEntries) {}

    // The labels, extracted from `volumes`' volume (step, level) unless kept. Throws what the volume's
    // loading and analysis::extractFeatures throw.
    std::shared_ptr<const Labels> get(StepCache& volumes, int step, int level, std::span<const analysis::RangeFilter> filters,
                                      const analysis::FeatureOptions& options);
    void put(int step, int level, std::span<const analysis::RangeFilter> filters, const analysis::FeatureOptions& options,
             std::shared_ptr<const Labels> labels);
    LruCache<std::string, Labels>::Counts counts() const { return m_cache.counts(); }

private:
    static std::string key(int step, int level, std::span<const analysis::RangeFilter> filters, const analysis::FeatureOptions& options);
    LruCache<std::string, Labels> m_cache;
};

// The answers of POST /api/features (their bytes) by featureSeriesKey, the least recently used out
// beyond `maxEntries` (an answer is some kB to a few MB: each track's points, the CSV tables).
using FeatureSeriesCache = LruCache<std::string, std::string>;

// What a features answer depends on: the selection (analysis::selectionKey), the options features are
// found and followed with, the level and the avalanche threshold. Not the step, the painting or the
// highlight.
std::string featureSeriesKey(std::span<const analysis::RangeFilter> filters, const analysis::FeatureOptions& options,
                             double minOverlapShare, analysis::StallMeasure stallBy, int level, double sigmas);

}  // namespace raypc::server
