// Stereo pairs: the state's "stereo" object, the eyes' cameras against the parallax geometry
// predicts, and the composition of two pictures. The rendered pairs are checked end to end in
// tests/render_cli (stereo_check.cpp).
#include "render/stereo.h"

#include "core/error.h"
#include "render/camera.h"
#include "state/render_state.h"
#include "state/test_states.h"

#include <gtest/gtest.h>

#include <cmath>

namespace raypc::render {
namespace {

using nlohmann::json;
using state::testing::refusalOf;

TEST(StereoState, RoundTripsAndDefaultsOff)
{
    const state::RenderState d;
    EXPECT_EQ(d.stereo.mode, StereoMode::Off);
    EXPECT_EQ(toJson(d)["stereo"], json::parse(R"({"mode": "off", "eyeSeparationKm": 600, "convergenceKm": null})"));
    for (StereoMode mode : state::allStereoModes()) {
        state::RenderState s;
        s.stereo.mode = mode;
        s.stereo.eyeSeparationKm = 321.5f;
        s.stereo.convergenceKm = 18000.0f;
        const state::RenderState t = state::parseRenderState(toJson(s));
        EXPECT_EQ(t.stereo.mode, mode);
        EXPECT_EQ(t.stereo.eyeSeparationKm, 321.5f);
        ASSERT_TRUE(t.stereo.convergenceKm.has_value());
        EXPECT_EQ(*t.stereo.convergenceKm, 18000.0f);
        EXPECT_EQ(toJson(t), toJson(s));
    }
    // null convergence: the camera's distance.
    json j = toJson(state::RenderState{});
    j["stereo"] = {{"mode", "anaglyph"}};
    const state::RenderState a = state::parseRenderState(j);
    EXPECT_EQ(a.stereo.mode, StereoMode::Anaglyph);
    EXPECT_FALSE(a.stereo.convergenceKm.has_value());
    EXPECT_EQ(a.stereo.convergenceOr(a.camera.distanceKm), a.camera.distanceKm);
}

TEST(StereoState, BadValuesAndOlderDocumentsAreRefusedByName)
{
    json j = toJson(state::RenderState{});
    j["stereo"]["mode"] = "top-bottom";
    EXPECT_NE(refusalOf(j).find("stereo.mode: stereo mode 'top-bottom' is unknown, expected one of: off, side-by-side, "
                              "side-by-side-half, anaglyph"),
              std::string::npos)
        << refusalOf(j);
    j = toJson(state::RenderState{});
    j["stereo"]["eyeSeparationKm"] = -1;
    EXPECT_NE(refusalOf(j).find("stereo.eyeSeparationKm: expected a number in [0, 1000000], found -1"), std::string::npos)
        << refusalOf(j);
    j = toJson(state::RenderState{});
    j["stereo"]["convergenceKm"] = 0;
    EXPECT_NE(refusalOf(j).find("stereo.convergenceKm"), std::string::npos) << refusalOf(j);
    j = toJson(state::RenderState{});
    j["stereo"]["parallax"] = 1;
    EXPECT_NE(refusalOf(j).find("stereo.parallax: unknown key"), std::string::npos) << refusalOf(j);
    j = toJson(state::RenderState{});
    j["version"] = 4;
    j["shading"].erase("shadows");  // version 6 to 10 keys, refused first otherwise
    j["shading"].erase("shadowStrength");
    j.erase("convergenceGreyLevels");
    j["camera"].erase("views");
    j.erase("selection");
    j.erase("map");
    j.erase("section");
    j.erase("features");
    j.erase("pair");  // version 13
    EXPECT_NE(refusalOf(j).find("stereo: needs version 5, the document says version 4"), std::string::npos) << refusalOf(j);
    j.erase("stereo");
    EXPECT_EQ(state::parseRenderState(j).stereo.mode, StereoMode::Off);  // a version-4 document still reads
}

// A point at depth z along the view axis is seen by the two eyes with the horizontal screen
// parallax separation (1/convergence - 1/z) (tangent units): zero on the convergence plane,
// the eyes' axes parallel (no vertical parallax anywhere, unlike toe-in).
TEST(StereoCamera, ParallaxFollowsSeparationAndConvergence)
{
    OrbitCamera c;
    c.azimuthDeg = 40;
    c.elevationDeg = 25;
    c.distanceKm = 20000;
    c.fovYDeg = 40;
    const int w = 400, h = 300;
    const CameraFrame mono(c, w, h);
    const double separationKm = 800, convergenceKm = 15000;
    const CameraFrame left(stereoEye(c, Eye::Left, separationKm, convergenceKm), w, h);
    const CameraFrame right(stereoEye(c, Eye::Right, separationKm, convergenceKm), w, h);
    EXPECT_NEAR(length(right.eye - left.eye), separationKm, 1e-2);
    EXPECT_NEAR(dot(right.eye - left.eye, mono.right), separationKm, 1e-2);
    EXPECT_NEAR(dot(left.forward, mono.forward), 1.0, 1e-7);  // parallel axes
    const double pixelsPerTangent = w / (2.0 * mono.tanHalfFovY * mono.aspect);
    for (double z : {7000.0, 15000.0, 20000.0, 60000.0}) {
        for (Vec3 side : {Vec3{0, 0, 0}, mono.right * 3000.0f + mono.up * 2000.0f, mono.up * -4000.0f}) {
            const Vec3 p = mono.eye + mono.forward * float(z) + side;
            float lx, ly, rx, ry, ld, rd;
            ASSERT_TRUE(left.project(p, lx, ly, ld));
            ASSERT_TRUE(right.project(p, rx, ry, rd));
            const double expected = separationKm * (1 / convergenceKm - 1 / z) * pixelsPerTangent;
            EXPECT_NEAR(rx - lx, expected, 2e-3 * std::max(1.0, std::abs(expected))) << "z=" << z;
            EXPECT_NEAR(ry, ly, 1e-2) << "z=" << z;
            // direction() is project()'s inverse.
            const Vec3 d = left.direction(lx, ly);
            EXPECT_NEAR(dot(d, normalize(p - left.eye)), 1.0, 1e-6);
        }
    }
    // The target, at the convergence distance, is at the image centre in both eyes.
    const CameraFrame l2(stereoEye(c, Eye::Left, separationKm, c.distanceKm), w, h);
    float x, y, dist;
    ASSERT_TRUE(l2.project(c.targetKm, x, y, dist));
    EXPECT_NEAR(x, w / 2.0, 1e-2);
    EXPECT_NEAR(y, h / 2.0, 1e-2);
    EXPECT_THROW(stereoEye(c, Eye::Left, -1, 1000), Error);
    EXPECT_THROW(stereoEye(c, Eye::Left, 100, 0), Error);
}

TEST(StereoCamera, SqueezedPixelsKeepTheFieldOfView)
{
    OrbitCamera c;
    c.pixelAspect = 2;
    const CameraFrame squeezed(c, 100, 200);
    c.pixelAspect = 1;
    const CameraFrame full(c, 200, 200);
    for (float u : {0.0f, 0.3f, 1.0f}) {
        const Vec3 a = squeezed.direction(u * 100, 70), b = full.direction(u * 200, 70);
        EXPECT_NEAR(dot(a, b), 1.0, 1e-6);
    }
}

TEST(StereoCompose, LayoutsPlaceTheEyes)
{
    EXPECT_EQ(stereoLayout(StereoMode::SideBySide, 30, 20).width, 60);
    const StereoLayout half = stereoLayout(StereoMode::SideBySideHalf, 30, 20);
    EXPECT_EQ(half.eyeWidth, 15);
    EXPECT_EQ(half.width, 30);
    EXPECT_DOUBLE_EQ(half.pixelAspect, 2.0);
    EXPECT_EQ(stereoLayout(StereoMode::SideBySideHalf, 31, 20).width, 30);
    EXPECT_EQ(stereoLayout(StereoMode::Anaglyph, 30, 20).width, 30);
    EXPECT_EQ(stereoLayout(StereoMode::Off, 30, 20).eyes, 1);

    const StereoLayout l = stereoLayout(StereoMode::SideBySide, 3, 2);
    std::vector<uint8_t> left(3 * 2 * 4), right(3 * 2 * 4);
    for (size_t i = 0; i < left.size(); ++i) {
        left[i] = uint8_t(i);
        right[i] = uint8_t(100 + i);
    }
    const auto sbs = composeStereo(StereoMode::SideBySide, l, left, right);
    ASSERT_EQ(sbs.size(), 6u * 2 * 4);
    // Row 1, column 4 (the right eye's column 1).
    EXPECT_EQ(sbs[(1 * 6 + 4) * 4 + 2], right[(1 * 3 + 1) * 4 + 2]);
    EXPECT_EQ(sbs[(1 * 6 + 1) * 4 + 0], left[(1 * 3 + 1) * 4 + 0]);
}

TEST(StereoCompose, AnaglyphRedIsTheLeftLumaGreenAndBlueTheRight)
{
    const StereoLayout l = stereoLayout(StereoMode::Anaglyph, 2, 1);
    // Left: pure blue then white; right: pure red then grey.
    const std::vector<uint8_t> left{0, 0, 255, 255, 255, 255, 255, 255};
    const std::vector<uint8_t> right{255, 0, 0, 255, 90, 91, 92, 255};
    const auto a = composeStereo(StereoMode::Anaglyph, l, left, right);
    EXPECT_EQ(a[0], 29);   // 0.114 x 255: blue still reaches the left eye
    EXPECT_EQ(a[1], 0);    // the right eye's red object is dark through the cyan filter
    EXPECT_EQ(a[2], 0);
    EXPECT_EQ(a[4], 255);
    EXPECT_EQ(a[5], 91);
    EXPECT_EQ(a[6], 92);
    EXPECT_EQ(a[7], 255);
}

}  // namespace
}  // namespace raypc::render
