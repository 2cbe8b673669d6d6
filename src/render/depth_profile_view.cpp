// A quantity against depth drawn as a curve (depth_profile_view.h).
#include "render/depth_profile_view.h"

#include "core/error.h"
#include "render/legend.h"
#include "render/line_raster.h"
#include "render/slice_drawing.h"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <numeric>

namespace raypc::render {

ImageRgba8 depthProfilePicture(const DepthProfileInputs& in)
{
    using namespace slice;  // slice_drawing.h
    if (in.depthsKm.size() != in.values.size() || in.depthsKm.empty())
        fail("depth profile picture: {} depths and {} values", in.depthsKm.size(), in.values.size());
    if (!(in.xMax > in.xMin) || !(in.depthSpanKm > 0))
        fail("depth profile picture: an empty axis ({:g}..{:g}, depth 0..{:g} km)", in.xMin, in.xMax, in.depthSpanKm);
    const int width = in.width, height = in.height, fontPx = legendFontPx(width, height);
    // Depth labels at the left, the marks' names at the right, the title's lines above, the axis's
    // labels, its title and the note below.
    const size_t titleLines = std::max<size_t>(1, in.titleLines.size());
    const DepthPlot plot{5.5 * fontPx, width - 4.5 * fontPx, (1.3 * double(titleLines) + 1.1) * fontPx, height - 4.8 * fontPx,
                         in.depthSpanKm};
    if (!(plot.right - plot.left >= 8 && plot.bottom - plot.top >= 8))
        fail("depth profile picture: {}x{} pixels have no room for the plot; choose a larger size", width, height);
    auto xOf = [&](double v) { return float(plot.left + (v - in.xMin) / (in.xMax - in.xMin) * (plot.right - plot.left)); };

    ImageRgba8 image{width, height, std::vector<uint8_t>(size_t(width) * size_t(height) * 4)};
    for (size_t p = 0; p < size_t(width) * size_t(height); ++p) {
        image.pixels[4 * p] = uint8_t(std::lround(255 * in.background.r));
        image.pixels[4 * p + 1] = uint8_t(std::lround(255 * in.background.g));
        image.pixels[4 * p + 2] = uint8_t(std::lround(255 * in.background.b));
        image.pixels[4 * p + 3] = 255;
    }
    const Rgb ink = inkFor(in.background);
    std::vector<TextLabel> labels;
    drawDepthMarks(image.pixels, width, height, plot, in.marks, labels);
    // Faint lines at the ticks, the one at zero stronger: where the curve crosses them reads at once.
    {
        LineLayer grid(width, height, false), zero(width, height, false);
        for (const double t : in.xTicks)
            if (t > in.xMin && t < in.xMax)
                drawSegment(std::abs(t) < 1e-12 ? zero : grid, xOf(t), float(plot.top), xOf(t), float(plot.bottom), 1.0f);
        compositeLines(image.pixels, grid, ink, 0.25f);
        compositeLines(image.pixels, zero, ink, 0.6f);
    }
    // The curve through the points in depth order, broken where a value is missing; a dot at each.
    std::vector<size_t> order(in.depthsKm.size());
    std::iota(order.begin(), order.end(), size_t(0));
    std::sort(order.begin(), order.end(), [&](size_t a, size_t b) { return in.depthsKm[a] < in.depthsKm[b]; });
    LineLayer curve(width, height, false);
    const float lineWidth = std::max(2.0f, float(std::min(width, height)) / 300.0f);
    size_t missing = 0;
    for (size_t k = 0; k < order.size(); ++k) {
        const size_t i = order[k];
        if (!std::isfinite(in.values[i])) {
            ++missing;
            continue;
        }
        const float x = xOf(std::clamp(in.values[i], in.xMin, in.xMax)), y = plot.yOfDepth(in.depthsKm[i]);
        drawSegment(curve, x - 0.01f, y, x + 0.01f, y, 2.6f * lineWidth);
        if (k + 1 < order.size() && std::isfinite(in.values[order[k + 1]])) {
            const size_t j = order[k + 1];
            drawSegment(curve, x, y, xOf(std::clamp(in.values[j], in.xMin, in.xMax)), plot.yOfDepth(in.depthsKm[j]), lineWidth);
        }
    }
    compositeLines(image.pixels, curve, in.curve, 1.0f);

    std::vector<std::pair<float, std::string>> ticks;
    for (const double t : in.xTicks)
        if (t >= in.xMin - 1e-12 && t <= in.xMax + 1e-12)
            ticks.emplace_back(xOf(t), fmt::format("{:g}", t));
    drawDepthPlotFrame(image.pixels, width, height, plot, ticks, ink, labels);
    labels.push_back({in.xTitle, float((plot.left + plot.right) / 2), float(plot.bottom + 2.4 * fontPx), ink});
    for (size_t k = 0; k < in.titleLines.size(); ++k)
        labels.push_back({fitTitle({in.titleLines[k]}, width, height), width / 2.0f, float((1.1 + 1.3 * double(k)) * fontPx), {1, 1, 1}});
    std::string note = in.note;
    if (missing)
        note += fmt::format("{}{} depth(s) without a value: gaps in the curve", note.empty() ? "" : "; ", missing);
    if (!note.empty())
        labels.push_back({fitTitle({note}, width, height), float((plot.left + plot.right) / 2), float(plot.bottom + 3.7 * fontPx), ink});
    drawTextLabels(image.pixels, width, height, labels);
    return image;
}

}  // namespace raypc::render
