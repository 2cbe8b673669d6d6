#include "render/render_state.h"

#include "core/atomic_file.h"
#include "core/error.h"
#include "core/json_input.h"

#include <cmath>

namespace raypc::render {

using nlohmann::json;

// parseRenderState and toJson are derived from the document's description (state_schema.cpp).

RenderState loadRenderState(const std::filesystem::path& path)
{
    return parseRenderState(parseJsonInput(readFile(path), path.string()), path.filename().string());
}

FeatureOptions featureOptions(const FeatureSettings& settings)
{
    return raypc::featureOptions(settings.minVolumeKm3, {settings.depthsKm.begin(), settings.depthsKm.end()},
                                 settings.bandHalfWidthKm);
}

void checkFeatureSettings(const FeatureSettings& settings,
                          std::initializer_list<std::pair<std::string_view, std::string_view>> optionNames)
{
    RenderState state;
    state.features = settings;
    try {
        parseRenderState(toJson(state), "options");
    } catch (const Error& e) {
        // "options: features.depthsKm[0]: expected ..." -> "--depth: expected ..."
        const std::string message = e.what();
        for (const auto& [key, option] : optionNames) {
            const std::string prefix = fmt::format("options: features.{}", key);
            if (message.starts_with(prefix)) {
                const size_t colon = message.find(": ", prefix.size());
                fail("{}{}", option, colon == std::string::npos ? message.substr(prefix.size()) : message.substr(colon));
            }
        }
        throw;
    }
}

std::vector<OpacityPoint> defaultOpacity(ColorMapId map)
{
    if (isCentredOnZero(map))
        return {{0.0f, 0.5f}, {0.5f, 0.0f}, {1.0f, 0.5f}};
    return {{0.0f, 0.0f}, {1.0f, 0.5f}};
}

std::string cameraViewsMismatch(const RenderState& s)
{
    const size_t views = s.camera.views.size();
    if (views == 0 || views == (s.stereo.enabled() ? 2u : 1u))
        return "";
    return fmt::format("{} views with stereo.mode \"{}\", expected {}", views, stereoModeName(s.stereo.mode),
                       s.stereo.enabled() ? "[] or 2 (left, right)" : "[] or 1");
}

RenderParams resolveParams(const RenderState& s, const VariableCatalog& catalog)
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
        fail("{} variable '{}' is unknown; the dataset has: {}", role, name, known());
    };
    if (catalog.names.empty())
        fail("the volume has no variables to render");
    if (const std::string problem = cameraViewsMismatch(s); !problem.empty())
        fail("camera.views: {}", problem);
    RenderParams p;
    p.camera = s.camera;
    p.width = s.width;
    p.height = s.height;
    p.colorVariable = s.colorVariable.empty() ? 0 : variableIndex(s.colorVariable, "colouring");
    auto defaultRange = [&](int var, ColorMapId map) {
        return defaultColorRange(var < int(catalog.ranges.size()) ? catalog.ranges[size_t(var)] : ValueRange{0, 1},
                                 isCentredOnZero(map));
    };
    p.transfer.colorMap = s.colorMap;
    p.transfer.range = s.colorRange ? *s.colorRange : defaultRange(p.colorVariable, s.colorMap);
    p.transfer.opacity = s.opacity.empty() ? defaultOpacity(s.colorMap) : s.opacity;
    p.transfer.opacityUnitKm = s.opacityUnitKm;
    p.transfer.colorPoints = s.colorPoints;
    p.transfer.reversed = s.colorReversed;
    p.transfer.logScale = s.logScale;
    if (s.logScale && !s.colorRange && !(p.transfer.range.min > 0))
        fail("color.logScale: the global range of '{}' is [{}, {}]; a log scale needs positive values (set "
             "color.range)",
             catalog.names[size_t(p.colorVariable)], p.transfer.range.min, p.transfer.range.max);
    p.transfer.validate();
    p.brushes = resolveRangeFilters(std::span<const std::string>(catalog.names), s.brushes, "brushes");
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

VariableCatalog catalogOf(const Dataset& dataset)
{
    VariableCatalog catalog;
    catalog.names = dataset.variableNames();
    for (const auto& v : dataset.variables())
        catalog.ranges.push_back(v.global.range);
    return catalog;
}

}  // namespace raypc::render
