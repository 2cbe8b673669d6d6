// Reference geometry against closed-form expectations: a thin shell's opacity seen face-on and at
// its silhouette, compositing by the volume's depth, graticule lines where the projection puts them
// and nowhere on the far side, and the coastline file's checks.
#include "render/reference_geometry.h"

#include "core/error.h"
#include "core/spherical.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fstream>

namespace raypc::render {
namespace {

constexpr int kSize = 101;  // odd: the centre pixel's ray passes through the planet's centre

OrbitCamera frontCamera()
{
    OrbitCamera c;
    c.azimuthDeg = 0;
    c.elevationDeg = 0;
    c.distanceKm = 30000;
    c.fovYDeg = 30;
    return c;
}

struct Image {
    std::vector<float> rgba = std::vector<float>(size_t(kSize) * kSize * 4, 0.0f);
    std::vector<float> depth = std::vector<float>(size_t(kSize) * kSize, INFINITY);
    float alpha(int x, int y) const { return rgba[(size_t(y) * kSize + size_t(x)) * 4 + 3]; }
};

state::ReferenceState shellsOnly(float depthKm, float opacity)
{
    state::ReferenceState r;
    r.shells.visible = true;
    r.shells.depthsKm = {depthKm};
    r.shells.opacity = opacity;
    return r;
}

TEST(ReferenceGeometry, ThinShellIsFaintFaceOnAndStrongAtItsSilhouette)
{
    Image im;
    drawReferenceGeometry(shellsOnly(660, 0.3f), frontCamera(), kSize, kSize, 6371, 3481, im.rgba, im.depth, nullptr);
    // The centre ray crosses the shell twice, face-on: 1 - (1 - 0.3)^2.
    EXPECT_NEAR(im.alpha(kSize / 2, kSize / 2), 1.0f - 0.7f * 0.7f, 0.01f);
    // Along the middle row alpha grows towards the silhouette, then drops to 0 outside the shell.
    const CameraFrame cam(frontCamera(), kSize, kSize);
    const float r = 6371 - 660;
    int silhouette = -1;
    for (int x = kSize / 2; x < kSize; ++x) {
        float t0, t1;
        if (!intersectSphere(cam.eye, cam.direction(float(x) + 0.5f, kSize / 2 + 0.5f), r, t0, t1)) {
            silhouette = x - 1;
            break;
        }
    }
    ASSERT_GT(silhouette, kSize / 2 + 5);
    EXPECT_GT(im.alpha(silhouette, kSize / 2), im.alpha(kSize / 2 + 3, kSize / 2) + 0.2f);
    EXPECT_EQ(im.alpha(silhouette + 2, kSize / 2), 0.0f);
}

TEST(ReferenceGeometry, ShellsAreCompositedByTheVolumesDepth)
{
    const CameraFrame cam(frontCamera(), kSize, kSize);
    const size_t centre = size_t(kSize / 2) * kSize + kSize / 2;
    const float frontT = float(cam.eye.x) - (6371 - 660);  // the eye is on +x
    for (bool volumeInFront : {true, false}) {
        Image im;
        // An opaque red volume at the centre pixel, in front of or behind the shell's near side.
        im.rgba[centre * 4] = 1.0f;
        im.rgba[centre * 4 + 3] = 1.0f;
        im.depth[centre] = volumeInFront ? frontT - 100 : frontT + 100;
        drawReferenceGeometry(shellsOnly(660, 0.5f), frontCamera(), kSize, kSize, 6371, 3481, im.rgba, im.depth, nullptr);
        const float* p = &im.rgba[centre * 4];
        if (volumeInFront) {
            EXPECT_FLOAT_EQ(p[0], 1.0f);  // the shell hides behind the opaque volume
            EXPECT_FLOAT_EQ(p[1], 0.0f);
        } else {
            // Shell (its palette colour, alpha 0.5) over the red volume.
            const Rgb c = shellColor(shellsOnly(660, 0.5f).shells, 0);
            EXPECT_NEAR(p[0], 0.5f * c.r + 0.5f, 1e-4f);
            EXPECT_NEAR(p[1], 0.5f * c.g, 1e-4f);
            EXPECT_NEAR(p[3], 1.0f, 1e-6f);
        }
    }
}

TEST(ReferenceGeometry, ShellsOutsideThePlanetsShellDrawNothing)
{
    Image im;
    state::ReferenceState r = shellsOnly(3000, 0.5f);  // radius 3371 km: inside the core (3481 km)
    drawReferenceGeometry(r, frontCamera(), kSize, kSize, 6371, 3481, im.rgba, im.depth, nullptr);
    for (float v : im.rgba)
        ASSERT_EQ(v, 0.0f);
}

// From the default camera the 410 and 660 km rings are only 4 % apart in radius, so each gets
// a colour of its own and its depth written on its ring, the labels apart.
TEST(ReferenceGeometry, ShellsHaveTheirOwnColoursAndTheirDepthsOnTheirRings)
{
    state::ReferenceState r;
    r.shells.visible = true;
    r.shells.depthsKm = {410, 660, 3000};  // 3000 km lies inside the core: no label, no key entry
    const Rgb a = shellColor(r.shells, 0), b = shellColor(r.shells, 1);
    EXPECT_GT(std::abs(a.r - b.r) + std::abs(a.g - b.g) + std::abs(a.b - b.b), 0.5f);
    const auto key = shellKey(r, 6371, 3481);
    ASSERT_EQ(key.size(), 2u);
    EXPECT_EQ(key[0].text, "410 km");
    EXPECT_EQ(key[1].text, "660 km");

    const int w = 800, h = 450;
    OrbitCamera cam = frontCamera();
    cam.distanceKm = framingDistanceKm(cam.fovYDeg, w, h, 6371, 0.94);
    const auto labels = shellLabels(r, cam, w, h, 6371, 3481);
    ASSERT_EQ(labels.size(), 2u);
    const CameraFrame frame(cam, w, h);
    float t0, t1;
    for (size_t k = 0; k < 2; ++k) {
        EXPECT_EQ(labels[k].text, key[k].text);
        // On the ring: the ray through the label grazes the shell (within two pixels).
        const float radius = 6371.0f - r.shells.depthsKm[k];
        const Vec3 outward{labels[k].x - w / 2.0f, labels[k].y - h / 2.0f, 0};
        const float len = std::sqrt(outward.x * outward.x + outward.y * outward.y);
        const float ox = labels[k].x + 2 * outward.x / len, oy = labels[k].y + 2 * outward.y / len;
        const float ix = labels[k].x - 2 * outward.x / len, iy = labels[k].y - 2 * outward.y / len;
        EXPECT_FALSE(intersectSphere(frame.eye, frame.direction(ox, oy), radius, t0, t1)) << k;
        EXPECT_TRUE(intersectSphere(frame.eye, frame.direction(ix, iy), radius, t0, t1)) << k;
    }
    // Staggered: the two labels' centres are more than a label's height apart.
    EXPECT_GT(std::hypot(labels[0].x - labels[1].x, labels[0].y - labels[1].y), 30.0f);
    // The framing (render::framingDistanceKm): the surface's silhouette lies 94 % of the height apart.
    const float edge = h / 2.0f - 0.94f * h / 2.0f;
    EXPECT_TRUE(intersectSphere(frame.eye, frame.direction(w / 2.0f, edge + 1), 6371, t0, t1));
    EXPECT_FALSE(intersectSphere(frame.eye, frame.direction(w / 2.0f, edge - 1), 6371, t0, t1));
}

TEST(ReferenceGeometry, GraticuleLinesLieWhereTheyProjectAndOnlyOnTheNearSide)
{
    state::ReferenceState r;
    r.graticule.visible = true;
    r.graticule.spacingDeg = 90;  // the equator, and meridians 0, 90, 180, 270
    r.graticule.opacity = 1;
    r.lineWidthPx = 2;
    Image im;
    drawReferenceGeometry(r, frontCamera(), kSize, kSize, 6371, 3481, im.rgba, im.depth, nullptr);
    // Seen from (lat 0, lon 0): the equator is the middle row, meridian 0 the middle column.
    EXPECT_GT(im.alpha(kSize / 2 + 10, kSize / 2), 0.5f);
    EXPECT_GT(im.alpha(kSize / 2, kSize / 2 - 10), 0.5f);
    // Between them nothing; meridian 180 (on the far side) is not drawn through the middle either.
    EXPECT_EQ(im.alpha(kSize / 2 + 10, kSize / 2 - 10), 0.0f);
    // Lines are hidden behind an opaque volume in front of the surface.
    Image hidden;
    for (size_t i = 0; i < hidden.depth.size(); ++i) {
        hidden.depth[i] = 1000;
        hidden.rgba[i * 4 + 3] = 1.0f;
    }
    drawReferenceGeometry(r, frontCamera(), kSize, kSize, 6371, 3481, hidden.rgba, hidden.depth, nullptr);
    EXPECT_EQ(hidden.rgba[(size_t(kSize / 2) * kSize + kSize / 2 + 10) * 4], 0.0f);
}

// The map's and the section's marks (state.map.showInView): seen from (0, 0), a section along the
// equator from 30°W to 30°E has its radial end lines at the projected end points and its arc across
// the middle row; the map's depth is a cyan shell; nothing is drawn without marks.
TEST(ReferenceGeometry, SliceMarksLieWhereTheSectionAndTheDepthAre)
{
    state::ReferenceState r;  // no shells, graticule or coastlines
    SliceMarks marks;
    marks.depthKm = 1000;
    marks.from = {0, -30};
    marks.to = {0, 30};
    Image none, im;
    drawReferenceGeometry(r, frontCamera(), kSize, kSize, 6371, 3481, none.rgba, none.depth, nullptr);
    EXPECT_EQ(*std::max_element(none.rgba.begin(), none.rgba.end()), 0.0f);
    drawReferenceGeometry(r, frontCamera(), kSize, kSize, 6371, 3481, im.rgba, im.depth, nullptr, &marks);
    const CameraFrame cam(frontCamera(), kSize, kSize);
    float x, y, t;
    auto at = [](double lat, double lon, double r) {
        const Vec3d p = sphericalToCartesianKm(lat, lon, r);
        return Vec3{float(p.x), float(p.y), float(p.z)};
    };
    // The end at 30°E, half way down: its radial line.
    ASSERT_TRUE(cam.project(at(0, 30, 5000), x, y, t));
    EXPECT_GT(im.alpha(int(x), int(y)), 0.5f) << "no radial line at the section's end (" << x << ", " << y << ")";
    const float* p = &im.rgba[(size_t(y) * kSize + size_t(x)) * 4];
    EXPECT_GT(p[2], p[0]) << "the mark is not cyan";
    // The arc at the surface crosses the middle row at lon 0; between the ends and off the
    // equator, only the faint depth shell.
    EXPECT_GT(im.alpha(kSize / 2, kSize / 2), 0.5f);
    ASSERT_TRUE(cam.project(at(20, 0, 6371), x, y, t));
    EXPECT_LT(im.alpha(int(x), int(y)), 0.3f);
    EXPECT_GT(im.alpha(int(x), int(y)), 0.0f) << "no depth shell";
}

// One layer, made once, composited over two different volume images (one empty, one opaque half
// way in with a depth in front of the shells on one side): each equals the geometry drawn afresh
// over that image, value for value.
TEST(ReferenceGeometry, OneLayerCompositesAsDrawingAfreshOverEveryVolume)
{
    state::ReferenceState r = shellsOnly(660, 0.4f);
    r.shells.depthsKm = {410, 660, 1600};
    r.graticule.visible = true;
    r.graticule.spacingDeg = 30;
    SliceMarks marks;
    marks.depthKm = 1000;
    marks.from = {10, -40};
    marks.to = {-5, 35};
    const ReferenceLayer layer(r, frontCamera(), kSize, kSize, 6371, 3481, nullptr, &marks);
    EXPECT_FALSE(layer.empty());
    EXPECT_GT(layer.bytes(), size_t(kSize) * kSize * sizeof(uint32_t));
    Image empty, volume;
    for (int y = 0; y < kSize; ++y)
        for (int x = 0; x < kSize / 2; ++x) {
            const size_t i = size_t(y) * kSize + size_t(x);
            volume.depth[i] = 24000;  // in front of the near side of the 410 km shell, behind the surface
            for (int c = 0; c < 4; ++c)
                volume.rgba[i * 4 + size_t(c)] = c == 3 ? 0.8f : 0.3f;
        }
    for (Image* im : {&empty, &volume}) {
        Image fresh = *im;
        drawReferenceGeometry(r, frontCamera(), kSize, kSize, 6371, 3481, fresh.rgba, fresh.depth, nullptr, &marks);
        layer.composite(im->rgba, im->depth);
        EXPECT_EQ(im->rgba, fresh.rgba);
    }
    EXPECT_NE(empty.rgba, volume.rgba);
    // An image of another size is refused, naming both.
    std::vector<float> small(16 * 4), smallDepth(16);
    EXPECT_THROW(layer.composite(small, smallDepth), Error);
    // Nothing to draw: an empty layer leaves the image as it was.
    const ReferenceLayer none(state::ReferenceState{}, frontCamera(), kSize, kSize, 6371, 3481, nullptr);
    EXPECT_TRUE(none.empty());
    Image kept = volume;
    none.composite(kept.rgba, kept.depth);
    EXPECT_EQ(kept.rgba, volume.rgba);
}

TEST(ReferenceGeometry, CoastlineFileIsCheckedAndDrawn)
{
    const auto dir = std::filesystem::temp_directory_path() / "raypc_coastlines_test";
    std::filesystem::create_directories(dir);
    auto write = [&](const std::string& name, const std::string& text) {
        std::ofstream(dir / name) << text;
        return dir / name;
    };
    // A square around (lat 0, lon 0), 20 degrees wide.
    const Coastlines c = readCoastlines(write("ok.json", R"({"source": "test", "lines": [[-10, -10, 10, -10, 10, 10, -10, 10, -10, -10]]})"));
    ASSERT_EQ(c.lines.size(), 1u);
    EXPECT_EQ(c.pointCount(), 5u);
    state::ReferenceState r;
    r.coastlines.visible = true;
    r.coastlines.opacity = 1;
    Image im;
    drawReferenceGeometry(r, frontCamera(), kSize, kSize, 6371, 3481, im.rgba, im.depth, &c);
    float drawn = 0;
    for (size_t i = 0; i < im.depth.size(); ++i)
        drawn += im.rgba[i * 4 + 3];
    EXPECT_GT(drawn, 20.0f);  // four sides of several pixels each
    EXPECT_EQ(im.alpha(kSize / 2, kSize / 2), 0.0f);  // the inside of the square stays empty

    auto errorOf = [&](const std::string& text) {
        try {
            readCoastlines(write("bad.json", text));
        } catch (const Error& e) {
            return std::string(e.what());
        }
        return std::string("no error");
    };
    EXPECT_NE(errorOf("not json").find("bad.json: not valid JSON"), std::string::npos);
    EXPECT_NE(errorOf(R"({"line": []})").find("expected an object with \"lines\""), std::string::npos);
    EXPECT_NE(errorOf(R"({"lines": [[1, 2, 3]]})").find("lines[0]: expected an even number"), std::string::npos);
    EXPECT_NE(errorOf(R"({"lines": [[0, 0, 10, 95]]})").find("lines[0]: point (10, 95)"), std::string::npos);
    r.coastlines.visible = true;
    EXPECT_THROW(drawReferenceGeometry(r, frontCamera(), kSize, kSize, 6371, 3481, im.rgba, im.depth, nullptr), Error);
    std::filesystem::remove_all(dir);
}

}  // namespace
}  // namespace raypc::render
