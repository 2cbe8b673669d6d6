#include "server/analysis_caches.h"

#include "core/error.h"

#include <fmt/format.h>
#include <fmt/ranges.h>

namespace raypc::server {

std::vector<analysis::StepSelection> SelectionCache::overTime(const dataset::Dataset& dataset, StepCache& volumes,
                                                              std::span<const analysis::RangeFilter> filters, int level,
                                                              int firstStep, int lastStep, std::optional<size_t> meanVariable,
                                                              const std::atomic<bool>* cancel, int* computed)
{
    dataset.checkLevel(level);
    dataset.checkStep(firstStep);
    dataset.checkStep(lastStep);
    const int nSteps = int(dataset.steps().size());
    Key key{level, 0, meanVariable ? int(*meanVariable) : -1, analysis::selectionKey(filters)};
    std::vector<analysis::StepSelection> out;
    out.reserve(size_t(std::max(0, lastStep - firstStep + 1)));
    for (int step = firstStep; step <= lastStep; ++step) {
        key.step = step;
        int how = Cache::kHit;
        const auto one = m_cache.get(
            key,
            [&] {
                if (cancel && *cancel)
                    fail("statistics cancelled at step {} of {} (the client went away or the server is stopping)", step, nSteps);
                return std::move(analysis::selectionOverTime(
                    dataset, filters, level, step, step,
                    [&](int s, int l) { return volumes.getWithoutEvicting(s, l); }, {}, meanVariable)[0]);
            },
            &how);
        if (computed && how == Cache::kMade)
            ++*computed;
        out.push_back(*one);
    }
    return out;
}

std::string FeatureLabelsCache::key(int step, int level, std::span<const analysis::RangeFilter> filters,
                                    const analysis::FeatureOptions& options)
{
    // Labels depend on the selection and the minimum volume only (the depths and band give measures).
    return fmt::format("{} | {} | {} | {}", step, level, options.minVolumeKm3, analysis::selectionKey(filters));
}

std::shared_ptr<const FeatureLabelsCache::Labels> FeatureLabelsCache::get(StepCache& volumes, int step, int level,
                                                                          std::span<const analysis::RangeFilter> filters,
                                                                          const analysis::FeatureOptions& options)
{
    return m_cache.get(key(step, level, filters, options),
                       [&] { return std::move(analysis::extractFeatures(*volumes.get(step, level), filters, options).labels); });
}

void FeatureLabelsCache::put(int step, int level, std::span<const analysis::RangeFilter> filters, const analysis::FeatureOptions& options,
                             std::shared_ptr<const Labels> labels)
{
    m_cache.put(key(step, level, filters, options), std::move(labels));
}

std::string featureSeriesKey(std::span<const analysis::RangeFilter> filters, const analysis::FeatureOptions& options,
                             double minOverlapShare, analysis::StallMeasure stallBy, int level, double sigmas)
{
    return fmt::format("level {} | min {} | depths {} | half {} | overlap {} | stall {} | sigmas {} | {}", level,
                       options.minVolumeKm3, fmt::join(options.bandDepthsKm, ","), options.bandHalfWidthKm, minOverlapShare,
                       int(stallBy), sigmas, analysis::selectionKey(filters));
}

}  // namespace raypc::server
