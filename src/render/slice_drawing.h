// Internal to raypc_render: what the pictures of maps, sections (slice_view.h) and time–depth plots
// (time_depth_view.h) draw alike, so that they read alike: the colours of the sampled pixels
// (greyed outside the brushes), contours, flow arrows, a depth plot's frame and its marks at the
// reference shells, pathlines, titles that fit, notes, and the ink over the background.
//
// Units: pixels (picture's top left at 0, 0), km, degrees. Thread safety: plain functions; the
// colours are computed in parallel over pixels (oneTBB).
#pragma once

#include "render/legend.h"
#include "render/line_raster.h"
#include "render/slice_sampling.h"
#include "render/slice_view.h"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <initializer_list>
#include <optional>
#include <span>
#include <string>
#include <utility>
#include <vector>

namespace raypc::render::slice {

// The picture's pixels: the transfer function's colour of each value over the background; what the
// brushes leave out drawn as unselectedColor when `greyUnselected`.
std::vector<uint8_t> colorPixels(const PixelSamples& s, const TransferFunction& tf, Rgb background, bool greyUnselected);

// "Not selected" in maps and sections, in a way no colour map draws: the colour `c` desaturated and
// dimmed to a dark grey (0.08–0.26, keeping a trace of its lightness) crossed by lighter diagonal
// hatching (every kUnselectedHatchPx pixels, at pixel x, y). A near-zero value on a diverging map
// (its light neutral) stays light and unhatched, so "stalled" is never read as "left out".
inline constexpr int kUnselectedHatchPx = 6;
Rgb unselectedColor(Rgb c, size_t x, size_t y);

// An arrow of the flow at (x, y): its unit direction on the picture and its speed (cm/yr).
struct Arrow {
    float x, y, dx, dy;
    double speed;
};

// The arrows' grid spacing in pixels.
int arrowSpacingPx(int width, int height);

// Draws the arrows centred on their points, each as long as 0.9 spacing times its speed over the
// fastest one's; returns the note of their scale ("what: 29 px = 1.23 cm/yr").
std::string drawArrows(std::vector<uint8_t>& rgba, int width, int height, const std::vector<Arrow>& arrows, int spacing,
                       const std::string& what);

// The contour lines of the picture's values, dark over the colours.
void drawContourLines(std::vector<uint8_t>& rgba, const PixelSamples& samples, std::span<const float> levels);

// "30.0°S", "160.0°W": a latitude or a longitude as titles and messages write it.
std::string latText(double lat);
std::string lonText(double lon);

// A round step for about `target` intervals over `span`.
double niceStep(double span, double target, std::initializer_list<double> steps);

// The title from its parts (" · " between them), as many as fit the picture's width: the first
// always, the later ones (time, projection) only where there is room.
std::string fitTitle(const std::vector<std::string>& parts, int width, int height);

// A depth plot's box (sections, time–depth pictures): pixels, depth 0 at `top`, `depthSpanKm` at
// `bottom`.
struct DepthPlot {
    double left, right, top, bottom, depthSpanKm;
    float yOfDepth(double d) const { return float(top + d / depthSpanKm * (bottom - top)); }
};

// Dashed lines across the plot at the reference shells' depths (when visible), labelled at the right.
void drawDepthMarks(std::vector<uint8_t>& rgba, int width, int height, const DepthPlot& plot,
                    const state::ReferenceState::Shells& shells, std::vector<TextLabel>& labels);

// The plot's frame, depth ticks every 250, 500, … km at the left and `xTicks` (position, label) below.
void drawDepthPlotFrame(std::vector<uint8_t>& rgba, int width, int height, const DepthPlot& plot,
                        std::span<const std::pair<float, std::string>> xTicks, Rgb ink, std::vector<TextLabel>& labels);

// For a regional grid (grid.h, dataLatDeg and dataLonDeg) the note that its data lie within its
// extent, e.g. "data: 20.0°N to 55.0°N, 130.0°W to 65.0°W (regional); none elsewhere"; empty for a
// global grid.
std::string regionNote(const grid::SphericalGrid& grid);

// What else a picture says, right-aligned above its bottom edge, one line each: what grey means,
// the arrows' scale and the pathlines drawn.
void addNotes(std::vector<TextLabel>& labels, int width, int height, const std::vector<std::string>& given);

// Where a pathline's point (x, y, z km) lies on the picture, and how strongly its segments are
// drawn there (0: not at all).
struct PlacedPoint {
    float x, y, weight;
};

// Draws the pathlines the state shows (the 3D view's rule: window, brushes at their starts,
// attribute filters), each segment in the tubes' colour of its start over a dark halo, placed by
// `place`; returns the note saying how many were drawn and how, and the legend in `legends`.
template <class Place>
std::string drawPathlines(std::vector<uint8_t>& rgba, int width, int height, const SliceInputs& in, const Place& place,
                          const std::string& how, std::vector<LegendSpec>& legends)
{
    const state::RenderState& state = in.resolved->state;
    if (!state.pathlines.visible)
        return {};
    if (!in.pathlines)
        fail("pathlines: visible, but no pathlines were given");
    const PathlineLines& lines = *in.pathlines;
    const std::vector<uint8_t> shown = lines.visibilityFor(state);
    const PathlineStyle style = lines.styleFor(state.pathlines);
    const float span = style.range.max - style.range.min;
    const float widthPx = std::max(2.0f, float(std::min(width, height)) / 300.0f);
    LineLayer halo(width, height, false, true), layer(width, height, false, true);
    size_t drawn = 0;
    for (size_t line = 0; line < lines.lineCount(); ++line) {
        if (!shown[line])
            continue;
        const std::span<const float> points = lines.points(line);
        bool any = false;
        std::optional<PlacedPoint> previous;
        for (size_t p = 0; 4 * p < points.size(); ++p) {
            const std::optional<PlacedPoint> here = place(points[4 * p], points[4 * p + 1], points[4 * p + 2]);
            if (previous && here && std::abs(here->x - previous->x) < 0.25f * float(width)) {
                const float weight = std::min(previous->weight, here->weight);
                if (weight > 0) {
                    const float value = lines.colorValue(style, line, p - 1);
                    const float at = std::isfinite(value) ? std::clamp((value - style.range.min) / span, 0.0f, 1.0f) : 0.0f;
                    drawSegment(halo, previous->x, previous->y, here->x, here->y, widthPx + 2, Rgb{0, 0, 0}, weight);
                    drawSegment(layer, previous->x, previous->y, here->x, here->y, widthPx, sampleColorMap(style.colorMap, at), weight);
                    any = true;
                }
            }
            previous = here;
        }
        drawn += any;
    }
    compositeLines(rgba, halo, 0.6f);
    compositeLines(rgba, layer, 1.0f);
    legends.push_back(pathlineLegend(style, lines.columns()));
    const size_t total = size_t(std::count_if(shown.begin(), shown.end(), [](uint8_t b) { return b != 0; }));
    return fmt::format("pathlines: {} of {} shown lines {}", drawn, total, how);
}

// The state of `in`; throws raypc::Error when it has no volume or state.
const state::RenderState& stateOf(const SliceInputs& in);

// The colour of the lines drawn over the data (contours, frame): dark over a light background,
// light over a dark one.
Rgb inkFor(Rgb background);

// The colour legend, and the pathlines' when they are shown.
size_t legendCount(const state::RenderState& s);

}  // namespace raypc::render::slice
