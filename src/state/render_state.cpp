#include "state/render_state.h"

#include "core/atomic_file.h"
#include "core/error.h"
#include "core/json_input.h"

#include <cmath>

namespace raypc::state {

using nlohmann::json;

// parseRenderState and toJson are derived from the document's description (state_schema.cpp).

RenderState loadRenderState(const std::filesystem::path& path)
{
    return parseRenderState(parseJsonInput(readFile(path), path.string()), path.filename().string());
}

analysis::FeatureOptions featureOptions(const FeatureSettings& settings)
{
    return analysis::featureOptions(settings.minVolumeKm3, {settings.depthsKm.begin(), settings.depthsKm.end()},
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

}  // namespace raypc::state
