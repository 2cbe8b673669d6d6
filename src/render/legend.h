// Colour legends in still pictures (`raypc render`, screenshots; RenderState::legend): a colour bar
// with its title (variable and units) and round values along it (colorBarTicks), stacked in the
// bottom-left corner on a translucent panel. Text is drawn with FreeType in DejaVu Sans (Debian
// fonts-dejavu-core), found at $RAYPC_FONT or the Debian path.
//
// Thread safety: drawLegends may be called from several threads (each call opens its own face).
#pragma once

#include "render/color_map.h"
#include "render/transfer_function.h"

#include <cstdint>
#include <functional>
#include <span>
#include <string>
#include <vector>

namespace raypc::render {

struct LegendSpec {
    std::string title;  // e.g. "temperature anomaly [K]" (UTF-8)
    TransferFunction colors;  // range, map or points, reversal, log scale (the opacity is not drawn)
    // Labels at positions along the bar (0: its left end, 1: its right end) instead of the values at
    // its ends and middle: for categories (feature ids), whose colours stand for names, not values.
    struct Tick {
        float at = 0;
        std::string text;
    };
    std::vector<Tick> ticks;
};

// A short text on the picture in a small dark box centred at (x, y) pixels (e.g. a reference
// shell's depth on its ring), in `color`.
struct TextLabel {
    std::string text;
    float x = 0, y = 0;
    Rgb color{1, 1, 1};
    bool rightAligned = false;  // (x, y): the middle of the box's right edge instead of its centre
};

// Units as written in pictures: exponents as superscripts ("kg/m^3" -> "kg/m³", as the UI writes
// them), CF names of angles as symbols ("degrees_north" -> "°N").
std::string displayUnits(const std::string& units);

// The label of a value on a legend: 4 significant digits, exponent form for very large or small values.
std::string legendNumber(double value);

// The legends' text size in a picture of this size, pixels: 1/36 of its smaller side, at least 12
// (legible beside the page's own text), but 10 in a picture under 120 px on a side (a thumbnail such
// as Python's 200x100 map), where 12 px titles and legends would leave the map or plot no room.
int legendFontPx(int width, int height);
// The width of a legend's colour bar in a picture of this size, pixels.
int legendBarPx(int width, int height);
// The width of `text` in the legends' font at `fontPx` pixels. Throws as drawLegends.
int legendTextWidthPx(const std::string& text, int fontPx);

// The values a colour bar `barPx` wide labels: round numbers (the multiples of a step of 1, 2 or
// 5 × 10^k, or of twice it; powers of ten on a log scale spanning a decade or more) inside the
// range, as many as fit with their labels (widths from `textWidthPx`) at least `gapPx` apart (drawLegends: half the text size), at
// most 6, two or more where two fit; an end's label is kept inside the bar (its text shifted in,
// the value's position unchanged). At least one (the middle's value when no round value fits).
// `at`: 0 the bar's left end (the range's min), 1 its right end.
std::vector<LegendSpec::Tick> colorBarTicks(const TransferFunction& colors, int barPx, int gapPx,
                                            const std::function<int(const std::string&)>& textWidthPx);
// Where a tick's label is drawn: its left edge along the bar (the label centred on its position,
// shifted to lie inside the bar), pixels.
int tickLabelLeftPx(float at, int labelPx, int barPx);
// How far up from the bottom `count` legends (without a shell key) reach, margin included: what a
// picture keeps free of data below them (maps and sections).
int legendsHeightPx(int width, int height, size_t count);

// Draws `legends` into `rgba` (width x height, 8-bit RGBA, row-major from the top left). Throws
// raypc::Error when the font cannot be found or read.
// `shellKey` (may be empty) adds one block above the colour bars naming each reference shell's
// depth beside a swatch of its colour (the labels' text and colour; their position is not used).
// The legends stand in the bottom-left corner, or from `leftPx` (e.g. beside a map) when given.
void drawLegends(std::vector<uint8_t>& rgba, int width, int height, std::span<const LegendSpec> legends,
                 std::span<const TextLabel> shellKey = {}, int leftPx = -1);

// The text size of drawTextLabels' labels in a picture of this size, pixels.
int labelFontPx(int width, int height);

// Draws each label's text centred at its position on a small dark box, at labelFontPx for the
// picture. Throws raypc::Error when the font cannot be found or read.
void drawTextLabels(std::vector<uint8_t>& rgba, int width, int height, std::span<const TextLabel> labels);

}  // namespace raypc::render
