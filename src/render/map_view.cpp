// Maps of a depth slice (slice_view.h): where a map's pixels fall (MapFrame), the picture
// (mapPicture) and the lat–lon grid exported as CF netCDF (latLonSlice).
#include "render/slice_view.h"

#include "core/error.h"
#include "core/lru_cache.h"
#include "core/spherical.h"
#include "grid/sampler.h"
#include "render/legend.h"
#include "render/line_raster.h"
#include "render/slice_drawing.h"
#include "render/slice_sampling.h"

#include <fmt/format.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <cmath>
#include <memory>
#include <span>

namespace raypc::render {
namespace {

// Where a map goes in its picture: below the title, and above the legends or, in a picture wide
// enough for the map at the full height and the legends beside it (a pane of the UI's bottom panel),
// the whole height with the legends to its right: a wide, low picture used to leave most of its
// height to the legends and the map a third of its width.
struct MapLayout {
    double left, top, width, height;
    int legendsLeftPx = -1;  // the legends' left edge when beside the map (-1: below it)
};

MapLayout mapLayoutOf(const state::RenderState& s)
{
    const int fontPx = legendFontPx(s.width, s.height);
    const double top = 2.2 * fontPx;
    const Projector::Extent e = Projector(s.map.projection, 0.0, 0.0).extent();
    const double aspect = e.xMax / e.yMax;
    // Beside: the map as high as the picture allows, then a gap and the legends' panel.
    const double fullHeight = s.height - fontPx - top - 0.5 * fontPx;
    // The legends' panel: its bar, or a title of up to about 26 characters (the UI's slice_panel.ts
    // sizes the map's pane by the same rule).
    const int legendsW = std::max(legendBarPx(s.width, s.height), 14 * fontPx) + fontPx;
    const double besideW = fullHeight * aspect;
    if (fontPx + besideW + fontPx + legendsW + fontPx <= s.width)
        return {double(fontPx), top, besideW, fullHeight, int(std::lround(fontPx + besideW + fontPx))};
    const double bottom = s.height - legendsHeightPx(s.width, s.height, slice::legendCount(s));
    return {double(fontPx), top, s.width - 2.0 * fontPx, bottom - top - 0.5 * fontPx};
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

// Every pixel's point (lat, lon in degrees; NaN off the sphere) of a map frame: the inverse
// projection of each pixel centre, the bulk of a map's cost. The same for every depth and step, so
// the last frames' are kept: dragging the depth (or playing the series) redraws without it.
struct MapPixelsKey {
    MapProjection projection;
    double centralMeridianDeg, centralLatitudeDeg, scale, cx, cy;
    int width, height;
    auto operator<=>(const MapPixelsKey&) const = default;
};
using MapPixelPoints = std::vector<std::array<float, 2>>;

std::shared_ptr<const MapPixelPoints> mapPixelPoints(const state::MapState& map, const MapFrame& frame, int width, int height)
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

MapFrame mapFrameOf(const state::RenderState& s)
{
    const MapLayout l = mapLayoutOf(s);
    // The picture's size in the message: the frame's own is what is left after titles and legends.
    if (!(l.width >= 8 && l.height >= 8))
        fail("map: a picture of {}x{} pixels has no room for the map; choose a larger size", s.width, s.height);
    return MapFrame(s.map, l.left, l.top, l.width, l.height);
}

MapFrame::MapFrame(const state::MapState& map, double left, double top, double width, double height)
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

namespace {

// The state's graticule and coastlines on the map.
void drawMapReference(std::vector<uint8_t>& pixels, int width, int height, const MapFrame& frame,
                      const state::ReferenceState& ref, const Coastlines* coastlines, double centralMeridianDeg)
{
    // A segment longer than this crosses the map's edge (the seam behind the central meridian).
    const double jumpPx = 0.25 * width;
    if (ref.graticule.visible && ref.graticule.opacity > 0) {
        LineLayer layer(width, height, false);
        const float step = ref.graticule.spacingDeg;
        const double lon0 = centralMeridianDeg;
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
        compositeLines(pixels, layer, ref.graticule.color, ref.graticule.opacity);
    }
    if (ref.coastlines.visible && ref.coastlines.opacity > 0) {
        if (!coastlines)
            fail("reference.coastlines: visible, but no coastlines were given");
        // Over a dark halo, so that the state's colour (chosen for the globe) reads on light colours too.
        LineLayer halo(width, height, false), layer(width, height, false);
        for (const auto& line : coastlines->lines) {
            drawMapPolyline(halo, frame, line, ref.lineWidthPx + 1.5f, jumpPx);
            drawMapPolyline(layer, frame, line, ref.lineWidthPx, jumpPx);
        }
        compositeLines(pixels, halo, {0, 0, 0}, 0.55f * ref.coastlines.opacity);
        compositeLines(pixels, layer, ref.coastlines.color, ref.coastlines.opacity);
    }
}

// The sphere's outline: along rays from the map's centre, the last point the projection inverts
// (bisection), joined in the picture's plane.
void drawSphereOutline(std::vector<uint8_t>& pixels, int width, int height, const MapFrame& frame, Rgb ink)
{
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
    compositeLines(pixels, layer, ink, 0.8f);
}

// Arrows of the horizontal flow on a regular grid of the picture (`spacing` pixels apart, between
// the rows `top` and `bottom`), their length the horizontal speed over the largest one among them.
std::vector<slice::Arrow> mapFlowArrows(const MapFrame& frame, const slice::PointProbe& probe, double rKm, int width,
                                        double top, double bottom, int spacing)
{
    std::vector<slice::Arrow> arrows;
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
    return arrows;
}

}  // namespace

ImageRgba8 mapPicture(const SliceInputs& in)
{
    using namespace slice;  // slice_sampling.h, slice_drawing.h
    const state::RenderState& state = stateOf(in);
    const RenderParams& params = in.resolved->params;
    const state::MapState& map = state.map;
    const int width = state.width, height = state.height;
    const grid::SphericalGrid& grid = in.volume->grid();
    const double rKm = radiusAtDepth(grid, map.depthKm, "map.depthKm");
    PointProbe probe(*in.volume, params, in.variableNames, map.flow, "map.flow");

    const int fontPx = legendFontPx(width, height);
    const MapLayout layout = mapLayoutOf(state);
    const double top = layout.top, bottom = layout.top + layout.height;
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

    // The graticule and the coastlines of the state's reference, the sphere's outline always.
    drawMapReference(image.pixels, width, height, frame, state.reference, in.coastlines, map.centralMeridianDeg);
    drawSphereOutline(image.pixels, width, height, frame, inkFor(state.background));
    drawContourLines(image.pixels, samples, map.contours);
    std::string flowText;
    if (map.flow) {
        const int spacing = arrowSpacingPx(width, height);
        const std::vector<Arrow> arrows = mapFlowArrows(frame, probe, rKm, width, top, bottom, spacing);
        flowText = drawArrows(image.pixels, width, height, arrows, spacing, "horizontal flow");
    }

    std::vector<LegendSpec> legends{{in.colorTitle, params.transfer, {}}};
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

    std::string where = fmt::format("{} centred on {}", state::mapProjectionTitle(map.projection), lonText(map.centralMeridianDeg));
    if (map.projection == MapProjection::Orthographic)
        where += ", " + latText(map.centralLatitudeDeg);
    const std::string title = fitTitle({fmt::format("{} at {:g} km depth", in.colorTitle, map.depthKm), in.when, where}, width, height);
    std::vector<TextLabel> labels{{title, width / 2.0f, 1.1f * fontPx, {1, 1, 1}}};
    addNotes(labels, width, height,
             {grey ? "hatched grey: outside the brushes" : "", flowText, pathlineText, regionNote(in.volume->grid())});
    drawTextLabels(image.pixels, width, height, labels);
    drawLegends(image.pixels, width, height, legends, {}, layout.legendsLeftPx);
    return image;
}

SliceGrid latLonSlice(const dataset::StepVolume& volume, size_t variable, double depthKm, double stepDeg, const std::string& what)
{
    const grid::SphericalGrid& grid = volume.grid();
    const double rKm = slice::radiusAtDepth(grid, depthKm, what);
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
    const grid::GridSampler sampler(grid);
    const float* values = volume.values(variable);
    tbb::parallel_for(size_t(0), nLat, [&](size_t i) {
        for (size_t j = 0; j < nLon; ++j)
            if (const auto at = sampler.locate(out.rows[i], out.columns[j], rKm))
                out.values[i * nLon + j] = float(sampler.sample(values, *at));
    });
    return out;
}

}  // namespace raypc::render
