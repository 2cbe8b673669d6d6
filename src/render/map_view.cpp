#include "render/slice_view.h"

#include "core/error.h"
#include "core/lru_cache.h"
#include "core/spherical.h"
#include "grid/coordinates.h"
#include "grid/sampler.h"
#include "render/legend.h"
#include "render/line_raster.h"

#include <fmt/format.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <cmath>
#include <memory>
#include <span>

namespace raypc::render {
namespace {

// The depths a grid covers: from its outermost to its innermost radius.
std::pair<double, double> depthRangeKm(const SphericalGrid& grid)
{
    return {kSurfaceRadiusKm - grid.rKm.back(), kSurfaceRadiusKm - grid.rKm.front()};
}

double radiusAtDepth(const SphericalGrid& grid, double depthKm, const std::string& what)
{
    const auto [top, bottom] = depthRangeKm(grid);
    constexpr double kTolerance = 1e-6;
    if (!(depthKm >= top - kTolerance && depthKm <= bottom + kTolerance))
        fail("{}: {} km is outside the grid's depths, {:g} to {:g} km", what, depthKm, top, bottom);
    return std::clamp(kSurfaceRadiusKm - depthKm, grid.rKm.front(), grid.rKm.back());
}

// The values at a point: the colour variable, whether the brushes select it, and the velocity.
class PointProbe {
public:
    PointProbe(const StepVolume& volume, const RenderParams& params, const std::vector<std::string>& names, bool flow,
               const std::string& flowKey)
        : m_sampler(volume.grid()), m_params(params), m_color(volume.values(size_t(params.colorVariable)))
    {
        for (const RangeFilter& f : params.brushes)
            m_brushValues.push_back(f.variable >= 0 ? volume.values(size_t(f.variable)) : nullptr);
        if (flow) {
            const char* component[3] = {"vx", "vy", "vz"};
            for (int k = 0; k < 3; ++k) {
                const auto it = std::find(names.begin(), names.end(), component[k]);
                if (it == names.end())
                    fail("{}: the flow needs the velocity's components vx, vy and vz; the dataset has no {}", flowKey,
                         component[k]);
                m_velocity[size_t(k)] = volume.values(size_t(it - names.begin()));
            }
        }
    }

    struct Sample {
        float value;
        bool selected;
    };
    // At a point whose location on the grid is known (a section locates its columns and its rows
    // once).
    Sample at(const GridSampler::Location& where, double latDeg, double lonDeg, double rKm) const
    {
        auto value = [&](size_t slot) { return m_sampler.sample(slot == 0 ? m_color : m_brushValues[slot - 1], where); };
        return evaluate(value, latDeg, lonDeg, rKm);
    }

    // From now on `onShell` samples the shell of radius rKm (a map's): the colour's and the brushes'
    // variables interpolated in radius once, then in lat and lon per point (the same trilinear
    // value; GridSampler::sampleLateral).
    void fixRadius(double rKm)
    {
        const auto radial = m_sampler.locateRadius(rKm);
        if (!radial)
            fail("a shell of radius {} km is outside the grid", rKm);
        m_shellRKm = rKm;
        const SphericalGrid& g = m_sampler.grid();
        auto layerOf = [&](const float* values) {
            std::vector<double> layer(g.nLat() * g.nLon());
            tbb::parallel_for(size_t(0), g.nLat(), [&](size_t iLat) {
                const float* a = values + g.index(iLat, radial->r0, 0);
                const float* b = values + g.index(iLat, radial->r1, 0);
                for (size_t iLon = 0; iLon < g.nLon(); ++iLon)
                    layer[iLat * g.nLon() + iLon] = a[iLon] + (double(b[iLon]) - a[iLon]) * radial->tR;
            });
            return layer;
        };
        m_layers.clear();
        m_layers.push_back(layerOf(m_color));
        for (const float* values : m_brushValues)
            m_layers.push_back(values ? layerOf(values) : std::vector<double>{});
    }
    std::optional<Sample> onShell(double latDeg, double lonDeg) const
    {
        const auto where = m_sampler.locateLatLon(latDeg, lonDeg);
        if (!where)
            return std::nullopt;
        const size_t nLon = m_sampler.grid().nLon();
        auto value = [&](size_t slot) {
            const std::vector<double>& layer = m_layers[slot];
            return m_sampler.sampleLateral([&](size_t iLat, size_t iLon) { return layer[iLat * nLon + iLon]; }, *where);
        };
        return evaluate(value, latDeg, lonDeg, m_shellRKm);
    }

    // The velocity (cm/yr, Cartesian components in the contest frame) at a point.
    std::optional<Vec3d> velocityCmPerYr(double latDeg, double lonDeg, double rKm) const
    {
        const auto where = m_sampler.locate(latDeg, lonDeg, rKm);
        if (!where || !m_velocity[0])
            return std::nullopt;
        return Vec3d{m_sampler.sample(m_velocity[0], *where), m_sampler.sample(m_velocity[1], *where),
                     m_sampler.sample(m_velocity[2], *where)} *
               kMpsToCmPerYr;
    }

    const GridSampler& sampler() const { return m_sampler; }

private:
    // The colour and whether the brushes select the point, with `value(slot)` the interpolated value
    // there of the colour variable (slot 0) or of brush i's variable (slot 1 + i).
    template <class Value>
    Sample evaluate(const Value& value, double latDeg, double lonDeg, double rKm) const
    {
        bool selected = true;
        for (size_t i = 0; i < m_params.brushes.size() && selected; ++i) {
            const RangeFilter& f = m_params.brushes[i];
            const double v = f.variable >= 0 ? value(1 + i) : coordinateValue(*f.coordinate, latDeg, lonDeg, rKm);
            selected = f.contains(v);
        }
        return Sample{float(value(size_t(0))), selected};
    }

