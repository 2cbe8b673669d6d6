// The colour maps a state names, from one table shared with the UI (src/state/color_maps.json,
// compiled in; web/src/colormaps.ts bundles the same file): their names, kinds and control points.
// The renderer samples them (render/color_map.h: stops interpolated linearly in RGB).
//
// Names (CLI, JSON): "viridis", "inferno" (black body), "cool-to-warm" (ParaView's default
// diverging map, Moreland 2009), "blue-white-red" (diverging, centred on zero for signed anomalies),
// "grayscale", and the perceptually uniform maps geoscientists use: Crameri's "batlow", "lajolla"
// (sequential), "vik", "roma" (diverging), cmocean's "thermal" (sequential) and "balance"
// (diverging). The sources of the tables are named in color_maps.json.
#pragma once

#include <span>
#include <string>
#include <string_view>
#include <vector>

namespace raypc::state {

// In the order of color_maps.json (checked when the table is read).
enum class ColorMapId { Viridis, Inferno, CoolToWarm, BlueWhiteRed, Grayscale, Batlow, Lajolla, Vik, Roma, Thermal, Balance };

struct Rgb {
    float r = 0, g = 0, b = 0;
};

// A control point of a colour map: position u in [0, 1] and its colour.
struct ColorStop {
    float u = 0;
    Rgb c;
};

// The map's control points as in the table.
std::span<const ColorStop> colorMapStops(ColorMapId map);

// Maps centred on zero: value 0 is the middle colour and equal magnitudes get equal saturation.
bool isCentredOnZero(ColorMapId map);
// Diverging maps (two hues meeting in a light middle), for signed anomalies.
bool isDiverging(ColorMapId map);

std::string_view colorMapName(ColorMapId map);
// Throws raypc::Error naming `name` and listing the known maps.
ColorMapId parseColorMap(std::string_view name);
const std::vector<ColorMapId>& allColorMaps();

}  // namespace raypc::state
