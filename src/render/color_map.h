// Colour maps scientists expect, sampled from published control points and interpolated linearly in RGB.
//
// Names (CLI, JSON): "viridis", "inferno" (black body), "cool-to-warm" (ParaView's default
// diverging map, Moreland 2009), "blue-white-red" (diverging, centred on zero for signed anomalies),
// "grayscale".
#pragma once

#include <string>
#include <string_view>
#include <vector>

namespace raypc::render {

enum class ColorMapId { Viridis, Inferno, CoolToWarm, BlueWhiteRed, Grayscale };

struct Rgb {
    float r = 0, g = 0, b = 0;
};

// The colour at u in [0, 1] (clamped).
Rgb sampleColorMap(ColorMapId map, float u);

// Maps centred on zero: value 0 is the middle colour and equal magnitudes get equal saturation.
bool isCentredOnZero(ColorMapId map);

std::string_view colorMapName(ColorMapId map);
// Throws raypc::Error naming `name` and listing the known maps.
ColorMapId parseColorMap(std::string_view name);
const std::vector<ColorMapId>& allColorMaps();

}  // namespace raypc::render
