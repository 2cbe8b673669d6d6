#include "app/slice_grid.h"

#include "core/error.h"
#include "core/spherical.h"
#include "render/slice_view.h"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>

namespace raypc::app {

using render::StateRenderer;

void checkSliceGridSpacing(StateRenderer::Slice slice, double gridStepDeg, double depthStepKm, const SliceGridNames& names)
{
    if (!(gridStepDeg >= 0) || !(depthStepKm > 0))
        fail("{} {} / {} {}: expected positive numbers", names.gridStep, gridStepDeg, names.depthStep, depthStepKm);
    if (slice == StateRenderer::Slice::Map && gridStepDeg > 0) {
        const double n = 180 / gridStepDeg;
        if (std::abs(n - std::round(n)) > 1e-9 || n > 36000)
            fail("{} {}: expected degrees that divide 180 (e.g. 0.25, 0.5, 1, 2)", names.gridStep, gridStepDeg);
    }
    if (slice == StateRenderer::Slice::Section && gridStepDeg > 0 && gridStepDeg < 0.001)
        fail("{} {}: at least 0.001 degrees", names.gridStep, gridStepDeg);
    if (slice == StateRenderer::Slice::Section && depthStepKm < 0.1)
        fail("{} {}: at least 0.1 km", names.depthStep, depthStepKm);
}

io::CfGridFile sliceGridFile(const dataset::Dataset& dataset, const dataset::StepVolume& volume,
                             const render::ResolvedState& resolved, StateRenderer::Slice slice, double gridStepDeg,
                             double depthStepKm, const std::string& source, const SliceGridNames& names)
{
    const state::RenderState& state = resolved.state;
    const size_t var = size_t(resolved.params.colorVariable);
    const dataset::VariableInfo& info = dataset.variables().at(var);
    io::CfGridFile file;
    file.name = io::cfName(info.name);
    file.units = info.units;
    file.longName = info.name;
    const double timeMyr = dataset.steps().at(size_t(state.step)).timeMyr;
    const io::CfVariable1D lat{"lat", "degrees_north", "latitude", "latitude", "Y", "", {}, ""};
    const io::CfVariable1D lon{"lon", "degrees_east", "longitude", "longitude", "X", "", {}, ""};
    if (slice == StateRenderer::Slice::Map) {
        const render::SliceGrid g =
            render::latLonSlice(volume, var, state.map.depthKm, gridStepDeg > 0 ? gridStepDeg : 1.0, names.depth);
        file.rows = lat;
        file.rows.values = g.rows;
        file.columns = lon;
        file.columns.values = g.columns;
        file.scalars.push_back({"depth", "km", "depth", "depth below the surface", "Z", "down", {state.map.depthKm}, ""});
        file.values = g.values;
        file.globalAttributes.emplace_back(
            "title", fmt::format("{} at {:g} km depth, step {} ({:.3f} Myr)", info.name, state.map.depthKm, state.step, timeMyr));
    } else {
        const render::GreatCircle circle(state.section.from, state.section.to);
        const double step = gridStepDeg > 0 ? gridStepDeg : 0.5;
        const int columns = std::max(2, int(std::ceil(circle.lengthDeg() / step)) + 1);
        const double depthSpan = kSurfaceRadiusKm - volume.grid().rKm.front();
        const int rows = std::max(2, int(std::ceil(depthSpan / depthStepKm)) + 1);
        const render::SectionGrid g = render::sectionGrid(volume, var, state.section, columns, rows);
        file.rows = {"depth", "km", "depth", "depth below the surface", "Z", "down", g.grid.rows, ""};
        file.columns = {"distance", "km", "", "distance along the great circle from the section's start, at the surface", "X", "", g.grid.columns, ""};
        file.auxiliary.push_back({"distance_deg", "degree", "", "angle along the great circle from the section's start", "", "", g.distanceDeg, "distance"});
        file.auxiliary.push_back({"lat", "degrees_north", "latitude", "latitude", "", "", g.latDeg, "distance"});
        file.auxiliary.push_back({"lon", "degrees_east", "longitude", "longitude", "", "", g.lonDeg, "distance"});
        file.values = g.grid.values;
        file.globalAttributes.emplace_back(
            "title", fmt::format("{} on the great-circle section from {} to {}, step {} ({:.3f} Myr)", info.name,
                                 render::latLonText(state.section.from.latDeg, state.section.from.lonDeg),
                                 render::latLonText(state.section.to.latDeg, state.section.to.lonDeg), state.step, timeMyr));
    }
    file.globalAttributes.emplace_back("source", "RayPC (" + source + "), sampled on the model's native grid as "
                                                 "raypc probe samples (trilinear, lon seam and pole caps joined)");
    file.globalAttributes.emplace_back("time", fmt::format("{:.6g} Myr", timeMyr));
    return file;
}

}  // namespace raypc::app
