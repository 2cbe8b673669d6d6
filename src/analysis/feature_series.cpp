#include "analysis/feature_series.h"
#include "grid/variable_names.h"

#include "core/error.h"

#include <cmath>

namespace raypc::analysis {

VelocityVariables velocityVariables(const dataset::Dataset& dataset, const char* what)
{
    VelocityVariables v;
    for (const auto& [name, index] : {std::pair<const char*, size_t*>{"vx", &v.x}, {"vy", &v.y}, {"vz", &v.z}}) {
        const int i = dataset.variableIndex(name);
        if (i < 0)
            fail("{}: the dataset has no velocity component '{}' (vx, vy, vz in m/s) to move features with", what,
                 name);
        *index = size_t(i);
    }
    return v;
}

FeatureSeries::FeatureSeries(const dataset::Dataset& dataset, double minOverlapShare, const char* what)
    : m_dataset(dataset), m_velocity(velocityVariables(dataset, what)), m_tracker(minOverlapShare)
{
    if (const int i = dataset.variableIndex(varname::kRadialVelocity); i >= 0)
        m_radialVelocity = size_t(i);
}

void FeatureSeries::addLinked(int step, const StepFeatures& features, const std::vector<FeatureLink>& links)
{
    const double timeMyr = m_dataset.steps().at(size_t(step)).timeMyr;
    const std::vector<int> tracks = m_tracker.add(step, features, links);
    for (size_t k = 0; k < features.features.size(); ++k) {
        const Feature& f = features.features[k];
        m_rowOf[{step, f.id}] = m_rows.size();
        m_rows.push_back({tracks[k], step, timeMyr, f});
        m_points[tracks[k]].push_back({step, timeMyr, f.meanDepthKm,
                                       m_radialVelocity ? f.variables[*m_radialVelocity].mean : std::nan(""),
                                       f.topDepthKm, f.bottomDepthKm});
    }
}

const Feature& FeatureSeries::feature(int step, int id) const
{
    const auto it = m_rowOf.find({step, id});
    if (it == m_rowOf.end())
        fail("feature series: step {} has no feature {}", step, id);
    return m_rows[it->second].feature;
}

std::vector<std::pair<int, Stall>> FeatureSeries::stalls(std::span<const double> depthsKm, double halfWidthKm,
                                                         int seriesLastStep, StallMeasure measure) const
{
    std::vector<std::pair<int, Stall>> out;
    for (const auto& [track, points] : m_points)
        for (Stall& s : stallTimes(points, depthsKm, halfWidthKm, seriesLastStep, measure))
            out.emplace_back(track, std::move(s));
    return out;
}

}  // namespace raypc::analysis
