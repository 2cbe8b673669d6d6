// Maps and sections of analytic volumes: the picture's colours are the truth's at pixel centres
// (poles and the lon seam included), the brushes grey what they leave out, a section through a
// blob finds it at its distance and depth, and the exported grids hold the truth.
#include "render/slice_view.h"

#include "render/color_map.h"
#include "render/slice_drawing.h"
#include "state/color_maps.h"

#include "core/error.h"
#include "core/spherical.h"
#include "analysis/selection.h"
#include "render/test_volumes.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>

namespace raypc::render {
namespace {

using testing::makeGrid;
using testing::makeVolume;

// Smooth over the sphere, linear in r: the trilinear sampler's error is small and known in size.
double field(double latDeg, double rKm, double lonDeg)
{
    return std::cos(degToRad(latDeg)) * std::cos(degToRad(lonDeg)) + 0.5 * std::sin(degToRad(latDeg)) + 1e-4 * rKm;
}

ResolvedState stateFor(int width, int height)
{
    ResolvedState r;
    r.state.width = width;
    r.state.height = height;
    r.state.reference.shells.visible = false;
    r.state.reference.graticule.visible = false;
    r.state.reference.coastlines.visible = false;
    r.params.colorVariable = 0;
    r.params.transfer.colorMap = ColorMapId::Viridis;
    r.params.transfer.range = {-1.2f, 2.2f};
    return r;
}

std::array<float, 3> pixel(const ImageRgba8& image, int x, int y)
{
    const uint8_t* p = &image.pixels[(size_t(y) * size_t(image.width) + size_t(x)) * 4];
    return {p[0] / 255.0f, p[1] / 255.0f, p[2] / 255.0f};
}

float colourError(const std::array<float, 3>& a, Rgb b)
{
    return std::max({std::abs(a[0] - b.r), std::abs(a[1] - b.g), std::abs(a[2] - b.b)});
}

class Slices : public ::testing::Test {
protected:
    // 2° cells; the outermost rows at ±89°, so the poles lie in the caps the sampler blends.
    grid::SphericalGrid grid = makeGrid(90, 21, 180);
    std::shared_ptr<dataset::StepVolume> volume = makeVolume(grid, {{"f", field}});
    std::vector<std::string> names{"f"};
};

TEST_F(Slices, MapColoursAreTheTruthAtPixelCentresInEveryProjection)
{
    for (const MapProjection projection : state::allMapProjections()) {
        ResolvedState r = stateFor(720, 400);
        r.state.map.projection = projection;
        r.state.map.depthKm = 1000;
        r.state.map.centralMeridianDeg = projection == MapProjection::Orthographic ? 0.0f : 150.0f;
        r.state.map.centralLatitudeDeg = 60;  // the orthographic view looks at the north pole's side
        const SliceInputs in{volume.get(), &r, names, "f", "step 0", nullptr};
        const ImageRgba8 image = mapPicture(in);
        ASSERT_EQ(image.width, 720);
        const MapFrame frame = mapFrameOf(r.state);
        // Points over the whole sphere: near both poles, on both sides of the seam (0°/360°) and of
        // the map's own edge (the antimeridian of 150°E is -30°).
        int checked = 0;
        for (const double lat : {-88.9, -60.0, -20.0, 0.5, 33.0, 75.0, 88.9})
            for (const double lon : {-179.0, -31.0, -29.0, -0.5, 0.5, 90.0, 149.0, 179.0}) {
                const auto p = frame.pixelOf(lon, lat);
                if (!p)
                    continue;  // the far side of the orthographic globe
                const int x = int((*p)[0]), y = int((*p)[1]);
                const auto ll = frame.lonLatAt(x + 0.5, y + 0.5);
                if (!ll)
                    continue;  // a pixel whose centre lies just off the sphere's edge
                // The outline is drawn over the sphere's rim: only pixels a few pixels inside it count.
                bool inside = true;
                for (const auto& [dx, dy] : {std::pair{-3, 0}, {3, 0}, {0, -3}, {0, 3}})
                    inside = inside && frame.lonLatAt(x + 0.5 + dx, y + 0.5 + dy).has_value();
                if (!inside)
                    continue;
                const double truth = field((*ll)[1], kSurfaceRadiusKm - 1000, (*ll)[0]);
                // 2° cells: the sampler's error is below 3e-3 here (1e-2 in the pole caps), a colour
                // difference far below the 8-bit step (2/255) plus the map's slope.
                const float err = colourError(pixel(image, x, y), r.params.transfer.colorOf(float(truth)));
                EXPECT_LT(err, 0.025f) << state::mapProjectionName(projection) << " at " << lon << ", " << lat;
                ++checked;
            }
        EXPECT_GT(checked, projection == MapProjection::Orthographic ? 12 : 24) << state::mapProjectionName(projection);
        // Outside the sphere: the background.
        if (projection != MapProjection::Equirectangular) {
            const auto corner = pixel(image, 12, int(mapFrameOf(r.state).centrePx()[1] * 0.35));
            EXPECT_LT(std::max({corner[0], corner[1], corner[2]}), 0.05f) << state::mapProjectionName(projection);
        }
    }
}

TEST_F(Slices, BrushesGreyWhatTheyLeaveOut)
{
    ResolvedState r = stateFor(400, 240);
    r.state.map.projection = MapProjection::Equirectangular;
    r.params.brushes = {analysis::RangeFilter{-1, grid::Coordinate::Lat, {{0.0f, 90.0f}}}};  // the northern hemisphere
    const SliceInputs in{volume.get(), &r, names, "f", "step 0", nullptr};
    const ImageRgba8 image = mapPicture(in);
    const MapFrame frame = mapFrameOf(r.state);
    for (const double lon : {-120.0, 10.0, 100.0}) {
        const auto north = frame.pixelOf(lon, 40), south = frame.pixelOf(lon, -40);
        const auto n = pixel(image, int((*north)[0]), int((*north)[1]));
        const auto s = pixel(image, int((*south)[0]), int((*south)[1]));
        EXPECT_TRUE(s[0] == s[1] && s[1] == s[2]) << "the south at " << lon << " is not grey";
        EXPECT_FALSE(n[0] == n[1] && n[1] == n[2]) << "the north at " << lon << " is grey";
    }
    // "Not selected" is hatched and dark, unlike any colour map, so that a near-zero value is never
    // read as unselected: over a hatch period around a southern point the grey takes a dark and a
    // lighter value, all below a third of a diverging map's light neutral.
    const auto south = frame.pixelOf(10, -40);
    float darkest = 1, lightest = 0;
    for (int dy = 0; dy < slice::kUnselectedHatchPx; ++dy)
        for (int dx = 0; dx < slice::kUnselectedHatchPx; ++dx) {
            const auto p = pixel(image, int((*south)[0]) + dx, int((*south)[1]) + dy);
            EXPECT_TRUE(p[0] == p[1] && p[1] == p[2]);
            darkest = std::min(darkest, p[0]);
            lightest = std::max(lightest, p[0]);
        }
    EXPECT_LT(darkest, 0.31f);
    EXPECT_GT(lightest - darkest, 0.15f) << "no hatching";
    r.state.map.greyUnselected = false;
    const ImageRgba8 colour = mapPicture(in);
    const auto s = pixel(colour, int((*south)[0]), int((*south)[1]));
    EXPECT_FALSE(s[0] == s[1] && s[1] == s[2]) << "greyUnselected off still greys";
}

// Whatever the colour map and value, "not selected" is a hatched grey, darker on most pixels than
// a third of every diverging map's light neutral (what a stalled slab, v_r ≈ 0, is drawn in), and
// never lighter than 0.55 on the hatching.
TEST(NotSelected, NoColourMapDrawsIt)
{
    for (ColorMapId m : state::allColorMaps()) {
        const Rgb neutral = sampleColorMap(m, 0.5f);
        const float neutralLuma = 0.2126f * neutral.r + 0.7152f * neutral.g + 0.0722f * neutral.b;
        for (float u = 0; u <= 1.0f; u += 0.125f) {
            const Rgb c = sampleColorMap(m, u);
            const Rgb off = slice::unselectedColor(c, 1, 0), on = slice::unselectedColor(c, 0, 0);
            EXPECT_TRUE(off.r == off.g && off.g == off.b && on.r == on.g && on.g == on.b);
            EXPECT_GT(on.r - off.r, 0.15f) << state::colorMapName(m);
            EXPECT_LE(on.r, 0.55f);
            if (state::isDiverging(m)) {
                EXPECT_LT(off.r, neutralLuma / 3) << state::colorMapName(m) << " at " << u;
            }
        }
    }
}

// The reference shells' dashes in depth plots have a dark casing: the 660 km shell's yellow dash is
// seen over viridis's yellow, where a bare yellow dash vanished.
TEST(DepthMarks, StandOutFromTheMapBeneath)
{
    const int width = 200, height = 100;
    const Rgb yellow = sampleColorMap(ColorMapId::Viridis, 1);
    std::vector<uint8_t> rgba(size_t(width) * height * 4);
    for (size_t i = 0; i < rgba.size(); i += 4) {
        rgba[i] = uint8_t(yellow.r * 255), rgba[i + 1] = uint8_t(yellow.g * 255), rgba[i + 2] = uint8_t(yellow.b * 255);
        rgba[i + 3] = 255;
    }
    state::ReferenceState::Shells shells;
    shells.visible = true;
    shells.depthsKm = {410, 660};
    const slice::DepthPlot plot{10, 190, 10, 90, 2890};
    std::vector<TextLabel> labels;
    slice::drawDepthMarks(rgba, width, height, plot, shells, labels);
    ASSERT_EQ(labels.size(), 2u);
    // Within a few rows of the 660 km line some pixel is far darker than the yellow beneath.
    const int y = int(std::lround(plot.yOfDepth(660)));
    int darkest = 255;
    for (int yy = y - 3; yy <= y + 3; ++yy)
        for (int x = 20; x < 60; ++x)
            darkest = std::min(darkest, int(rgba[(size_t(yy) * width + x) * 4 + 1]));
    EXPECT_LT(darkest, 80) << "the 660 km line has no dark casing over viridis's yellow";
}

TEST_F(Slices, LatLonSliceIsTheTruthAtPolesAndSeam)
{
    const SliceGrid g = latLonSlice(*volume, 0, 660, 0.5);
    ASSERT_EQ(g.rows.size(), 360u);
    ASSERT_EQ(g.columns.size(), 720u);
    EXPECT_DOUBLE_EQ(g.rows.front(), -89.75);
    EXPECT_DOUBLE_EQ(g.columns.back(), 359.75);
    double worst = 0;
    for (size_t i = 0; i < g.rows.size(); ++i)
        for (size_t j = 0; j < g.columns.size(); ++j)
            worst = std::max(worst, std::abs(g.values[i * g.columns.size() + j] - field(g.rows[i], kSurfaceRadiusKm - 660, g.columns[j])));
    EXPECT_LT(worst, 1e-2);
    EXPECT_THROW(latLonSlice(*volume, 0, 3000, 1), Error);  // below the core-mantle boundary
    EXPECT_THROW(latLonSlice(*volume, 0, 660, 0.7), Error);  // does not divide 180
}

TEST_F(Slices, GreatCircleLengthsPointsAndRefusals)
{
    const GreatCircle c({0, 0}, {0, 90});
    EXPECT_NEAR(c.lengthDeg(), 90, 1e-9);
    EXPECT_NEAR(c.lengthKm(), 0.5 * M_PI * kSurfaceRadiusKm, 1e-6);
    const SphericalPoint mid = cartesianToSpherical(c.at(0.5));
    EXPECT_NEAR(mid.latDeg, 0, 1e-9);
    EXPECT_NEAR(mid.lonDeg, 45, 1e-9);
    // The shorter arc across the seam: from 170°E to 170°W passes 180°.
    const GreatCircle seam({10, 170}, {10, -170});
    EXPECT_NEAR(cartesianToSpherical(seam.at(0.5)).lonDeg, 180, 1e-6);
    EXPECT_LT(seam.lengthDeg(), 21);
    EXPECT_THROW(GreatCircle({10, 20}, {10, 20}), Error);
    EXPECT_THROW(GreatCircle({30, 20}, {-30, 200}), Error);  // antipodal
    // Over a pole.
    const GreatCircle pole({80, 0}, {80, 180});
    EXPECT_NEAR(cartesianToSpherical(pole.at(0.5)).latDeg, 90, 1e-6);
}

// A section given by its start, azimuth and length: the destination formula of spherical
// trigonometry, and the arc it makes leaves at that azimuth with that length.
TEST_F(Slices, SectionByAzimuthAndLength)
{
    // Due east along the equator, due north along a meridian, due south.
    auto near = [](state::SectionState::Point p, double lat, double lon) {
        EXPECT_NEAR(p.latDeg, lat, 1e-4);
        EXPECT_NEAR(p.lonDeg, lon, 1e-4);
    };
    near(GreatCircle::pointAlong({0, 0}, 90, 30), 0, 30);
    near(GreatCircle::pointAlong({0, 0}, 0, 30), 30, 0);
    near(GreatCircle::pointAlong({10, 20}, 180, 10), 0, 20);
    near(GreatCircle::pointAlong({0, 170}, 90, 20), 0, -170);  // across the date line
    for (const auto& [lat, lon, az, d] : {std::array{-40.0, 170.0, 45.0, 60.0}, {80.0, -10.0, 200.0, 50.0}, {5.0, 5.0, 300.0, 120.0}}) {
        // sin(lat2) = sin(lat1) cos(d) + cos(lat1) sin(d) cos(az)
        const state::SectionState::Point to = GreatCircle::pointAlong({float(lat), float(lon)}, az, d);
        const double r = M_PI / 180;
        EXPECT_NEAR(std::sin(to.latDeg * r), std::sin(lat * r) * std::cos(d * r) + std::cos(lat * r) * std::sin(d * r) * std::cos(az * r), 1e-6);
        const GreatCircle arc({float(lat), float(lon)}, to);
        EXPECT_NEAR(arc.lengthDeg(), d, 1e-4);
        EXPECT_NEAR(arc.azimuthDeg(), az, 1e-3);
    }
    // From a pole: the limit of a start approaching it along its meridian (north continues over
    // the pole, down the opposite meridian).
    EXPECT_NEAR(GreatCircle({90, 0}, {0, 180}).azimuthDeg(), 0, 1e-6);
    EXPECT_NEAR(GreatCircle({89.999f, 0}, {0, 180}).azimuthDeg(), 0, 1e-3);
    EXPECT_NEAR(GreatCircle({90, 0}, {0, 90}).azimuthDeg(), GreatCircle({89.999f, 0}, {0, 90}).azimuthDeg(), 0.01);
    near(GreatCircle::pointAlong({90, 0}, 90, 90), 0, 90);
}

// A blob at 30°E on the equator, 1000 km deep: the section from 0°E to 60°E meets it half way.
TEST(SectionOfABlob, CrossesItAtItsDistanceAndDepth)
{
    const grid::SphericalGrid grid = makeGrid(90, 41, 180);
    const Vec3d centre = sphericalToCartesianKm(0, 30, kSurfaceRadiusKm - 1000);
    const auto blob = [&](double lat, double r, double lon) {
        const Vec3d d = sphericalToCartesianKm(lat, lon, r) - centre;
        return float(std::exp(-dot(d, d) / (2 * 300.0 * 300.0)));
    };
    const auto volume = makeVolume(grid, {{"blob", blob}});
    state::SectionState section;
    section.from = {0, 0};
    section.to = {0, 60};
    const SectionGrid g = sectionGrid(*volume, 0, section, 121, 289);
    size_t best = 0;
    for (size_t i = 0; i < g.grid.values.size(); ++i)
        if (g.grid.values[i] > g.grid.values[best])
            best = i;
    const double distanceKm = g.grid.columns[best % 121], depthKm = g.grid.rows[best / 121];
    EXPECT_NEAR(distanceKm, degToRad(30) * kSurfaceRadiusKm, 60) << "distance of the blob's peak";
    EXPECT_NEAR(depthKm, 1000, 40) << "depth of the blob's peak";
    EXPECT_NEAR(g.latDeg[60], 0, 1e-9);
    EXPECT_NEAR(g.lonDeg[60], 30, 1e-9);
    EXPECT_NEAR(g.grid.rows.back(), kSurfaceRadiusKm - grid.rKm.front(), 1e-9);

    // The picture: the blob's colour at its place, the background colour far from it.
    ResolvedState r = stateFor(800, 500);
    r.state.section = section;
    r.params.transfer.range = {0, 1};
    const std::vector<std::string> names{"blob"};
    const SliceInputs in{volume.get(), &r, names, "blob", "step 0", nullptr};
    const ImageRgba8 image = sectionPicture(in);
    if (const char* out = std::getenv("RAYPC_TEST_PICTURES"))
        writePng(std::string(out) + "/section_blob.png", image);
    const SectionLayout l = sectionLayoutOf(r.state, grid);
    const int x = int(l.left + 0.5 * (l.right - l.left)), y = int(l.top + 1000 / l.depthSpanKm * (l.bottom - l.top));
    // There the picture shows what the grid export holds (the blob's peak, as 2° cells sample it).
    const float peak = g.grid.values[size_t(std::lround(1000 / (g.grid.rows[1] - g.grid.rows[0]))) * 121 + 60];
    EXPECT_GT(peak, 0.5f);
    EXPECT_LT(colourError(pixel(image, x, y), r.params.transfer.colorOf(peak)), 0.03f);
    const int x0 = int(l.left + 0.05 * (l.right - l.left));
    EXPECT_LT(colourError(pixel(image, x0, y), r.params.transfer.colorOf(0.0f)), 0.03f);
    r.state.section.to = {0, 180};
    EXPECT_THROW(sectionPicture(in), Error);  // antipodal ends
}

TEST(MapFlow, NeedsTheVelocity)
{
    const grid::SphericalGrid grid = makeGrid(18, 5, 36);
    const auto volume = makeVolume(grid, {{"f", field}});
    ResolvedState r = stateFor(200, 120);
    r.state.map.flow = true;
    const std::vector<std::string> names{"f"};
    const SliceInputs in{volume.get(), &r, names, "f", "step 0", nullptr};
    try {
        mapPicture(in);
        FAIL() << "a flow without vx, vy, vz was drawn";
    } catch (const Error& e) {
        EXPECT_NE(std::string(e.what()).find("map.flow"), std::string::npos) << e.what();
    }
}

// Pathlines on maps and sections: a line along the equator at 660 km depth is drawn in its age
// colours on the map of that depth and on a section in its plane, and not on a section 10° away;
// a line 2000 km deep shows only faintly on the map at 660 km.
TEST_F(Slices, PathlinesOnMapsAndSections)
{
    analysis::PathlineSet set;
    set.endStep = 1;
    set.offsets = {0};
    auto addLine = [&](auto pointAt) {
        for (int k = 0; k <= 40; ++k) {
            const auto [lat, lon, depth] = pointAt(k);
            const Vec3d p = sphericalToCartesianKm(lat, lon, kSurfaceRadiusKm - depth);
            set.points.insert(set.points.end(), {float(p.x), float(p.y), float(p.z), float(0.25 * k)});  // 10 Myr in all
        }
        set.offsets.push_back(uint32_t(set.pointCount()));
    };
    addLine([](int k) { return std::array{0.0, double(k), 660.0}; });         // the equator, 0 to 40°E
    addLine([](int k) { return std::array{double(k) - 20, 100.0, 2000.0}; });  // 100°E, 20°S to 20°N, deep
    const PathlineLines lines(std::make_shared<const std::vector<analysis::PathlineSet>>(std::vector{set}));

    ResolvedState r = stateFor(900, 520);
    r.state.pathlines.visible = true;
    r.state.pathlines.window = 1;
    r.state.map.projection = MapProjection::Equirectangular;
    r.state.map.depthKm = 660;
    SliceInputs in{volume.get(), &r, names, "f", "step 0", nullptr, &lines};
    const PathlineStyle style = lines.styleFor(r.state.pathlines);
    auto lineColour = [&](double ageMyr) {
        return sampleColorMap(style.colorMap, float((ageMyr - style.range.min) / (style.range.max - style.range.min)));
    };
    auto fieldColour = [&](double lat, double lon, double depth) {
        return r.params.transfer.colorAt(r.params.transfer.colorPositionOf(float(field(lat, kSurfaceRadiusKm - depth, lon))));
    };

    // The line is 2 pixels wide: the pixel nearest its centre within one of a point.
    auto nearest = [](const ImageRgba8& image, double px, double py, Rgb colour) {
        float best = 1;
        for (int dy = -1; dy <= 1; ++dy)
            for (int dx = -1; dx <= 1; ++dx)
                best = std::min(best, colourError(pixel(image, int(px) + dx, int(py) + dy), colour));
        return best;
    };
    const ImageRgba8 map = mapPicture(in);
    const MapFrame frame = mapFrameOf(r.state);
    const auto onLine = *frame.pixelOf(20.5, 0);  // between points 20 and 21: age 5 Myr
    EXPECT_LT(nearest(map, onLine[0], onLine[1], lineColour(5.0)), 0.04);
    const auto deep = *frame.pixelOf(100, 0.5);
    const auto deepPixel = pixel(map, int(deep[0]), int(deep[1]));
    EXPECT_LT(colourError(deepPixel, fieldColour(0.5, 100, 660)), colourError(deepPixel, lineColour(5.1)));
    EXPECT_LT(colourError(deepPixel, fieldColour(0.5, 100, 660)), 0.25);  // at most faint

    r.state.section.from = {0, -10};
    r.state.section.to = {0, 60};
    const ImageRgba8 inPlane = sectionPicture(in);
    const SectionLayout l = sectionLayoutOf(r.state, grid);
    const double x = l.left + (20.5 + 10) / 70 * (l.right - l.left), y = l.top + 660 / l.depthSpanKm * (l.bottom - l.top);
    EXPECT_LT(nearest(inPlane, x, y, lineColour(5.0)), 0.04);
    r.state.section.from = {10, -10};
    r.state.section.to = {10, 60};
    const ImageRgba8 away = sectionPicture(in);
    EXPECT_GT(nearest(away, x, y, lineColour(5.0)), 0.2);

    // Shown but not given: one error.
    in.pathlines = nullptr;
    EXPECT_THROW(mapPicture(in), Error);
}

}  // namespace
}  // namespace raypc::render
