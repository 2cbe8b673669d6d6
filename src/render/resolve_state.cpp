#include "render/resolve_state.h"

#include "core/error.h"
#include "core/error_kinds.h"
#include "core/spherical.h"
#include "grid/variable_names.h"
#include "analysis/pathline_storage.h"
#include "render/camera.h"
#include "render/stereo.h"
#include "render/transfer_function.h"

#include <fmt/format.h>
#include <fmt/ranges.h>

#include <algorithm>
#include <cmath>

namespace raypc::render {

RenderParams resolveParams(const state::RenderState& s, const VariableCatalog& catalog)
{
    auto known = [&] {
        std::string list;
        for (const auto& n : catalog.names)
            list += (list.empty() ? "" : ", ") + n;
        return list;
    };
    auto variableIndex = [&](const std::string& name, const char* role) {
        for (size_t i = 0; i < catalog.names.size(); ++i)
            if (catalog.names[i] == name)
                return int(i);
        failUnknownName("{} variable '{}' is unknown; the dataset has: {}", role, name, known());
    };
    if (catalog.names.empty())
        fail("the volume has no variables to render");
    if (const std::string problem = state::cameraViewsMismatch(s); !problem.empty())
        fail("camera.views: {}", problem);
    RenderParams p;
    p.camera = s.camera;
    p.width = s.width;
    p.height = s.height;
    p.colorVariable = s.colorVariable.empty() ? 0 : variableIndex(s.colorVariable, "colouring");
    auto defaultRange = [&](int var, ColorMapId map) {
        const bool known = var < int(catalog.ranges.size());
        return defaultColorRange(known ? catalog.ranges[size_t(var)] : dataset::ValueRange{0, 1},
                                 state::isCentredOnZero(map),
                                 var < int(catalog.histograms.size()) ? std::span<const double>(catalog.histograms[size_t(var)])
                                                                      : std::span<const double>());
    };
    p.transfer.colorMap = s.colorMap;
    p.transfer.range = s.colorRange ? *s.colorRange : defaultRange(p.colorVariable, s.colorMap);
    p.transfer.opacity = s.opacity.empty() ? state::defaultOpacity(s.colorMap) : s.opacity;
    p.transfer.opacityUnitKm = s.opacityUnitKm;
    p.transfer.colorPoints = s.colorPoints;
    p.transfer.reversed = s.colorReversed;
    p.transfer.logScale = s.logScale;
    if (s.logScale && !s.colorRange && !(p.transfer.range.min > 0))
        fail("color.logScale: the global range of '{}' is [{}, {}]; a log scale needs positive values (set "
             "color.range)",
             catalog.names[size_t(p.colorVariable)], p.transfer.range.min, p.transfer.range.max);
    p.transfer.validate();
    p.brushes = analysis::resolveRangeFilters(std::span<const std::string>(catalog.names), s.brushes, "brushes");
    p.core.visible = s.core.visible;
    p.core.color = s.core.color;
    p.core.colorMap = s.core.colorMap;
    if (!s.core.variable.empty()) {
        p.core.variable = variableIndex(s.core.variable, "core");
        p.core.range = s.core.range ? *s.core.range : defaultRange(p.core.variable, s.core.colorMap);
    }
    p.shading = s.shading;
    p.stepFactor = s.stepFactor;
    p.depthOpacity = s.depthOpacity;
    p.selectionMinOpacity = s.selection.show ? s.selection.minOpacity : 0.0f;
    return p;
}

VariableCatalog catalogOf(const dataset::Dataset& dataset)
{
    VariableCatalog catalog;
    catalog.names = dataset.variableNames();
    for (const auto& v : dataset.variables()) {
        catalog.ranges.push_back(v.global.range);
        catalog.histograms.push_back(v.global.histogram);
    }
    return catalog;
}

state::RenderState defaultState(const dataset::Dataset& dataset)
{
    state::RenderState s = defaultState(catalogOf(dataset));
    // A regional model faces the camera: the orbit looks at the centre of its data from above it, and
    // maps are centred on it.
    const grid::SphericalGrid& g = dataset.levels().front().grid;
    if (g.regional()) {
        if (g.dataLatDeg) {
            s.camera.elevationDeg = 0.5 * ((*g.dataLatDeg)[0] + (*g.dataLatDeg)[1]);
            s.map.centralLatitudeDeg = float(s.camera.elevationDeg);
        }
        if (g.dataLonDeg) {
            const double west = (*g.dataLonDeg)[0], east = (*g.dataLonDeg)[1];
            s.camera.azimuthDeg = wrapLonDeg(west + 0.5 * wrapLonDeg(east - west));
            s.map.centralMeridianDeg = float(std::remainder(s.camera.azimuthDeg, 360.0));
        }
    }
    return s;
}

state::RenderState defaultState(const VariableCatalog& catalog)
{
    state::RenderState s;
    // What there is to see (varname::anomalyToShow), else the first variable.
    const auto anomaly = std::find(catalog.names.begin(), catalog.names.end(), varname::anomalyToShow(catalog.names));
    const size_t var = anomaly != catalog.names.end() ? size_t(anomaly - catalog.names.begin()) : 0;
    s.colorVariable = catalog.names.at(var);
    const dataset::ValueRange r = catalog.ranges.at(var);
    if (r.min < 0 && r.max > 0) {
        // An anomaly (values either side of zero): the default colour range (defaultColorRange:
        // symmetric, the bulk of the values, the same the presets take), so that plumes and slabs
        // saturate, as bodies with edges: the tails opaque over 80 km (200 km made them soft,
        // translucent blobs), nothing in the middle 30 % of the range.
        s.colorMap = ColorMapId::BlueWhiteRed;
        s.colorRange.reset();
        s.opacity = {{0.0f, 1.0f}, {0.25f, 0.6f}, {0.35f, 0.0f}, {0.65f, 0.0f}, {0.75f, 0.6f}, {1.0f, 1.0f}};
        s.opacityUnitKm = 80.0f;
    } else {
        // A quantity of one sign (a seismic velocity, a density): a sequential map over its
        // range, the default ramp of opacity.
        s.colorMap = ColorMapId::Viridis;
    }
    // A dark core: the light grey one outshone the anomalies in front of it.
    s.core.color = Rgb{0.22f, 0.22f, 0.24f};
    // The mantle fills 94 % of the picture's shorter side (a landscape view is bound by its height,
    // whatever its width; the UI's views are landscape).
    s.camera.distanceKm = framingDistanceKm(s.camera.fovYDeg, s.width, s.height, kSurfaceRadiusKm, 0.94);
    // Where and how deep: the 410 and 660 km discontinuities as labelled rings, and the legend
    // naming the variable, its units and range (in the UI's view, screenshots and pictures).
    s.reference.shells.visible = true;
    s.reference.shells.depthsKm = {410.0f, 660.0f};
    s.reference.shells.opacity = 0.012f;  // rings at the silhouette; face-on a 2 % tint, not a veil
    s.legend = true;
    s.passes = 8;
    s.pathlines.minWidthPx = 2.0f;  // 12 km tubes are a hair wide at this distance
    // Lit: plumes and slabs read as shapes and which is in front shows (docs/rendering.md,
    // "Shading"); a document without the key stays unlit, as it was written.
    s.shading.enabled = true;
    return s;
}

ResolvedState resolveState(state::RenderState state, const dataset::Dataset& dataset)
{
    dataset.checkStep(state.step);
    if (state.level)
        dataset.checkLevel(*state.level);
    // Pathline attributes are checked even while the lines are hidden, so that a state that shows
    // them later does not fail then (the columns follow from the dataset's variables).
    const std::vector<std::string> columns = analysis::pathlineColumns(dataset.variableNames());
    auto checkColumn = [&](const std::string& name, const std::string& key) {
        if (std::find(columns.begin(), columns.end(), name) == columns.end())
            fail("pathlines: {}: the lines have no attribute '{}'; they have: {}", key, name, fmt::join(columns, ", "));
    };
    if (state.pathlines.colorBy != "age")
        checkColumn(state.pathlines.colorBy, "colorBy");
    for (size_t i = 0; i < state.pathlines.filters.size(); ++i)
        checkColumn(state.pathlines.filters[i].name, fmt::format("filters[{}]", i));
    ResolvedState r;
    r.params = resolveParams(state, catalogOf(dataset));
    r.state = std::move(state);
    return r;
}

ResolvedState resolveState(const nlohmann::json& document, const dataset::Dataset& dataset, const std::string& what)
{
    return resolveState(state::parseRenderState(document, what), dataset);
}

std::vector<ResolvedState> stereoViews(const ResolvedState& resolved)
{
    const StereoState& stereo = resolved.state.stereo;
    if (!stereo.enabled())
        return {resolved};
    const StereoLayout layout = stereoLayout(stereo.mode, resolved.state.width, resolved.state.height);
    const double convergenceKm = stereo.convergenceOr(resolved.state.camera.distanceKm);
    std::vector<ResolvedState> views;
    for (Eye eye : {Eye::Left, Eye::Right}) {
        ResolvedState v = resolved;
        v.state.stereo.mode = StereoMode::Off;
        v.state.camera = stereoEye(resolved.state.camera, eye, stereo.eyeSeparationKm, convergenceKm);
        v.state.camera.pixelAspect = layout.pixelAspect;
        v.state.width = layout.eyeWidth;
        v.state.height = layout.eyeHeight;
        v.params.camera = v.state.camera;
        v.params.width = layout.eyeWidth;
        v.params.height = layout.eyeHeight;
        views.push_back(std::move(v));
    }
    return views;
}

}  // namespace raypc::render
