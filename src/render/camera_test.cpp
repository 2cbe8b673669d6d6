#include "render/camera.h"

#include "core/error.h"

#include <gtest/gtest.h>

namespace raypc::render {
namespace {

TEST(Shell, RayThroughCentreStopsAtCoreOrPassesThrough)
{
    const Vec3 o{20000, 0, 0}, d{-1, 0, 0};
    ShellSegments s = intersectShell(o, d, 3485, 6371, false);
    ASSERT_EQ(s.count, 1);
    EXPECT_NEAR(s.t0[0], 20000 - 6371, 1e-2);
    EXPECT_NEAR(s.t1[0], 20000 - 3485, 1e-2);
    EXPECT_NEAR(s.coreT, 20000 - 3485, 1e-2);
    s = intersectShell(o, d, 3485, 6371, true);
    ASSERT_EQ(s.count, 2);
    EXPECT_NEAR(s.t0[1], 20000 + 3485, 1e-2);
    EXPECT_NEAR(s.t1[1], 20000 + 6371, 1e-2);
}

TEST(Shell, ChordLengthsMatchGeometry)
{
    // A ray at impact parameter b: shell chord 2 sqrt(R² - b²) minus the core chord 2 sqrt(rc² - b²).
    for (float b : {0.0f, 1000.0f, 3400.0f, 3600.0f, 6000.0f, 6370.0f}) {
        const Vec3 o{-30000, b, 0}, d{1, 0, 0};
        const ShellSegments s = intersectShell(o, d, 3485, 6371, true);
        float chord = 0;
        for (int i = 0; i < s.count; ++i)
            chord += s.t1[i] - s.t0[i];
        const float expected =
            2 * std::sqrt(6371.0f * 6371 - b * b) - (b < 3485 ? 2 * std::sqrt(3485.0f * 3485 - b * b) : 0.0f);
        EXPECT_NEAR(chord, expected, 0.05f) << "b=" << b;
        EXPECT_EQ(s.coreT >= 0, b < 3485) << "b=" << b;
    }
    float t0, t1;
    EXPECT_FALSE(intersectSphere({-30000, 6400, 0}, {1, 0, 0}, 6371, t0, t1));
}

TEST(Shell, EyeInsideTheShellStartsAtZero)
{
    const ShellSegments s = intersectShell({5000, 0, 0}, {0, 1, 0}, 3485, 6371, false);
    ASSERT_EQ(s.count, 1);
    EXPECT_EQ(s.t0[0], 0.0f);
    EXPECT_NEAR(s.t1[0], std::sqrt(6371.0f * 6371 - 5000.0f * 5000), 0.05f);
}

TEST(Camera, CentrePixelLooksAtTargetAndUpIsNorth)
{
    OrbitCamera c;
    c.azimuthDeg = 90;
    c.elevationDeg = 0;
    c.distanceKm = 10000;
    const CameraFrame f(c, 101, 101);
    EXPECT_NEAR(f.eye.y, 10000, 1e-2);
    const Vec3 d = f.direction(50.5f, 50.5f);
    EXPECT_NEAR(d.y, -1, 1e-6);
    EXPECT_GT(f.direction(50.5f, 0.0f).z, 0.1f);  // top of the image is north
    c.distanceKm = -1;
    EXPECT_THROW(c.validate(), Error);
}

}  // namespace
}  // namespace raypc::render
