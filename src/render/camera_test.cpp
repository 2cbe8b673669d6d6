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

// ---- Explicit views (camera.views, WebXR eyes) ----------------------------------------------------

// The unit quaternion [x, y, z, w] of the rotation whose matrix has columns a, b, c (Shepperd's
// method; independent of CameraFrame's quaternion-to-matrix formula).
std::array<float, 4> quaternionOfColumns(Vec3 a, Vec3 b, Vec3 c)
{
    const double m00 = a.x, m10 = a.y, m20 = a.z, m01 = b.x, m11 = b.y, m21 = b.z, m02 = c.x, m12 = c.y, m22 = c.z;
    const double trace = m00 + m11 + m22;
    double x, y, z, w;
    if (trace > 0) {
        const double s = 2 * std::sqrt(1 + trace);
        w = s / 4, x = (m21 - m12) / s, y = (m02 - m20) / s, z = (m10 - m01) / s;
    } else if (m00 > m11 && m00 > m22) {
        const double s = 2 * std::sqrt(1 + m00 - m11 - m22);
        w = (m21 - m12) / s, x = s / 4, y = (m01 + m10) / s, z = (m02 + m20) / s;
    } else if (m11 > m22) {
        const double s = 2 * std::sqrt(1 + m11 - m00 - m22);
        w = (m02 - m20) / s, x = (m01 + m10) / s, y = s / 4, z = (m12 + m21) / s;
    } else {
        const double s = 2 * std::sqrt(1 + m22 - m00 - m11);
        w = (m10 - m01) / s, x = (m02 + m20) / s, y = (m12 + m21) / s, z = s / 4;
    }
    return {float(x), float(y), float(z), float(w)};
}

// The view of an orbit camera's frame: camera +x = right, +y = up, -z = forward.
CameraView viewOf(const CameraFrame& f)
{
    CameraView v;
    v.positionKm = f.eye;
    v.orientation = quaternionOfColumns(f.right, f.up, f.forward * -1.0f);
    const float tx = f.tanHalfFovY * f.aspect;
    v.frustum = {f.shiftX - tx, f.shiftX + tx, -f.tanHalfFovY, f.tanHalfFovY};
    return v;
}

TEST(CameraView, ViewOfAnOrbitFrameGivesTheSameRays)
{
    OrbitCamera orbit;
    orbit.azimuthDeg = 35;
    orbit.elevationDeg = 25;
    orbit.distanceKm = 18500;
    orbit.fovYDeg = 45;
    orbit.targetKm = {300, -200, 100};
    for (const OrbitCamera& camera : {orbit, stereoEye(orbit, Eye::Right, 600, 18500)}) {
        const CameraFrame a(camera, 96, 64);
        OrbitCamera general = camera;
        general.eyeOffsetKm = 0;  // an explicit view ignores the orbit's offsets
        general.views = {viewOf(a)};
        general.validate();
        const CameraFrame b(general, 96, 64);
        for (float py : {0.0f, 10.5f, 32.0f, 63.5f, 64.0f})
            for (float px : {0.0f, 0.5f, 47.25f, 95.5f, 96.0f}) {
                const Vec3 da = a.direction(px, py), db = b.direction(px, py);
                EXPECT_NEAR(da.x, db.x, 2e-6f) << px << "," << py;
                EXPECT_NEAR(da.y, db.y, 2e-6f) << px << "," << py;
                EXPECT_NEAR(da.z, db.z, 2e-6f) << px << "," << py;
            }
        EXPECT_EQ(a.eye.x, b.eye.x);
        EXPECT_EQ(a.eye.y, b.eye.y);
        EXPECT_EQ(a.eye.z, b.eye.z);
    }
}

