#include "render/slice_drawing.h"

#include "core/error.h"
#include "render/legend.h"
#include "render/line_raster.h"

#include <fmt/format.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <cmath>
#include <span>

namespace raypc::render {
namespace slice {
namespace {

// Contour lines of the pixel values at `levels` (marching squares between pixel centres; a cell
// with a NaN corner draws nothing; a saddle is split by the cell's mean).
void drawContours(LineLayer& layer, const PixelSamples& s, std::span<const float> levels, float widthPx)
{
    const int w = s.width, h = s.height;
    for (const float level : levels) {
        for (int y = 0; y + 1 < h; ++y)
            for (int x = 0; x + 1 < w; ++x) {
                const float v[4] = {s.value[size_t(y) * size_t(w) + size_t(x)], s.value[size_t(y) * size_t(w) + size_t(x + 1)],
                                    s.value[size_t(y + 1) * size_t(w) + size_t(x + 1)],
                                    s.value[size_t(y + 1) * size_t(w) + size_t(x)]};
                if (std::isnan(v[0]) || std::isnan(v[1]) || std::isnan(v[2]) || std::isnan(v[3]))
                    continue;
                // Corners counter-clockwise from the top left: (x, y), (x+1, y), (x+1, y+1), (x, y+1).
                const float cx[4] = {x + 0.5f, x + 1.5f, x + 1.5f, x + 0.5f};
                const float cy[4] = {y + 0.5f, y + 0.5f, y + 1.5f, y + 1.5f};
                std::array<float, 2> cut[4];
                bool crossed[4] = {};
                int n = 0;
                for (int e = 0; e < 4; ++e) {
                    const int a = e, b = (e + 1) % 4;
                    if ((v[a] < level) != (v[b] < level)) {
                        const float t = (level - v[a]) / (v[b] - v[a]);
                        cut[e] = {cx[a] + t * (cx[b] - cx[a]), cy[a] + t * (cy[b] - cy[a])};
                        crossed[e] = true;
                        ++n;
                    }
                }
                if (n == 2) {
                    int e0 = -1, e1 = -1;
                    for (int e = 0; e < 4; ++e)
                        if (crossed[e])
                            (e0 < 0 ? e0 : e1) = e;
                    drawSegment(layer, cut[e0][0], cut[e0][1], cut[e1][0], cut[e1][1], widthPx);
                } else if (n == 4) {
                    // A saddle: the corners on the mean's side are joined.
                    const bool centreLow = (v[0] + v[1] + v[2] + v[3]) / 4 < level;
                    const bool firstLow = v[0] < level;
                    const int pairs[2][2] = {{0, 1}, {2, 3}}, other[2][2] = {{3, 0}, {1, 2}};
                    const auto& p = centreLow == firstLow ? other : pairs;
                    for (const auto& q : p)
                        drawSegment(layer, cut[q[0]][0], cut[q[0]][1], cut[q[1]][0], cut[q[1]][1], widthPx);
                }
            }
    }
}

// An arrow from (x, y) along (dx, dy) pixels: a dark halo under a light line, so that it reads over
// any colour.
void drawArrow(LineLayer& halo, LineLayer& line, float x, float y, float dx, float dy)
{
    const float len = std::hypot(dx, dy);
    if (len < 4.0f)
        return;  // slower than an eighth of the fastest: no arrow rather than a blot
    const float ux = dx / len, uy = dy / len, head = std::max(3.0f, 0.3f * len);
    const float x1 = x + dx, y1 = y + dy;
    const float hx0 = x1 - head * (ux * 0.87f - uy * 0.5f), hy0 = y1 - head * (uy * 0.87f + ux * 0.5f);
    const float hx1 = x1 - head * (ux * 0.87f + uy * 0.5f), hy1 = y1 - head * (uy * 0.87f - ux * 0.5f);
    for (auto* l : {&halo, &line}) {
        const float w = l == &halo ? 3.2f : 1.3f;
        drawSegment(*l, x, y, x1, y1, w);
        drawSegment(*l, x1, y1, hx0, hy0, w);
        drawSegment(*l, x1, y1, hx1, hy1, w);
    }
}

}  // namespace

Rgb unselectedColor(Rgb c, size_t x, size_t y)
{
    const float luma = 0.2126f * c.r + 0.7152f * c.g + 0.0722f * c.b;
    const bool hatch = (x + y) % size_t(kUnselectedHatchPx) == 0;
    const float g = 0.08f + 0.18f * luma + (hatch ? 0.22f : 0.0f);
    return {g, g, g};
}

std::vector<uint8_t> colorPixels(const PixelSamples& s, const TransferFunction& tf, Rgb background, bool greyUnselected)
{
    std::vector<uint8_t> rgba(s.value.size() * 4);
    auto byte = [](float v) { return uint8_t(std::clamp(v * 255.0f + 0.5f, 0.0f, 255.0f)); };
    // The colours in a table of 4096 positions: within a tenth of an 8-bit level of colorOf.
    constexpr int kTable = 4096;
    std::vector<Rgb> table(kTable);
    for (int k = 0; k < kTable; ++k)
        table[size_t(k)] = tf.colorAt(float(k) / (kTable - 1));
    tbb::parallel_for(size_t(0), s.value.size(), [&](size_t i) {
        Rgb c = background;
        if (!std::isnan(s.value[i])) {
            c = table[size_t(std::lround(tf.colorPositionOf(s.value[i]) * (kTable - 1)))];
            if (greyUnselected && !s.selected[i])
                c = unselectedColor(c, i % size_t(std::max(s.width, 1)), i / size_t(std::max(s.width, 1)));
        }
        rgba[i * 4 + 0] = byte(c.r);
        rgba[i * 4 + 1] = byte(c.g);
        rgba[i * 4 + 2] = byte(c.b);
        rgba[i * 4 + 3] = 255;
    });
    return rgba;
}

int arrowSpacingPx(int width, int height) { return std::max(18, std::min(width, height) / 20); }

std::string drawArrows(std::vector<uint8_t>& rgba, int width, int height, const std::vector<Arrow>& arrows, int spacing,
                       const std::string& what)
{
    double fastest = 0;
    for (const Arrow& a : arrows)
        fastest = std::max(fastest, a.speed);
    LineLayer halo(width, height, false), line(width, height, false);
    for (const Arrow& a : arrows) {
        const float len = float(0.9 * spacing * a.speed / fastest);
        drawArrow(halo, line, a.x - 0.5f * len * a.dx, a.y - 0.5f * len * a.dy, len * a.dx, len * a.dy);
    }
    compositeLines(rgba, halo, {0, 0, 0}, 0.6f);
    compositeLines(rgba, line, {1, 1, 1}, 0.95f);
    return fmt::format("arrows: {}, {} px = {:.3g} cm/yr", what, int(0.9 * spacing), fastest);
}

void drawContourLines(std::vector<uint8_t>& rgba, const PixelSamples& samples, std::span<const float> levels)
{
    if (levels.empty())
        return;
    LineLayer layer(samples.width, samples.height, false);
    drawContours(layer, samples, levels, 1.4f);
    compositeLines(rgba, layer, {0.02f, 0.02f, 0.02f}, 0.9f);
}

std::string latText(double lat) { return fmt::format("{:.1f}°{}", std::abs(lat), lat < 0 ? "S" : "N"); }
std::string lonText(double lon)
{
    lon = std::remainder(lon, 360.0);
    return fmt::format("{:.1f}°{}", std::abs(lon), lon < 0 ? "W" : "E");
}

double niceStep(double span, double target, std::initializer_list<double> steps)
{
    for (const double s : steps)
        if (span / s <= target)
            return s;
    return *(steps.end() - 1);
}

std::string fitTitle(const std::vector<std::string>& parts, int width, int height)
{
    // Measured in the labels' font (drawTextLabels), its box's padding and a margin each side.
    const int fontPx = labelFontPx(width, height);
    const int room = width - 2 * fontPx - 2 * std::max(2, fontPx / 4);
    const auto fits = [&](const std::string& t) { return legendTextWidthPx(t, fontPx) <= room; };
    std::string title = parts.front();
    for (size_t i = 1; i < parts.size(); ++i) {
        const std::string longer = title + " · " + parts[i];
        if (!fits(longer))
            break;
        title = longer;
    }
    // A first part wider than the picture loses its end (whole UTF-8 characters) to "…".
    if (fits(title))
        return title;
    while (!title.empty()) {
        while (!title.empty() && (uint8_t(title.back()) & 0xC0) == 0x80)
            title.pop_back();  // a character's continuation bytes
        if (!title.empty())
            title.pop_back();  // its first byte
        while (!title.empty() && title.back() == ' ')
            title.pop_back();
        if (fits(title + "…"))
            return title + "…";
    }
    return "…";
}

void drawDepthMarks(std::vector<uint8_t>& rgba, int width, int height, const DepthPlot& plot,
                    const state::ReferenceState::Shells& shells, std::vector<TextLabel>& labels)
{
    const int fontPx = legendFontPx(width, height);
    for (size_t k = 0; k < shells.depthsKm.size(); ++k) {
        const double d = shells.depthsKm[k];
        if (!shells.visible || d <= 0 || d >= plot.depthSpanKm)
            continue;
        LineLayer casing(width, height, false), layer(width, height, false);
        const float y = plot.yOfDepth(d);
        // Dashed: the data shows between the dashes. Each dash on a dark casing, so that it stands out
        // from every colour map beneath (the 660 km shell's yellow vanished on viridis's yellow).
        for (float x = float(plot.left); x < plot.right; x += 12) {
            drawSegment(casing, x - 1, y, std::min(float(plot.right), x + 8), y, 4.0f);
            drawSegment(layer, x, y, std::min(float(plot.right), x + 7), y, 1.5f);
        }
        const Rgb c = shellColor(shells, k);
        compositeLines(rgba, casing, {0, 0, 0}, 0.85f);
        compositeLines(rgba, layer, c, 0.95f);
        labels.push_back({fmt::format("{:g} km", d), float(plot.right + 2.2 * fontPx), y, c});
    }
}

void drawDepthPlotFrame(std::vector<uint8_t>& rgba, int width, int height, const DepthPlot& plot,
                        std::span<const std::pair<float, std::string>> xTicks, Rgb ink, std::vector<TextLabel>& labels)
{
    const int fontPx = legendFontPx(width, height);
    LineLayer layer(width, height, false);
    const float l = float(plot.left), r = float(plot.right), t = float(plot.top), b = float(plot.bottom);
    drawSegment(layer, l, t, r, t, 1.2f);
    drawSegment(layer, l, b, r, b, 1.2f);
    drawSegment(layer, l, t, l, b, 1.2f);
    drawSegment(layer, r, t, r, b, 1.2f);
    // As many ticks as their labels have room for.
    const double depthStep =
        niceStep(plot.depthSpanKm, std::max(1.0, (plot.bottom - plot.top) / (2.2 * fontPx)), {250, 500, 1000, 1500, 3000});
    for (double d = 0; d <= plot.depthSpanKm + 1e-6; d += depthStep) {
        const float y = plot.yOfDepth(d);
        drawSegment(layer, l - 0.4f * fontPx, y, l, y, 1.2f);
        labels.push_back({fmt::format("{:g} km", d), float(plot.left - 2.6 * fontPx), y, ink});
    }
    for (const auto& [x, text] : xTicks) {
        drawSegment(layer, x, b, x, b + 0.4f * fontPx, 1.2f);
        labels.push_back({text, x, float(plot.bottom + 1.1 * fontPx), ink});
    }
    compositeLines(rgba, layer, ink, 0.9f);
}

std::string regionNote(const grid::SphericalGrid& grid)
{
    if (!grid.regional())
        return "";
    const std::string lat = grid.dataLatDeg ? fmt::format("{} to {}", latText((*grid.dataLatDeg)[0]), latText((*grid.dataLatDeg)[1]))
                                            : std::string("pole to pole");
    const std::string lon = grid.dataLonDeg ? fmt::format("{} to {}", lonText((*grid.dataLonDeg)[0]), lonText((*grid.dataLonDeg)[1]))
                                            : std::string("all longitudes");
    return fmt::format("data: {}, {} (regional); none elsewhere", lat, lon);
}

void addNotes(std::vector<TextLabel>& labels, int width, int height, const std::vector<std::string>& given)
{
    std::vector<std::string> notes;
    for (const std::string& n : given)
        if (!n.empty())
            notes.push_back(fitTitle({n}, width, height));  // a long one ends in "…", not off the picture
    const int fontPx = legendFontPx(width, height);
    for (size_t i = 0; i < notes.size(); ++i)
        labels.push_back({notes[i], float(width - fontPx), float(height - fontPx * (1.2 + 1.6 * double(notes.size() - 1 - i))),
                          {0.9f, 0.9f, 0.9f}, true});
}

const state::RenderState& stateOf(const SliceInputs& in)
{
    if (!in.volume || !in.resolved)
        fail("slice: no volume or state given");
    return in.resolved->state;
}

Rgb inkFor(Rgb background)
{
    const float luma = 0.2126f * background.r + 0.7152f * background.g + 0.0722f * background.b;
    return luma > 0.5f ? Rgb{0.1f, 0.1f, 0.1f} : Rgb{0.85f, 0.85f, 0.85f};
}

size_t legendCount(const state::RenderState& s) { return s.pathlines.visible ? 2 : 1; }

}  // namespace slice

std::string latLonText(double latDeg, double lonDeg) { return slice::latText(latDeg) + " " + slice::lonText(lonDeg); }

}  // namespace raypc::render