    GridSampler m_sampler;
    const RenderParams& m_params;
    const float* m_color;
    std::vector<const float*> m_brushValues;  // per brush: its variable's values, or null for a coordinate
    std::array<const float*, 3> m_velocity{};
    double m_shellRKm = NAN;                   // fixRadius's
    std::vector<std::vector<double>> m_layers;  // fixRadius's: the colour's, then per brush (empty: a coordinate)
};

// Per pixel: the colour variable (NaN where nothing is drawn) and whether it is selected.
struct PixelSamples {
    int width = 0, height = 0;
    std::vector<float> value;
    std::vector<uint8_t> selected;
    PixelSamples(int w, int h) : width(w), height(h), value(size_t(w) * size_t(h), NAN), selected(value.size(), 1) {}
};

// Samples every pixel: `sampleAt(x, y)` gives the sample at the centre of pixel (x, y), or nullopt
// where nothing is drawn.
template <class SampleAt>
PixelSamples samplePixels(int width, int height, const SampleAt& sampleAt)
{
    PixelSamples out(width, height);
    tbb::parallel_for(0, height, [&](int y) {
        for (int x = 0; x < width; ++x)
            if (const std::optional<PointProbe::Sample> s = sampleAt(x, y)) {
                const size_t i = size_t(y) * size_t(width) + size_t(x);
                out.value[i] = s->value;
                out.selected[i] = s->selected ? 1 : 0;
            }
    });
    return out;
}

// The picture's pixels: the transfer function's colour of each value over the background; what the
// brushes leave out in a muted grey of its lightness when `greyUnselected`.
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
            if (greyUnselected && !s.selected[i]) {
                const float luma = 0.2126f * c.r + 0.7152f * c.g + 0.0722f * c.b;
                const float g = 0.22f + 0.45f * luma;
                c = {g, g, g};
            }
        }
        rgba[i * 4 + 0] = byte(c.r);
        rgba[i * 4 + 1] = byte(c.g);
        rgba[i * 4 + 2] = byte(c.b);
        rgba[i * 4 + 3] = 255;
    });
    return rgba;
}

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

// An arrow of the flow at (x, y): its unit direction on the picture and its speed (cm/yr).
struct Arrow {
    float x, y, dx, dy;
    double speed;
};

// The arrows' grid spacing in pixels.
int arrowSpacingPx(int width, int height) { return std::max(18, std::min(width, height) / 20); }

// Draws the arrows centred on their points, each as long as 0.9 spacing times its speed over the
// fastest one's; returns the note of their scale ("what: 29 px = 1.23 cm/yr").
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

// The contour lines of the picture's values, dark over the colours.
void drawContourLines(std::vector<uint8_t>& rgba, const PixelSamples& samples, std::span<const float> levels)
{
    if (levels.empty())
        return;
    LineLayer layer(samples.width, samples.height, false);
    drawContours(layer, samples, levels, 1.4f);
    compositeLines(rgba, layer, {0.02f, 0.02f, 0.02f}, 0.9f);
}

// A polyline of (lon, lat) degrees on the map, subdivided to at most half a degree a segment; a
// segment is left out where an end is not shown or where it jumps across the map (the seam).
void drawMapPolyline(LineLayer& layer, const MapFrame& frame, std::span<const std::pair<float, float>> lonLat,
                     float widthPx, double jumpPx)
{
    std::optional<std::array<double, 2>> last;
    auto add = [&](double lon, double lat) {
        const auto p = frame.pixelOf(lon, lat);
        if (p && last && std::hypot((*p)[0] - (*last)[0], (*p)[1] - (*last)[1]) < jumpPx)
            drawSegment(layer, float((*last)[0]), float((*last)[1]), float((*p)[0]), float((*p)[1]), widthPx);
        last = p;
    };
    for (size_t i = 0; i < lonLat.size(); ++i) {
        if (i == 0) {
            add(lonLat[0].first, lonLat[0].second);
            continue;
        }
        const auto [lon0, lat0] = lonLat[i - 1];
        auto [lon1, lat1] = lonLat[i];
        if (lon1 - lon0 > 180.0f)
            lon1 -= 360.0f;  // across the date line the short way
        else if (lon0 - lon1 > 180.0f)
            lon1 += 360.0f;
        const int pieces = std::max(1, int(std::ceil(std::max(std::abs(lon1 - lon0), std::abs(lat1 - lat0)) / 0.5)));
        for (int k = 1; k <= pieces; ++k) {
            const double t = double(k) / pieces;
            add(lon0 + t * (lon1 - lon0), lat0 + t * (lat1 - lat0));
        }
    }
}

std::string latText(double lat) { return fmt::format("{:.1f}°{}", std::abs(lat), lat < 0 ? "S" : "N"); }
std::string lonText(double lon)
{
    lon = std::remainder(lon, 360.0);
    return fmt::format("{:.1f}°{}", std::abs(lon), lon < 0 ? "W" : "E");
}

// A round step for about `target` intervals over `span`.
double niceStep(double span, double target, std::initializer_list<double> steps)
{
    for (const double s : steps)
        if (span / s <= target)
            return s;
    return *(steps.end() - 1);
}