TEST(CameraView, AsymmetricFrustumProjectsTheCentreAndTheLimbAnalytically)
{
    // The eye 20000 km out on +x looking at the centre: camera +x -> +y, +y -> +z, -z -> -x, a
    // rotation by 120 degrees about (1, 1, 1) (quaternion [1/2, 1/2, 1/2, 1/2]).
    const float D = 20000, R = 6371, left = -0.2f, right = 0.5f, down = -0.1f, up = 0.4f;
    const int w = 70, h = 50;
    OrbitCamera camera;
    camera.views = {CameraView{{D, 0, 0}, {0.5f, 0.5f, 0.5f, 0.5f}, {left, right, down, up}}};
    const CameraFrame f(camera, w, h);
    // The view axis lands where the tangent 0 lies between the frustum's edges.
    float px, py, dist;
    ASSERT_TRUE(f.project({0, 0, 0}, px, py, dist));
    EXPECT_NEAR(px, (0 - left) / (right - left) * w, 1e-3);  // 20
    EXPECT_NEAR(py, (up - 0) / (up - down) * h, 1e-3);       // 40
    EXPECT_NEAR(dist, D, 1e-2);
    // The top of the limb: the tangent point P (|P| = R, (P - E).P = 0) at x = R^2 / D, seen at the
    // tangent R / sqrt(D^2 - R^2) above the axis.
    const float tanLimb = R / std::sqrt(D * D - R * R);
    const float limbRow = (up - tanLimb) / (up - down) * h;
    ASSERT_TRUE(f.project({R * R / D, 0, R * std::sqrt(1 - R * R / (D * D))}, px, py, dist));
    EXPECT_NEAR(px, 20, 1e-3);
    EXPECT_NEAR(py, limbRow, 1e-3);
    // Rays just below the limb row hit the sphere, rays just above miss it.
    float t0, t1;
    EXPECT_TRUE(intersectSphere(f.eye, f.direction(20, limbRow + 0.02f), R, t0, t1));
    EXPECT_FALSE(intersectSphere(f.eye, f.direction(20, limbRow - 0.02f), R, t0, t1));
    // Image corners are the frustum's corners.
    const Vec3 corner = f.direction(0, 0);
    EXPECT_NEAR(corner.y / -corner.x, left, 1e-6);
    EXPECT_NEAR(corner.z / -corner.x, up, 1e-6);
    const Vec3 far = f.direction(float(w), float(h));
    EXPECT_NEAR(far.y / -far.x, right, 1e-6);
    EXPECT_NEAR(far.z / -far.x, down, 1e-6);
}

TEST(CameraView, TurningTheHeadTurnsTheViewAndStereoPicksTheEyesView)
{
    // The head turned 90 degrees to the left (about camera +y) from the pose above: it looks along
    // the old camera -x, which is world -y.
    const float s = float(std::sqrt(0.5));
    const std::array<float, 4> base{0.5f, 0.5f, 0.5f, 0.5f}, yaw{0, s, 0, s};
    const auto [ax, ay, az, aw] = base;
    const auto [bx, by, bz, bw] = yaw;
    const std::array<float, 4> q{aw * bx + ax * bw + ay * bz - az * by, aw * by - ax * bz + ay * bw + az * bx,
                                 aw * bz + ax * by - ay * bx + az * bw, aw * bw - ax * bx - ay * by - az * bz};
    OrbitCamera left, right;
    left.views = {CameraView{{20000, 0, 0}, q, {-1, 1, -1, 1}}};
    const CameraFrame f(left, 10, 10);
    EXPECT_NEAR(f.forward.x, 0, 1e-6);
    EXPECT_NEAR(f.forward.y, -1, 1e-6);
    EXPECT_NEAR(f.up.z, 1, 1e-6);
    right.views = {CameraView{{20000, 5, 0}, base, {-1, 1, -1, 1}}};
    OrbitCamera pair;
    pair.views = {left.views[0], right.views[0]};
    EXPECT_EQ(stereoEye(pair, Eye::Left, 600, 100).views[0].orientation, q);
    EXPECT_EQ(stereoEye(pair, Eye::Right, 600, 100).views[0].positionKm.y, 5.0f);
    EXPECT_EQ(stereoEye(pair, Eye::Right, 600, 100).eyeOffsetKm, 0.0);
}

TEST(CameraView, InvalidViewsAreRefused)
{
    const auto message = [](CameraView v) {
        try {
            v.validate();
        } catch (const Error& e) {
            return std::string(e.what());
        }
        return std::string("accepted");
    };
    CameraView v;
    EXPECT_EQ(message(v), "accepted");
    v.orientation = {0, 0, 0, 1.0005f};  // within the tolerance
    EXPECT_EQ(message(v), "accepted");
    v.orientation = {0, 0, 0.1f, 1};
    EXPECT_NE(message(v).find("expected a unit quaternion"), std::string::npos) << message(v);
    v.orientation = {0, 0, 0, 1};
    v.frustum = {1, -1, -1, 1};
    EXPECT_NE(message(v).find("left < right"), std::string::npos) << message(v);
    v.frustum = {-1, 1, 0.5f, 0.5f};
    EXPECT_NE(message(v).find("down < up"), std::string::npos) << message(v);
    v.frustum = {-1, 1, -1, 1};
    v.positionKm.x = NAN;
    EXPECT_NE(message(v).find("finite"), std::string::npos) << message(v);
    OrbitCamera three;
    three.views.resize(3);
    EXPECT_THROW(three.validate(), Error);
}

}  // namespace
}  // namespace raypc::render
