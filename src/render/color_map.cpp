#include "render/color_map.h"

#include "core/error.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <span>

namespace raypc::render {
namespace {

struct Stop {
    float u;
    Rgb c;
};

// Samples of matplotlib's viridis and inferno (van der Walt & Smith), ParaView's "Cool to Warm"
// (Moreland, "Diverging Color Maps for Scientific Visualization", 2009) and ColorBrewer's RdBu reversed.
constexpr std::array kViridis{
    Stop{0.000f, {0.267f, 0.005f, 0.329f}}, Stop{0.125f, {0.283f, 0.141f, 0.458f}},
    Stop{0.250f, {0.254f, 0.265f, 0.530f}}, Stop{0.375f, {0.207f, 0.372f, 0.553f}},
    Stop{0.500f, {0.164f, 0.471f, 0.558f}}, Stop{0.625f, {0.128f, 0.567f, 0.551f}},
    Stop{0.750f, {0.135f, 0.659f, 0.518f}}, Stop{0.875f, {0.267f, 0.749f, 0.441f}},
    Stop{0.9375f, {0.478f, 0.821f, 0.318f}}, Stop{1.000f, {0.993f, 0.906f, 0.144f}}};
constexpr std::array kInferno{
    Stop{0.000f, {0.001f, 0.000f, 0.014f}}, Stop{0.125f, {0.087f, 0.045f, 0.225f}},
    Stop{0.250f, {0.258f, 0.039f, 0.406f}}, Stop{0.375f, {0.416f, 0.090f, 0.433f}},
    Stop{0.500f, {0.578f, 0.148f, 0.404f}}, Stop{0.625f, {0.736f, 0.216f, 0.330f}},
    Stop{0.750f, {0.865f, 0.317f, 0.226f}}, Stop{0.875f, {0.955f, 0.469f, 0.100f}},
    Stop{0.9375f, {0.976f, 0.680f, 0.150f}}, Stop{1.000f, {0.988f, 0.998f, 0.645f}}};
constexpr std::array kCoolToWarm{
    Stop{0.000f, {0.230f, 0.299f, 0.754f}}, Stop{0.125f, {0.384f, 0.510f, 0.918f}},
    Stop{0.250f, {0.552f, 0.690f, 0.996f}}, Stop{0.375f, {0.717f, 0.795f, 0.950f}},
    Stop{0.500f, {0.865f, 0.865f, 0.865f}}, Stop{0.625f, {0.957f, 0.752f, 0.651f}},
    Stop{0.750f, {0.958f, 0.603f, 0.482f}}, Stop{0.875f, {0.866f, 0.394f, 0.315f}},
    Stop{1.000f, {0.706f, 0.016f, 0.150f}}};
constexpr std::array kBlueWhiteRed{
    Stop{0.000f, {0.020f, 0.188f, 0.380f}}, Stop{0.167f, {0.129f, 0.400f, 0.675f}},
    Stop{0.333f, {0.573f, 0.773f, 0.871f}}, Stop{0.500f, {0.969f, 0.969f, 0.969f}},
    Stop{0.667f, {0.957f, 0.647f, 0.510f}}, Stop{0.833f, {0.698f, 0.094f, 0.169f}},
    Stop{1.000f, {0.404f, 0.000f, 0.122f}}};
constexpr std::array kGrayscale{Stop{0.0f, {0, 0, 0}}, Stop{1.0f, {1, 1, 1}}};

Rgb interpolate(std::span<const Stop> stops, float u)
{
    u = std::clamp(std::isfinite(u) ? u : 0.0f, 0.0f, 1.0f);
    size_t i = 1;
    while (i + 1 < stops.size() && stops[i].u < u)
        ++i;
    const Stop& a = stops[i - 1];
    const Stop& b = stops[i];
    const float w = (u - a.u) / (b.u - a.u);
    return {a.c.r + w * (b.c.r - a.c.r), a.c.g + w * (b.c.g - a.c.g), a.c.b + w * (b.c.b - a.c.b)};
}

}  // namespace

Rgb sampleColorMap(ColorMapId map, float u)
{
    switch (map) {
    case ColorMapId::Viridis: return interpolate(kViridis, u);
    case ColorMapId::Inferno: return interpolate(kInferno, u);
    case ColorMapId::CoolToWarm: return interpolate(kCoolToWarm, u);
    case ColorMapId::BlueWhiteRed: return interpolate(kBlueWhiteRed, u);
    case ColorMapId::Grayscale: return interpolate(kGrayscale, u);
    }
    return {};
}

bool isCentredOnZero(ColorMapId map) { return map == ColorMapId::BlueWhiteRed; }

std::string_view colorMapName(ColorMapId map)
{
    switch (map) {
    case ColorMapId::Viridis: return "viridis";
    case ColorMapId::Inferno: return "inferno";
    case ColorMapId::CoolToWarm: return "cool-to-warm";
    case ColorMapId::BlueWhiteRed: return "blue-white-red";
    case ColorMapId::Grayscale: return "grayscale";
    }
    return "?";
}

const std::vector<ColorMapId>& allColorMaps()
{
    static const std::vector<ColorMapId> maps = {ColorMapId::Viridis, ColorMapId::Inferno, ColorMapId::CoolToWarm,
                                                 ColorMapId::BlueWhiteRed, ColorMapId::Grayscale};
    return maps;
}

ColorMapId parseColorMap(std::string_view name)
{
    std::string known;
    for (ColorMapId map : allColorMaps()) {
        if (name == colorMapName(map))
            return map;
        known += (known.empty() ? "" : ", ") + std::string(colorMapName(map));
    }
    // Accepted aliases: the names ParaView and matplotlib users type.
    if (name == "coolwarm" || name == "Cool to Warm")
        return ColorMapId::CoolToWarm;
    if (name == "blackbody" || name == "black-body")
        return ColorMapId::Inferno;
    if (name == "RdBu" || name == "bwr")
        return ColorMapId::BlueWhiteRed;
    fail("colour map '{}' is unknown, expected one of: {}", name, known);
}

}  // namespace raypc::render
