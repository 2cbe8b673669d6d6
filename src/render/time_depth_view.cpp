// Time–depth (Hovmöller) pictures of a selection over time (time_depth_view.h): what they show at
// each step and radius, their colours and titles, and the picture.
#include "render/time_depth_view.h"

#include "core/error.h"
#include "core/spherical.h"
#include "render/legend.h"
#include "render/slice_drawing.h"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <optional>
#include <span>

namespace raypc::render {
namespace {
// Depth labels at the left, the marks' names at the right, the title above, time labels and the
// legend below (a section's layout).
slice::DepthPlot timeDepthPlot(int width, int height, double depthSpanKm)
{
    const int fontPx = legendFontPx(width, height);
    const slice::DepthPlot plot{5.5 * fontPx, width - 4.5 * fontPx, 2.4 * fontPx,
                         height - legendsHeightPx(width, height, 1) - 2.2 * fontPx, depthSpanKm};
    if (!(plot.right - plot.left >= 8 && plot.bottom - plot.top >= 8))
        fail("time-depth picture: {}x{} pixels have no room for the plot; choose a larger size", width, height);
    return plot;
}
}  // namespace

void checkTimeDepthPictureSize(int width, int height) { timeDepthPlot(width, height, 1.0); }

ImageRgba8 timeDepthPicture(const TimeDepthInputs& in)
{
    using namespace slice;  // slice_sampling.h, slice_drawing.h
    const size_t nSteps = in.columns.size(), nR = in.radiiKm.size();
    if (nSteps == 0 || nR < 2 || in.values.size() != nSteps * nR)
        fail("time-depth picture: {} values for {} steps and {} radii", in.values.size(), nSteps, nR);
    const int width = in.width, height = in.height, fontPx = legendFontPx(width, height);
    const DepthPlot plot = timeDepthPlot(width, height, kSurfaceRadiusKm - in.radiiKm.front());
    // The time axis spans the steps' times, half a step beyond the first and last (one step: 1 Myr).
    const double dt = nSteps > 1 ? (in.columns.back() - in.columns.front()) / double(nSteps - 1) : 1.0;
    const double t0 = in.columns.front() - dt / 2, t1 = in.columns.back() + dt / 2;
    auto xOfTime = [&](double t) { return float(plot.left + (t - t0) / (t1 - t0) * (plot.right - plot.left)); };
    // The nearest of sorted `axis` to v (ties to the lower), or nullopt beyond half a spacing outside.
    auto nearest = [](const std::vector<double>& axis, double v) -> std::optional<size_t> {
        const auto it = std::lower_bound(axis.begin(), axis.end(), v);
        if (it == axis.begin())
            return axis.size() > 1 && v < axis[0] - (axis[1] - axis[0]) / 2 ? std::nullopt : std::optional<size_t>(0);
        if (it == axis.end()) {
            const size_t n = axis.size();
            return n > 1 && v > axis[n - 1] + (axis[n - 1] - axis[n - 2]) / 2 ? std::nullopt : std::optional<size_t>(n - 1);
        }
        const size_t hi = size_t(it - axis.begin());
        return v - axis[hi - 1] <= axis[hi] - v ? hi - 1 : hi;
    };
    std::vector<std::optional<size_t>> columns(static_cast<size_t>(width)), rows(static_cast<size_t>(height));
    for (int x = 0; x < width; ++x)
        if (x + 0.5 >= plot.left && x + 0.5 <= plot.right)
            columns[size_t(x)] = nSteps == 1 ? std::optional<size_t>(0)
                                             : nearest(in.columns, t0 + (x + 0.5 - plot.left) / (plot.right - plot.left) * (t1 - t0));
    for (int y = 0; y < height; ++y)
        if (y + 0.5 >= plot.top && y + 0.5 <= plot.bottom)
            rows[size_t(y)] = nearest(in.radiiKm, kSurfaceRadiusKm - (y + 0.5 - plot.top) / (plot.bottom - plot.top) * plot.depthSpanKm);
    PixelSamples samples(width, height);
    for (int y = 0; y < height; ++y)
        for (int x = 0; x < width; ++x)
            if (columns[size_t(x)] && rows[size_t(y)])
                samples.value[size_t(y) * size_t(width) + size_t(x)] = in.values[*columns[size_t(x)] * nR + *rows[size_t(y)]];
    ImageRgba8 image{width, height, colorPixels(samples, in.colors, in.background, false)};

    const Rgb ink = inkFor(in.background);
    std::vector<TextLabel> labels;
    drawDepthMarks(image.pixels, width, height, plot, in.marks, labels);
    std::vector<std::pair<float, std::string>> ticks;
    const bool degrees = in.columnsAre == TimeDepthInputs::Columns::Degree;
    auto columnText = [&](double v) { return degrees ? fmt::format("l = {:g}", v) : fmt::format("{:g} Myr", v); };
    const double span = in.columns.back() - in.columns.front();
    if (span > 0) {
        const double step = degrees ? niceStep(span, std::max(1.0, (plot.right - plot.left) / (6.0 * fontPx)), {1, 2, 5, 10, 20, 50, 100})
                                    : niceStep(span, std::max(1.0, (plot.right - plot.left) / (6.0 * fontPx)),
                                               {0.1, 0.2, 0.5, 1, 2, 5, 10, 20, 50, 100, 200, 500, 1000, 2000, 5000});
        for (double t = std::ceil(in.columns.front() / step) * step; t <= in.columns.back() + 1e-9; t += step)
            ticks.emplace_back(xOfTime(t), columnText(t));
    } else {
        ticks.emplace_back(xOfTime(in.columns.front()), columnText(in.columns.front()));
    }
    drawDepthPlotFrame(image.pixels, width, height, plot, ticks, ink, labels);
    labels.push_back({fitTitle({in.title}, width, height), width / 2.0f, 1.1f * fontPx, {1, 1, 1}});
    const bool blank = std::any_of(in.values.begin(), in.values.end(), [](float v) { return std::isnan(v); });
    addNotes(labels, width, height, {blank ? in.blankNote : ""});
    drawTextLabels(image.pixels, width, height, labels);
    const LegendSpec legend{in.colorTitle, in.colors, {}};
    drawLegends(image.pixels, width, height, std::span(&legend, 1));
    return image;
}

TimeDepthOf parseTimeDepthOf(const std::string& text, const std::string& what)
{
    if (text == "share")
        return TimeDepthOf::Share;
    if (text == "selected-mean")
        return TimeDepthOf::SelectedMean;
    if (text == "shell-mean")
        return TimeDepthOf::ShellMean;
    fail("{} '{}': expected share, selected-mean or shell-mean", what, text.substr(0, 40));
}

void appendTimeDepthValues(std::span<const analysis::StepSelection> selections, TimeDepthOf of, std::vector<float>& out)
{
    for (const analysis::StepSelection& sel : selections) {
        const analysis::SelectionStats& s = sel.stats;
        for (size_t iR = 0; iR < s.volumeByRadiusKm3.size(); ++iR)
            out.push_back(float(of == TimeDepthOf::Share          ? 100.0 * s.volumeByRadiusKm3[iR] / s.shellVolumeByRadiusKm3[iR]
                                : of == TimeDepthOf::SelectedMean ? s.selectedMeanByRadius[iR]
                                                                  : s.shellMeanByRadius[iR]));
    }
}

TimeDepthInputs timeDepthInputs(const dataset::Dataset& dataset, int first, int last, int level, std::vector<float> values,
                                TimeDepthOf of, const dataset::VariableInfo* mean, size_t ranges)
{
    if (of != TimeDepthOf::Share && !mean)
        fail("time-depth picture: the mean of which variable? (none given)");
    TimeDepthInputs in;
    for (int step = first; step <= last; ++step)
        in.columns.push_back(dataset.steps().at(size_t(step)).timeMyr);
    in.radiiKm = dataset.levels().at(size_t(level)).grid.rKm;
    in.values = std::move(values);
    float lo = INFINITY, hi = -INFINITY;
    for (const float v : in.values)
        if (std::isfinite(v))
            lo = std::min(lo, v), hi = std::max(hi, v);
    if (!(lo <= hi))  // nothing selected anywhere
        lo = 0, hi = 1;
    if (of == TimeDepthOf::Share) {
        in.colors.colorMap = ColorMapId::Viridis;
        in.colors.range = {0, std::max(hi, 1e-3f)};
    } else if (lo < 0 && hi > 0) {
        in.colors.colorMap = ColorMapId::Vik;
        const float m = std::max(-lo, hi);
        in.colors.range = {-m, m};
    } else {
        in.colors.colorMap = ColorMapId::Viridis;
        in.colors.range = {lo, hi > lo ? hi : lo + 1};
    }
    in.colorTitle = of == TimeDepthOf::Share
                        ? std::string("selected share of the shell [%]")
                        : fmt::format("{} mean over the {} [{}]", mean->name,
                                      of == TimeDepthOf::SelectedMean ? "selection" : "shell", displayUnits(mean->units));
    in.title = fmt::format("{} · steps {}–{} ({:g}–{:g} Myr) · {} range(s), level {}", in.colorTitle, first, last,
                           in.columns.front(), in.columns.back(), ranges, level);
    return in;
}

}  // namespace raypc::render