// The title from its parts (" · " between them), as many as fit the picture's width: the first
// always, the later ones (time, projection) only where there is room.
std::string fitTitle(const std::vector<std::string>& parts, int width, int height)
{
    // About 0.55 em a character at the labels' size (drawTextLabels: 5/6 of the legend's font).
    const double em = std::max(10, legendFontPx(width, height) * 5 / 6), room = width - 2.0 * em;
    std::string title = parts.front();
    for (size_t i = 1; i < parts.size(); ++i) {
        const std::string longer = title + " · " + parts[i];
        if (0.55 * em * double(longer.size()) > room)
            break;
        title = longer;
    }
    return title;
}

// A depth plot's box (sections, time–depth pictures): pixels, depth 0 at `top`, `depthSpanKm` at
// `bottom`.
struct DepthPlot {
    double left, right, top, bottom, depthSpanKm;
    float yOfDepth(double d) const { return float(top + d / depthSpanKm * (bottom - top)); }
};

// Dashed lines across the plot at the reference shells' depths (when visible), labelled at the right.
void drawDepthMarks(std::vector<uint8_t>& rgba, int width, int height, const DepthPlot& plot,
                    const ReferenceState::Shells& shells, std::vector<TextLabel>& labels)
{
    const int fontPx = legendFontPx(width, height);
    for (size_t k = 0; k < shells.depthsKm.size(); ++k) {
        const double d = shells.depthsKm[k];
        if (!shells.visible || d <= 0 || d >= plot.depthSpanKm)
            continue;
        LineLayer layer(width, height, false);
        const float y = plot.yOfDepth(d);
        // Dashed: the data shows between the dashes.
        for (float x = float(plot.left); x < plot.right; x += 12)
            drawSegment(layer, x, y, std::min(float(plot.right), x + 7), y, 1.5f);
        const Rgb c = shellColor(shells, k);
        compositeLines(rgba, layer, c, 0.95f);
        labels.push_back({fmt::format("{:g} km", d), float(plot.right + 2.2 * fontPx), y, c});
    }
}

// The plot's frame, depth ticks every 250, 500, … km at the left and `xTicks` (position, label) below.
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

// What else a picture says, right-aligned above its bottom edge, one line each: what grey means,
// the arrows' scale and the pathlines drawn.
void addNotes(std::vector<TextLabel>& labels, int width, int height, const std::vector<std::string>& given)
{
    std::vector<std::string> notes;
    for (const std::string& n : given)
        if (!n.empty())
            notes.push_back(n);
    const int fontPx = legendFontPx(width, height);
    for (size_t i = 0; i < notes.size(); ++i)
        labels.push_back({notes[i], float(width - fontPx), float(height - fontPx * (1.2 + 1.6 * double(notes.size() - 1 - i))),
                          {0.9f, 0.9f, 0.9f}, true});
}

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
    const RenderState& state = in.resolved->state;
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

const RenderState& stateOf(const SliceInputs& in)
{
    if (!in.volume || !in.resolved)
        fail("slice: no volume or state given");
    return in.resolved->state;
}

// The colour of the lines drawn over the data (contours, frame): dark over a light background,
// light over a dark one.
Rgb inkFor(Rgb background)
{
    const float luma = 0.2126f * background.r + 0.7152f * background.g + 0.0722f * background.b;
    return luma > 0.5f ? Rgb{0.1f, 0.1f, 0.1f} : Rgb{0.85f, 0.85f, 0.85f};
}

}  // namespace

namespace {

// A map's band: below the title, above the legend.
double mapTopPx(const RenderState& s) { return 2.2 * legendFontPx(s.width, s.height); }
// The colour legend, and the pathlines' when they are shown.
size_t legendCount(const RenderState& s) { return s.pathlines.visible ? 2 : 1; }
double mapBottomPx(const RenderState& s) { return s.height - legendsHeightPx(s.width, s.height, legendCount(s)); }

}  // namespace

std::string latLonText(double latDeg, double lonDeg) { return latText(latDeg) + " " + lonText(lonDeg); }

MapFrame mapFrameOf(const RenderState& s)
{
    const int fontPx = legendFontPx(s.width, s.height);
    const double top = mapTopPx(s), bottom = mapBottomPx(s);
    // The picture's size in the message: the frame's own is what is left after titles and legends.
    if (!(s.width - 2.0 * fontPx >= 8 && bottom - top - 0.5 * fontPx >= 8))
        fail("map: a picture of {}x{} pixels has no room for the map; choose a larger size", s.width, s.height);
    return MapFrame(s.map, fontPx, top, s.width - 2.0 * fontPx, bottom - top - 0.5 * fontPx);
}

SectionLayout sectionLayoutOf(const RenderState& s, const SphericalGrid& grid)
{
    const int fontPx = legendFontPx(s.width, s.height);
    // Depth labels at the left, the shells' names at the right, the title above, distance labels
    // and the legend below.
    SectionLayout l{5.5 * fontPx, s.width - 4.5 * fontPx, 2.4 * fontPx,
                    s.height - legendsHeightPx(s.width, s.height, legendCount(s)) - 2.2 * fontPx, depthRangeKm(grid).second};
    if (!(l.right - l.left >= 8 && l.bottom - l.top >= 8))
        fail("section: a picture of {}x{} pixels has no room for the section; choose a larger size", s.width, s.height);
    return l;
}

MapFrame::MapFrame(const MapState& map, double left, double top, double width, double height)
    : m_projector(map.projection, map.centralMeridianDeg,
                  map.projection == MapProjection::Orthographic ? map.centralLatitudeDeg : 0.0)
{
    if (!(width >= 1 && height >= 1))
        fail("map: a picture of {:.0f}x{:.0f} pixels has no room for the map", width, height);
    const Projector::Extent e = m_projector.extent();
    m_scale = std::min(width / (2 * e.xMax), height / (2 * e.yMax));
    m_cx = left + width / 2;
    m_cy = top + height / 2;
}

