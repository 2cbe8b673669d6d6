// Colour legends in still pictures (`raypc render`, screenshots; RenderState::legend): a colour bar
// with its title (variable and units) and the values at its ends and middle, stacked in the
// bottom-left corner on a translucent panel. Text is drawn with FreeType in DejaVu Sans (Debian
// fonts-dejavu-core), found at $RAYPC_FONT or the Debian path.
//
// Thread safety: drawLegends may be called from several threads (each call opens its own face).
#pragma once

#include "render/color_map.h"
#include "render/transfer_function.h"

#include <cstdint>
#include <span>
#include <string>
#include <vector>

namespace raypc::render {

struct LegendSpec {
    std::string title;  // e.g. "temperature anomaly [K]" (UTF-8)
    TransferFunction colors;  // range, map or points, reversal, log scale (the opacity is not drawn)
};

// Units as written in pictures: exponents as superscripts ("kg/m^3" -> "kg/m³", as the UI writes
// them), CF names of angles as symbols ("degrees_north" -> "°N").
std::string displayUnits(const std::string& units);

// The label of a value on a legend: 4 significant digits, exponent form for very large or small values.
std::string legendNumber(double value);

// Draws `legends` into `rgba` (width x height, 8-bit RGBA, row-major from the top left). Throws
// raypc::Error when the font cannot be found or read.
void drawLegends(std::vector<uint8_t>& rgba, int width, int height, std::span<const LegendSpec> legends);

}  // namespace raypc::render
