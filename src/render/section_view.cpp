// Great-circle cross-sections (slice_view.h): the arc (GreatCircle), where the picture puts it
// (sectionLayoutOf), the picture (sectionPicture) and the grid exported as CF netCDF (sectionGrid).
#include "render/slice_view.h"

#include "core/error.h"
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

namespace raypc::render {

SectionLayout sectionLayoutOf(const state::RenderState& s, const grid::SphericalGrid& grid)
{
    const int fontPx = legendFontPx(s.width, s.height);
    // Depth labels at the left, the shells' names at the right, the title above, distance labels
    // and the legend below.
    SectionLayout l{5.5 * fontPx, s.width - 4.5 * fontPx, 2.4 * fontPx,
                    s.height - legendsHeightPx(s.width, s.height, slice::legendCount(s)) - 2.2 * fontPx,
                    slice::depthRangeKm(grid).second};
    if (!(l.right - l.left >= 8 && l.bottom - l.top >= 8))
        fail("section: a picture of {}x{} pixels has no room for the section; choose a larger size", s.width, s.height);
    return l;
}

GreatCircle::GreatCircle(state::SectionState::Point from, state::SectionState::Point to, const std::string& what)
{
    using namespace slice;  // slice_sampling.h, slice_drawing.h
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

state::SectionState::Point GreatCircle::pointAlong(state::SectionState::Point from, double azimuthDeg, double distanceDeg)
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

// Where a pixel of the section's picture lies: along the great circle left to right, from the
// surface down to the core-mantle boundary top to bottom.
struct SectionPlane {
    const GreatCircle& circle;
    const grid::SphericalGrid& grid;
    double left, right, top, bottom, depthSpanKm;

    // (lat, lon, r) of the pixel position (x, y); nullopt outside the plot or below the grid.
    std::optional<std::array<double, 3>> pointAt(double x, double y) const
    {
        if (x < left || x > right || y < top || y > bottom)
            return std::nullopt;
        const double f = (x - left) / (right - left), depth = (y - top) / (bottom - top) * depthSpanKm;
        const double r = kSurfaceRadiusKm - depth;
        if (r < grid.rKm.front() - 1e-6)
            return std::nullopt;
        const SphericalPoint p = cartesianToSpherical(circle.at(f));
        return std::array{p.latDeg, p.lonDeg, std::clamp(r, grid.rKm.front(), grid.rKm.back())};
    }
};

// The colour variable at every pixel: every column's point on the arc and every row's radius
// located once.
slice::PixelSamples sampleSection(const SectionPlane& plane, const slice::PointProbe& probe, int width, int height)
{
    using slice::PointProbe;
    const grid::GridSampler& sampler = probe.sampler();
    struct Column {
        double latDeg, lonDeg;
        grid::GridSampler::LateralPart where;
    };
    std::vector<std::optional<Column>> columns(static_cast<size_t>(width));
    for (int x = 0; x < width; ++x)
        if (const auto p = plane.pointAt(x + 0.5, plane.top))
            if (const auto where = sampler.locateLatLon((*p)[0], (*p)[1]))
                columns[size_t(x)] = Column{(*p)[0], (*p)[1], *where};
    std::vector<std::optional<std::pair<double, grid::GridSampler::RadialPart>>> rows(static_cast<size_t>(height));
    for (int y = 0; y < height; ++y)
        if (const auto p = plane.pointAt(0.5 * (plane.left + plane.right), y + 0.5))
            if (const auto where = sampler.locateRadius((*p)[2]))
                rows[size_t(y)] = {(*p)[2], *where};
    return slice::samplePixels(width, height, [&](int x, int y) -> std::optional<PointProbe::Sample> {
        const auto& column = columns[size_t(x)];
        const auto& row = rows[size_t(y)];
        if (!column || !row)
            return std::nullopt;
        return probe.at(grid::GridSampler::combine(column->where, row->second), column->latDeg, column->lonDeg, row->first);
    });
}

// Arrows of the flow in the section's plane on a regular grid of the picture (`spacing` pixels
// apart): along the profile to the right, radial up, each axis at its own km per pixel (the
// section is not drawn at true scale).
std::vector<slice::Arrow> sectionFlowArrows(const SectionPlane& plane, const slice::PointProbe& probe, int spacing)
{
    std::vector<slice::Arrow> arrows;
    const double kmPerPxX = plane.circle.lengthKm() / (plane.right - plane.left);
    const double kmPerPxY = plane.depthSpanKm / (plane.bottom - plane.top);
    for (double y = plane.top + spacing / 2.0; y < plane.bottom; y += spacing)
        for (double x = plane.left + spacing / 2.0; x < plane.right; x += spacing) {
            const auto p = plane.pointAt(x, y);
            if (!p)
                continue;
            const auto v = probe.velocityCmPerYr((*p)[0], (*p)[1], (*p)[2]);
            if (!v)
                continue;
            const double f = (x - plane.left) / (plane.right - plane.left);
            const double along = dot(*v, plane.circle.tangentAt(f)), radial = dot(*v, plane.circle.at(f));
            const double sx = along / kmPerPxX, sy = -radial / kmPerPxY, sl = std::hypot(sx, sy);
            const double speed = std::hypot(along, radial);
            if (!(sl > 0))
                continue;
            arrows.push_back({float(x), float(y), float(sx / sl), float(sy / sl), speed});
        }
    return arrows;
}

}  // namespace

ImageRgba8 sectionPicture(const SliceInputs& in)
{
    using namespace slice;  // slice_sampling.h, slice_drawing.h
    const state::RenderState& state = stateOf(in);
    const RenderParams& params = in.resolved->params;
    const state::SectionState& section = state.section;
    const int width = state.width, height = state.height;
    const grid::SphericalGrid& grid = in.volume->grid();
    const GreatCircle circle(section.from, section.to);
    const PointProbe probe(*in.volume, params, in.variableNames, section.flow, "section.flow");

    const int fontPx = legendFontPx(width, height);
    // Plain variables, not a structured binding: the lambdas below capture them (clang 14 cannot
    // capture bindings).
    const SectionLayout layout = sectionLayoutOf(state, grid);
    const double left = layout.left, right = layout.right;
    const SectionPlane plane{circle, grid, left, right, layout.top, layout.bottom, layout.depthSpanKm};
    const PixelSamples samples = sampleSection(plane, probe, width, height);
    const bool grey = state.map.greyUnselected && !params.brushes.empty();
    ImageRgba8 image{width, height, colorPixels(samples, params.transfer, state.background, grey)};
    const Rgb ink = inkFor(state.background);
    const DepthPlot plot{left, right, layout.top, layout.bottom, layout.depthSpanKm};
    auto xOfFraction = [&](double f) { return float(left + f * (right - left)); };

    drawContourLines(image.pixels, samples, state.map.contours);
    std::vector<TextLabel> labels;
    drawDepthMarks(image.pixels, width, height, plot, state.reference.shells, labels);
    std::string flowText;
    if (section.flow) {
        const int spacing = arrowSpacingPx(width, height);
        flowText = drawArrows(image.pixels, width, height, sectionFlowArrows(plane, probe, spacing), spacing,
                              "flow in the section's plane (directions on the picture's axes)");
    }
    std::vector<LegendSpec> legends{{in.colorTitle, params.transfer, {}}};
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
    addNotes(labels, width, height,
             {grey ? "hatched grey: outside the brushes" : "", flowText, pathlineText, regionNote(in.volume->grid())});
    drawTextLabels(image.pixels, width, height, labels);
    drawLegends(image.pixels, width, height, legends);
    return image;
}

SectionGrid sectionGrid(const dataset::StepVolume& volume, size_t variable, const state::SectionState& section, int columns, int rows)
{
    if (columns < 2 || rows < 2)
        fail("section: a grid of {} x {} points; expected at least 2 x 2", columns, rows);
    const grid::SphericalGrid& grid = volume.grid();
    const GreatCircle circle(section.from, section.to);
    const double bottom = slice::depthRangeKm(grid).second;
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
    const grid::GridSampler sampler(grid);
    const float* values = volume.values(variable);
    tbb::parallel_for(0, rows, [&](int i) {
        const double r = std::clamp(kSurfaceRadiusKm - out.grid.rows[size_t(i)], grid.rKm.front(), grid.rKm.back());
        for (int j = 0; j < columns; ++j)
            if (const auto at = sampler.locate(out.latDeg[size_t(j)], out.lonDeg[size_t(j)], r))
                out.grid.values[size_t(i) * size_t(columns) + size_t(j)] = float(sampler.sample(values, *at));
    });
    return out;
}

}  // namespace raypc::render