std::optional<std::array<double, 2>> MapFrame::lonLatAt(double px, double py) const
{
    return m_projector.inverse((px - m_cx) / m_scale, (m_cy - py) / m_scale);
}

std::optional<std::array<double, 2>> MapFrame::pixelOf(double lonDeg, double latDeg) const
{
    const auto xy = m_projector.forward(lonDeg, latDeg);
    if (!xy)
        return std::nullopt;
    return std::array{m_cx + (*xy)[0] * m_scale, m_cy - (*xy)[1] * m_scale};
}

GreatCircle::GreatCircle(SectionState::Point from, SectionState::Point to, const std::string& what)
{
    m_from = normalize(sphericalToCartesianKm(from.latDeg, from.lonDeg, 1.0));
    const Vec3d b = normalize(sphericalToCartesianKm(to.latDeg, to.lonDeg, 1.0));
    m_angleRad = std::acos(std::clamp(dot(m_from, b), -1.0, 1.0));
    if (m_angleRad < degToRad(0.01))
        fail("{}: the ends {}, {} and {}, {} are less than 0.01° apart", what, latText(from.latDeg), lonText(from.lonDeg),
             latText(to.latDeg), lonText(to.lonDeg));
    if (m_angleRad > degToRad(179.99))
        fail("{}: the ends {}, {} and {}, {} are antipodal: every great circle through them is as short; move one "
             "end",
             what, latText(from.latDeg), lonText(from.lonDeg), latText(to.latDeg), lonText(to.lonDeg));
    m_ortho = normalize(b - m_from * dot(m_from, b));
}

double GreatCircle::lengthKm() const { return m_angleRad * kSurfaceRadiusKm; }

std::array<double, 2> GreatCircle::locate(const Vec3d& p) const
{
    const Vec3d u = normalize(p), normal = cross(m_from, m_ortho);
    return {std::atan2(dot(u, m_ortho), dot(u, m_from)) / m_angleRad, std::asin(std::clamp(dot(u, normal), -1.0, 1.0))};
}

double GreatCircle::azimuthDeg() const
{
    const SphericalPoint a = cartesianToSpherical(m_from);
    const auto [east, north] = eastNorthAt(a.latDeg, a.lonDeg);
    const double az = radToDeg(std::atan2(dot(m_ortho, east), dot(m_ortho, north)));
    return az < 0 ? az + 360 : az;
}

SectionState::Point GreatCircle::pointAlong(SectionState::Point from, double azimuthDeg, double distanceDeg)
{
    const Vec3d a = normalize(sphericalToCartesianKm(from.latDeg, from.lonDeg, 1.0));
    const auto [east, north] = eastNorthAt(from.latDeg, from.lonDeg);
    const double az = degToRad(azimuthDeg), d = degToRad(distanceDeg);
    const SphericalPoint p =
        cartesianToSpherical(a * std::cos(d) + (north * std::cos(az) + east * std::sin(az)) * std::sin(d));
    return {float(p.latDeg), float(p.lonDeg > 180 ? p.lonDeg - 360 : p.lonDeg)};
}

Vec3d GreatCircle::at(double fraction) const
{
    const double a = fraction * m_angleRad;
    return m_from * std::cos(a) + m_ortho * std::sin(a);
}

Vec3d GreatCircle::tangentAt(double fraction) const
{
    const double a = fraction * m_angleRad;
    return m_ortho * std::cos(a) - m_from * std::sin(a);
}

namespace {

// Every pixel's point (lat, lon in degrees; NaN off the sphere) of a map frame: the inverse
// projection of each pixel centre, the bulk of a map's cost. The same for every depth and step, so
// the last frames' are kept: dragging the depth (or playing the series) redraws without it.
struct MapPixelsKey {
    MapProjection projection;
    double centralMeridianDeg, centralLatitudeDeg, scale, cx, cy;
    int width, height;
    bool operator==(const MapPixelsKey&) const = default;
};
using MapPixelPoints = std::vector<std::array<float, 2>>;

std::shared_ptr<const MapPixelPoints> mapPixelPoints(const MapState& map, const MapFrame& frame, int width, int height)
{
    auto make = [&] {
        MapPixelPoints points(size_t(width) * size_t(height), {NAN, NAN});
        tbb::parallel_for(0, height, [&](int y) {
            for (int x = 0; x < width; ++x)
                if (const auto ll = frame.lonLatAt(x + 0.5, y + 0.5))
                    points[size_t(y) * size_t(width) + size_t(x)] = {float((*ll)[1]), float((*ll)[0])};
        });
        return points;
    };
    // Two frames (the map pane's and a full-size figure's, say): 16 MB each at 1920 x 1080; larger
    // pictures (screenshots, figures) are not kept.
    constexpr int64_t kMostPixelsKept = int64_t(3840) * 2160;
    if (int64_t(width) * height > kMostPixelsKept)
        return std::make_shared<const MapPixelPoints>(make());
    static LruCache<MapPixelsKey, MapPixelPoints> cache(2);
    const auto [cx, cy] = frame.centrePx();
    const double centralLatitudeDeg = map.projection == MapProjection::Orthographic ? map.centralLatitudeDeg : 0.0;
    return cache.get(MapPixelsKey{map.projection, map.centralMeridianDeg, centralLatitudeDeg, frame.scale(), cx, cy, width, height},
                     make);
}

}  // namespace

