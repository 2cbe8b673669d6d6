#include "server/render_support.h"

#include "core/error.h"

#include <cmath>

namespace raypc::server {

using namespace raypc::render;

RenderState defaultState(const Dataset& dataset)
{
    RenderState s;
    const int anomaly = dataset.variableIndex("temperature anomaly");
    const int var = anomaly >= 0 ? anomaly : 0;
    s.colorVariable = dataset.variables().at(size_t(var)).name;
    s.colorMap = ColorMapId::BlueWhiteRed;
    // Symmetric range over the bulk of the values, so that plumes and slabs saturate.
    const ValueRange r = dataset.variables()[size_t(var)].global.range;
    const float m = 0.6f * std::max(std::abs(r.min), std::abs(r.max));
    if (m > 0)
        s.colorRange = ValueRange{-m, m};
    s.opacity = {{0.0f, 0.8f}, {0.3f, 0.05f}, {0.4f, 0.0f}, {0.6f, 0.0f}, {0.7f, 0.05f}, {1.0f, 0.8f}};
    s.opacityUnitKm = 200.0f;
    s.camera.distanceKm = 22000.0;
    s.passes = 8;
    return s;
}

ResolvedState resolveState(const nlohmann::json& document, const Dataset& dataset)
{
    ResolvedState r;
    r.state = parseRenderState(document, "state");
    const int steps = int(dataset.steps().size());
    if (r.state.step < 0 || r.state.step >= steps)
        fail("step: {} out of range 0..{}", r.state.step, steps - 1);
    const int levels = int(dataset.levels().size());
    if (r.state.level && (*r.state.level < 0 || *r.state.level >= levels))
        fail("level: {} out of range 0..{}", *r.state.level, levels - 1);
    r.params = resolveParams(r.state, catalogOf(dataset));
    return r;
}

std::vector<RangeFilter> selectionFilters(const RenderParams& params)
{
    std::vector<RangeFilter> filters;
    for (const auto& b : params.brushes)
        filters.push_back({b.variable, b.coordinate, b.min, b.max});
    return filters;
}

}  // namespace raypc::server
