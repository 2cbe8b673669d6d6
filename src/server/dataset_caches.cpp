#include "server/dataset_caches.h"

#include "core/error.h"

#include <algorithm>

namespace raypc::server {

namespace fs = std::filesystem;

render::StateSources cacheSources(StepCache* volumes, PathlineCache* lines, FeatureLabelsCache* labels)
{
    render::StateSources s;
    s.volume = [volumes](int step, int level) { return volumes->get(step, level); };
    s.pathlines = [lines](int step, int window) -> std::shared_ptr<const std::vector<analysis::PathlineSet>> {
        if (!lines)
            fail("this server has no pathline cache");
        return lines->get(step, window);
    };
    if (labels)
        s.featureLabels = [volumes, labels](int step, int level, std::span<const analysis::RangeFilter> filters,
                                            const analysis::FeatureOptions& options) {
            return labels->get(*volumes, step, level, filters, options);
        };
    return s;
}

DatasetCaches openDatasetCaches(const fs::path& dir, size_t cacheBytes, size_t cacheEntries)
{
    DatasetCaches c;
    c.dataset = dataset::Dataset::open(dir);
    c.volumes = std::make_unique<StepCache>([dataset = c.dataset](int step, int level) { return dataset->load(step, level); },
                                            cacheBytes, cacheEntries);
    c.pathlines = std::make_unique<PathlineCache>(dir);
    return c;
}

PathlineCache::PathlineCache(fs::path datasetDir, size_t maxEntries) : m_dir(std::move(datasetDir)), m_cache(maxEntries)
{
}

std::shared_ptr<const PathlineCache::Window> PathlineCache::get(int step, int window)
{
    return m_cache.get({step, window}, [&] { return analysis::loadPathlineWindow(m_dir, step, window); });
}

PersistenceCache::PersistenceCache(StepCache* volumes, size_t maxEntries) : m_volumes(volumes), m_cache(maxEntries)
{
}

std::shared_ptr<const PersistenceCache::Pairs> PersistenceCache::get(int step, int variable)
{
    return m_cache.get({step, variable}, [&] {
        const auto volume = m_volumes->getWithoutEvicting(step, 0);
        const std::span<const float> values(volume->values(size_t(variable)), volume->grid().cellCount());
        return analysis::persistencePairs(volume->grid(), values);
    });
}

}  // namespace raypc::server