ImageRgba8 mapPicture(const SliceInputs& in)
{
    const RenderState& state = stateOf(in);
    const RenderParams& params = in.resolved->params;
    const MapState& map = state.map;
    const int width = state.width, height = state.height;
    const SphericalGrid& grid = in.volume->grid();
    const double rKm = radiusAtDepth(grid, map.depthKm, "map.depthKm");
    PointProbe probe(*in.volume, params, in.variableNames, map.flow, "map.flow");

    const int fontPx = legendFontPx(width, height);
    const double top = mapTopPx(state), bottom = mapBottomPx(state);
    const MapFrame frame = mapFrameOf(state);
    probe.fixRadius(rKm);
    const std::shared_ptr<const MapPixelPoints> points = mapPixelPoints(map, frame, width, height);
    const PixelSamples samples = samplePixels(width, height, [&](int x, int y) -> std::optional<PointProbe::Sample> {
        const auto [lat, lon] = (*points)[size_t(y) * size_t(width) + size_t(x)];
        if (std::isnan(lat))
            return std::nullopt;
        return probe.onShell(lat, lon);
    });
    const bool grey = map.greyUnselected && !params.brushes.empty();
    ImageRgba8 image{width, height, colorPixels(samples, params.transfer, state.background, grey)};
    const Rgb ink = inkFor(state.background);
    const double jumpPx = 0.25 * width;

    // The graticule and the coastlines of the state's reference, the sphere's outline always.
    const ReferenceState& ref = state.reference;
    if (ref.graticule.visible && ref.graticule.opacity > 0) {
        LineLayer layer(width, height, false);
        const float step = ref.graticule.spacingDeg;
        const double lon0 = map.centralMeridianDeg;
        for (float lat = -90.0f + step; lat < 90.0f - 1e-3f; lat += step) {
            std::vector<std::pair<float, float>> parallel;
            for (int k = 0; k <= 720; ++k)
                parallel.emplace_back(float(lon0 - 180 + 0.5 * k), lat);
            drawMapPolyline(layer, frame, parallel, ref.lineWidthPx * 0.75f, jumpPx);
        }
        for (float lon = 0.0f; lon < 360.0f - 1e-3f; lon += step) {
            std::vector<std::pair<float, float>> meridian;
            for (int lat = -90; lat <= 90; ++lat)
                meridian.emplace_back(lon, float(lat));
            drawMapPolyline(layer, frame, meridian, ref.lineWidthPx * 0.75f, jumpPx);
        }
        compositeLines(image.pixels, layer, ref.graticule.color, ref.graticule.opacity);
    }
    if (ref.coastlines.visible && ref.coastlines.opacity > 0) {
        if (!in.coastlines)
            fail("reference.coastlines: visible, but no coastlines were given");
        // Over a dark halo, so that the state's colour (chosen for the globe) reads on light colours too.
        LineLayer halo(width, height, false), layer(width, height, false);
        for (const auto& line : in.coastlines->lines) {
            drawMapPolyline(halo, frame, line, ref.lineWidthPx + 1.5f, jumpPx);
            drawMapPolyline(layer, frame, line, ref.lineWidthPx, jumpPx);
        }
        compositeLines(image.pixels, halo, {0, 0, 0}, 0.55f * ref.coastlines.opacity);
        compositeLines(image.pixels, layer, ref.coastlines.color, ref.coastlines.opacity);
    }
    {
        // The sphere's outline: along rays from the map's centre, the last point the projection
        // inverts (bisection), joined in the picture's plane.
        LineLayer layer(width, height, false);
        const Projector::Extent e = frame.projector().extent();
        const auto [cx, cy] = frame.centrePx();
        std::optional<std::array<float, 2>> last;
        const int n = 1440;
        for (int k = 0; k <= n; ++k) {
            const double a = 2 * M_PI * k / n, dx = std::cos(a), dy = std::sin(a);
            double lo = 0, hi = 1.01 * std::hypot(e.xMax, e.yMax);
            for (int i = 0; i < 40; ++i) {
                const double mid = (lo + hi) / 2;
                (frame.projector().inverse(dx * mid, dy * mid) ? lo : hi) = mid;
            }
            const std::array p{float(cx + dx * lo * frame.scale()), float(cy - dy * lo * frame.scale())};
            if (last)
                drawSegment(layer, (*last)[0], (*last)[1], p[0], p[1], 1.2f);
            last = p;
        }
        compositeLines(image.pixels, layer, ink, 0.8f);
    }
    drawContourLines(image.pixels, samples, map.contours);
    std::string flowText;
    if (map.flow) {
        // Arrows on a regular grid of the picture, their length the horizontal speed over the
        // largest one among them.
        const int spacing = arrowSpacingPx(width, height);
        std::vector<Arrow> arrows;
        for (int y = int(top) + spacing / 2; y < int(bottom); y += spacing)
            for (int x = spacing / 2; x < width; x += spacing) {
                const auto ll = frame.lonLatAt(x, y);
                if (!ll)
                    continue;
                const double lon = (*ll)[0], lat = (*ll)[1];
                const auto v = probe.velocityCmPerYr(lat, lon, rKm);
                if (!v)
                    continue;
                const EastNorth basis = eastNorthAt(lat, lon);
                const double ve = dot(*v, basis.east), vn = dot(*v, basis.north), speed = std::hypot(ve, vn);
                if (!(speed > 0))
                    continue;
                // The flow's direction on the map: a step of a tenth of a degree along it, projected.
                const double d = 0.1;
                const auto p0 = frame.pixelOf(lon, lat);
                const auto p1 = frame.pixelOf(lon + d * ve / speed / std::max(1e-6, std::cos(degToRad(lat))), lat + d * vn / speed);
                if (!p0 || !p1)
                    continue;
                const double ux = (*p1)[0] - (*p0)[0], uy = (*p1)[1] - (*p0)[1], ul = std::hypot(ux, uy);
                if (!(ul > 0) || ul > 0.1 * width)
                    continue;
                arrows.push_back({float(x), float(y), float(ux / ul), float(uy / ul), speed});
            }
        flowText = drawArrows(image.pixels, width, height, arrows, spacing, "horizontal flow");
    }

    std::vector<LegendSpec> legends{{in.colorTitle, params.transfer}};
    const std::string pathlineText = drawPathlines(
        image.pixels, width, height, in,
        [&](float x, float y, float z) -> std::optional<PlacedPoint> {
            const SphericalPoint p = cartesianToSpherical({x, y, z});
            const auto px = frame.pixelOf(p.lonDeg, p.latDeg);
            if (!px)
                return std::nullopt;
            const double off = std::max(0.0, std::abs(kSurfaceRadiusKm - p.rKm - map.depthKm) - kMapPathlineBandKm);
            return PlacedPoint{float((*px)[0]), float((*px)[1]), float(0.15 + 0.85 * std::exp(-std::pow(off / kMapPathlineBandKm, 2)))};
        },
        fmt::format("(full within {:g} km of this depth, fainter beyond)", kMapPathlineBandKm), legends);

    std::string where = fmt::format("{} centred on {}", mapProjectionTitle(map.projection), lonText(map.centralMeridianDeg));
    if (map.projection == MapProjection::Orthographic)
        where += ", " + latText(map.centralLatitudeDeg);
    const std::string title = fitTitle({fmt::format("{} at {:g} km depth", in.colorTitle, map.depthKm), in.when, where}, width, height);
    std::vector<TextLabel> labels{{title, width / 2.0f, 1.1f * fontPx, {1, 1, 1}}};
    addNotes(labels, width, height, {grey ? "grey: outside the brushes" : "", flowText, pathlineText});
    drawTextLabels(image.pixels, width, height, labels);
    drawLegends(image.pixels, width, height, legends);
    return image;
}

ImageRgba8 sectionPicture(const SliceInputs& in)
{
    const RenderState& state = stateOf(in);
    const RenderParams& params = in.resolved->params;
    const SectionState& section = state.section;
    const int width = state.width, height = state.height;
    const SphericalGrid& grid = in.volume->grid();
    const GreatCircle circle(section.from, section.to);
    const PointProbe probe(*in.volume, params, in.variableNames, section.flow, "section.flow");

    const int fontPx = legendFontPx(width, height);
    // Plain variables, not a structured binding: the lambdas below capture them (clang 14 cannot
    // capture bindings).
    const SectionLayout layout = sectionLayoutOf(state, grid);
    const double left = layout.left, right = layout.right, top = layout.top, bottom = layout.bottom;
    const double depthSpan = layout.depthSpanKm;
    auto pointAt = [&](double x, double y) -> std::optional<std::array<double, 3>> {
        if (x < left || x > right || y < top || y > bottom)
            return std::nullopt;
        const double f = (x - left) / (right - left), depth = (y - top) / (bottom - top) * depthSpan;
        const double r = kSurfaceRadiusKm - depth;
        if (r < grid.rKm.front() - 1e-6)
            return std::nullopt;
        const SphericalPoint p = cartesianToSpherical(circle.at(f));
        return std::array{p.latDeg, p.lonDeg, std::clamp(r, grid.rKm.front(), grid.rKm.back())};
    };
    // Every column's point on the arc and every row's radius located once.
    const GridSampler& sampler = probe.sampler();
    struct Column {
        double latDeg, lonDeg;
        GridSampler::LateralPart where;
    };
    std::vector<std::optional<Column>> columns(static_cast<size_t>(width));
    for (int x = 0; x < width; ++x)
        if (const auto p = pointAt(x + 0.5, top))
            if (const auto where = sampler.locateLatLon((*p)[0], (*p)[1]))
                columns[size_t(x)] = Column{(*p)[0], (*p)[1], *where};
    std::vector<std::optional<std::pair<double, GridSampler::RadialPart>>> rows(static_cast<size_t>(height));
    for (int y = 0; y < height; ++y)
        if (const auto p = pointAt(0.5 * (left + right), y + 0.5))
            if (const auto where = sampler.locateRadius((*p)[2]))
                rows[size_t(y)] = {(*p)[2], *where};
    const PixelSamples samples = samplePixels(width, height, [&](int x, int y) -> std::optional<PointProbe::Sample> {
        const auto& column = columns[size_t(x)];
        const auto& row = rows[size_t(y)];
        if (!column || !row)
            return std::nullopt;
        return probe.at(GridSampler::combine(column->where, row->second), column->latDeg, column->lonDeg, row->first);
    });
    const bool grey = state.map.greyUnselected && !params.brushes.empty();
    ImageRgba8 image{width, height, colorPixels(samples, params.transfer, state.background, grey)};
    const Rgb ink = inkFor(state.background);
    const DepthPlot plot{left, right, top, bottom, depthSpan};
    auto xOfFraction = [&](double f) { return float(left + f * (right - left)); };

    drawContourLines(image.pixels, samples, state.map.contours);
    std::vector<TextLabel> labels;
    drawDepthMarks(image.pixels, width, height, plot, state.reference.shells, labels);
    std::string flowText;
    if (section.flow) {
        const int spacing = arrowSpacingPx(width, height);
        std::vector<Arrow> arrows;
        const double kmPerPxX = circle.lengthKm() / (right - left), kmPerPxY = depthSpan / (bottom - top);
        for (double y = top + spacing / 2.0; y < bottom; y += spacing)
            for (double x = left + spacing / 2.0; x < right; x += spacing) {
                const auto p = pointAt(x, y);
                if (!p)
                    continue;
                const auto v = probe.velocityCmPerYr((*p)[0], (*p)[1], (*p)[2]);
                if (!v)
                    continue;
                const double f = (x - left) / (right - left);
                const double along = dot(*v, circle.tangentAt(f)), radial = dot(*v, circle.at(f));
                // On the picture: along the profile to the right, radial up, each axis at its own km
                // per pixel (the section is not drawn at true scale).
                const double sx = along / kmPerPxX, sy = -radial / kmPerPxY, sl = std::hypot(sx, sy);
                const double speed = std::hypot(along, radial);
                if (!(sl > 0))
                    continue;
                arrows.push_back({float(x), float(y), float(sx / sl), float(sy / sl), speed});
            }
        flowText = drawArrows(image.pixels, width, height, arrows, spacing,
                              "flow in the section's plane (directions on the picture's axes)");
    }
    std::vector<LegendSpec> legends{{in.colorTitle, params.transfer}};
    const std::string pathlineText = drawPathlines(
        image.pixels, width, height, in,
        [&](float x, float y, float z) -> std::optional<PlacedPoint> {
            const Vec3d p{x, y, z};
            const double r = length(p);
            if (!(r > 0))
                return std::nullopt;
            const auto [fraction, offRad] = circle.locate(p);
            const double offKm = std::abs(offRad) * r;
            if (fraction < 0 || fraction > 1 || offKm > kSectionPathlineBandKm)
                return std::nullopt;
            return PlacedPoint{xOfFraction(fraction), plot.yOfDepth(kSurfaceRadiusKm - r), float(1 - 0.8 * offKm / kSectionPathlineBandKm)};
        },
        fmt::format("within {:g} km of the section's plane", kSectionPathlineBandKm), legends);
    {
        // Distance ticks in round degrees, as many as their labels have room for.
        const double lengthDeg = circle.lengthDeg();
        const double degStep = niceStep(lengthDeg, std::max(1.0, (right - left) / (11.0 * fontPx)), {1, 2, 5, 10, 15, 20, 30, 45, 60, 90, 180});
        std::vector<std::pair<float, std::string>> ticks;
        for (double a = 0; a <= lengthDeg + 1e-9; a += degStep)
            ticks.emplace_back(xOfFraction(a / lengthDeg), fmt::format("{:g}° · {:.0f} km", a, degToRad(a) * kSurfaceRadiusKm));
        drawDepthPlotFrame(image.pixels, width, height, plot, ticks, ink, labels);
    }
    const SphericalPoint a = cartesianToSpherical(circle.at(0)), z = cartesianToSpherical(circle.at(1));
    const std::string title = fitTitle({in.colorTitle, in.when,
                                        fmt::format("section from {} to {}", latLonText(a.latDeg, a.lonDeg),
                                                    latLonText(z.latDeg, z.lonDeg)),
                                        fmt::format("{:.1f}°, {:.0f} km along the surface, azimuth {:.0f}°",
                                                    circle.lengthDeg(), circle.lengthKm(), circle.azimuthDeg())},
                                       width, height);
    labels.push_back({title, width / 2.0f, 1.1f * fontPx, {1, 1, 1}});
    addNotes(labels, width, height, {grey ? "grey: outside the brushes" : "", flowText, pathlineText});
    drawTextLabels(image.pixels, width, height, labels);
    drawLegends(image.pixels, width, height, legends);
    return image;
}

namespace {
// Depth labels at the left, the marks' names at the right, the title above, time labels and the
// legend below (a section's layout).
DepthPlot timeDepthPlot(int width, int height, double depthSpanKm)
{
    const int fontPx = legendFontPx(width, height);
    const DepthPlot plot{5.5 * fontPx, width - 4.5 * fontPx, 2.4 * fontPx,
                         height - legendsHeightPx(width, height, 1) - 2.2 * fontPx, depthSpanKm};
    if (!(plot.right - plot.left >= 8 && plot.bottom - plot.top >= 8))
        fail("time-depth picture: {}x{} pixels have no room for the plot; choose a larger size", width, height);
    return plot;
}
}  // namespace

void checkTimeDepthPictureSize(int width, int height) { timeDepthPlot(width, height, 1.0); }

ImageRgba8 timeDepthPicture(const TimeDepthInputs& in)
{
    const size_t nSteps = in.timesMyr.size(), nR = in.radiiKm.size();
    if (nSteps == 0 || nR < 2 || in.values.size() != nSteps * nR)
        fail("time-depth picture: {} values for {} steps and {} radii", in.values.size(), nSteps, nR);
    const int width = in.width, height = in.height, fontPx = legendFontPx(width, height);
    const DepthPlot plot = timeDepthPlot(width, height, kSurfaceRadiusKm - in.radiiKm.front());
    // The time axis spans the steps' times, half a step beyond the first and last (one step: 1 Myr).
    const double dt = nSteps > 1 ? (in.timesMyr.back() - in.timesMyr.front()) / double(nSteps - 1) : 1.0;
    const double t0 = in.timesMyr.front() - dt / 2, t1 = in.timesMyr.back() + dt / 2;
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
                                             : nearest(in.timesMyr, t0 + (x + 0.5 - plot.left) / (plot.right - plot.left) * (t1 - t0));
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
    const double span = in.timesMyr.back() - in.timesMyr.front();
    if (span > 0) {
        const double step = niceStep(span, std::max(1.0, (plot.right - plot.left) / (6.0 * fontPx)),
                                     {0.1, 0.2, 0.5, 1, 2, 5, 10, 20, 50, 100, 200, 500, 1000, 2000, 5000});
        for (double t = std::ceil(in.timesMyr.front() / step) * step; t <= in.timesMyr.back() + 1e-9; t += step)
            ticks.emplace_back(xOfTime(t), fmt::format("{:g} Myr", t));
    } else {
        ticks.emplace_back(xOfTime(in.timesMyr.front()), fmt::format("{:g} Myr", in.timesMyr.front()));
    }
    drawDepthPlotFrame(image.pixels, width, height, plot, ticks, ink, labels);
    labels.push_back({fitTitle({in.title}, width, height), width / 2.0f, 1.1f * fontPx, {1, 1, 1}});
    const bool blank = std::any_of(in.values.begin(), in.values.end(), [](float v) { return std::isnan(v); });
    addNotes(labels, width, height, {blank ? "background: nothing selected at that depth and time" : ""});
    drawTextLabels(image.pixels, width, height, labels);
    const LegendSpec legend{in.colorTitle, in.colors};
    drawLegends(image.pixels, width, height, std::span(&legend, 1));
    return image;
}

SliceGrid latLonSlice(const StepVolume& volume, size_t variable, double depthKm, double stepDeg, const std::string& what)
{
    const SphericalGrid& grid = volume.grid();
    const double rKm = radiusAtDepth(grid, depthKm, what);
    const double n = 180.0 / stepDeg;
    if (!(stepDeg > 0) || std::abs(n - std::round(n)) > 1e-9 || n > 36000)
        fail("{}: a grid step of {}° does not divide 180° (e.g. 0.5, 1, 2)", what, stepDeg);
    const size_t nLat = size_t(std::round(n)), nLon = 2 * nLat;
    SliceGrid out;
    for (size_t i = 0; i < nLat; ++i)
        out.rows.push_back(-90 + (double(i) + 0.5) * stepDeg);
    for (size_t j = 0; j < nLon; ++j)
        out.columns.push_back((double(j) + 0.5) * stepDeg);
    out.values.assign(nLat * nLon, NAN);
    const GridSampler sampler(grid);
    const float* values = volume.values(variable);
    tbb::parallel_for(size_t(0), nLat, [&](size_t i) {
        for (size_t j = 0; j < nLon; ++j)
            if (const auto at = sampler.locate(out.rows[i], out.columns[j], rKm))
                out.values[i * nLon + j] = float(sampler.sample(values, *at));
    });
    return out;
}

SectionGrid sectionGrid(const StepVolume& volume, size_t variable, const SectionState& section, int columns, int rows)
{
    if (columns < 2 || rows < 2)
        fail("section: a grid of {} x {} points; expected at least 2 x 2", columns, rows);
    const SphericalGrid& grid = volume.grid();
    const GreatCircle circle(section.from, section.to);
    const double bottom = depthRangeKm(grid).second;
    SectionGrid out;
    for (int j = 0; j < columns; ++j) {
        const double f = double(j) / (columns - 1);
        const SphericalPoint p = cartesianToSpherical(circle.at(f));
        out.grid.columns.push_back(f * circle.lengthKm());
        out.distanceDeg.push_back(f * circle.lengthDeg());
        out.latDeg.push_back(p.latDeg);
        out.lonDeg.push_back(p.lonDeg);
    }
    for (int i = 0; i < rows; ++i)
        out.grid.rows.push_back(bottom * i / (rows - 1));
    out.grid.depthsKm = out.grid.rows;
    out.grid.values.assign(size_t(rows) * size_t(columns), NAN);
    const GridSampler sampler(grid);
    const float* values = volume.values(variable);
    tbb::parallel_for(0, rows, [&](int i) {
        const double r = std::clamp(kSurfaceRadiusKm - out.grid.rows[size_t(i)], grid.rKm.front(), grid.rKm.back());
        for (int j = 0; j < columns; ++j)
            if (const auto at = sampler.locate(out.latDeg[size_t(j)], out.lonDeg[size_t(j)], r))
                out.grid.values[size_t(i) * size_t(columns) + size_t(j)] = float(sampler.sample(values, *at));
    });
    return out;
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

void appendTimeDepthValues(std::span<const StepSelection> selections, TimeDepthOf of, std::vector<float>& out)
{
    for (const StepSelection& sel : selections) {
        const SelectionStats& s = sel.stats;
        for (size_t iR = 0; iR < s.volumeByRadiusKm3.size(); ++iR)
            out.push_back(float(of == TimeDepthOf::Share          ? 100.0 * s.volumeByRadiusKm3[iR] / s.shellVolumeByRadiusKm3[iR]
                                : of == TimeDepthOf::SelectedMean ? s.selectedMeanByRadius[iR]
                                                                  : s.shellMeanByRadius[iR]));
    }
}

TimeDepthInputs timeDepthInputs(const Dataset& dataset, int first, int last, int level, std::vector<float> values,
                                TimeDepthOf of, const VariableInfo* mean, size_t ranges)
{
    if (of != TimeDepthOf::Share && !mean)
        fail("time-depth picture: the mean of which variable? (none given)");
    TimeDepthInputs in;
    for (int step = first; step <= last; ++step)
        in.timesMyr.push_back(dataset.steps().at(size_t(step)).timeMyr);
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
                           in.timesMyr.front(), in.timesMyr.back(), ranges, level);
    return in;
}

}  // namespace raypc::render
