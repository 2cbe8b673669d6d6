#include "render/camera.h"

#include "core/error.h"
#include "core/spherical.h"

#include <algorithm>

namespace raypc::render {

OrbitCamera stereoEye(const OrbitCamera& camera, Eye eye, double eyeSeparationKm, double convergenceKm)
{
    if (!(eyeSeparationKm >= 0) || !std::isfinite(eyeSeparationKm))
        fail("stereo eye separation: {} km, expected a distance >= 0", eyeSeparationKm);
    if (!(convergenceKm > 0) || !std::isfinite(convergenceKm))
        fail("stereo convergence distance: {} km, expected a positive distance", convergenceKm);
    OrbitCamera e = camera;
    if (camera.views.size() == 2) {
        e.views = {camera.views[eye == Eye::Left ? 0 : 1]};
        return e;
    }
    e.eyeOffsetKm = (eye == Eye::Left ? -0.5 : 0.5) * eyeSeparationKm;
    e.convergenceKm = convergenceKm;
    return e;
}

double framingDistanceKm(double fovYDeg, int width, int height, double radiusKm, double fill)
{
    RAYPC_CHECK(width > 0 && height > 0 && fill > 0 && fill <= 1 && radiusKm > 0);
    // The shorter side's half-angle tangent; the sphere's silhouette is at tangent R / sqrt(D² - R²).
    const double tanHalf = std::tan(fovYDeg * M_PI / 360.0) * std::min(1.0, double(width) / double(height));
    const double k = fill * tanHalf;
    return radiusKm * std::sqrt(1.0 + 1.0 / (k * k));
}

CameraFrame::CameraFrame(const OrbitCamera& camera, int width_, int height_) : width(width_), height(height_)
{
    RAYPC_CHECK_LT(camera.views.size(), size_t(2));
    if (camera.views.size() == 1) {
        // The rotation of the (normalised) quaternion applied to the camera's axes +x, +y and -z.
        const CameraView& v = camera.views.front();
        const double n = std::sqrt(double(v.orientation[0]) * v.orientation[0] + double(v.orientation[1]) * v.orientation[1] +
                                   double(v.orientation[2]) * v.orientation[2] + double(v.orientation[3]) * v.orientation[3]);
        const double x = v.orientation[0] / n, y = v.orientation[1] / n, z = v.orientation[2] / n, w = v.orientation[3] / n;
        right = Vec3{float(1 - 2 * (y * y + z * z)), float(2 * (x * y + z * w)), float(2 * (x * z - y * w))};
        up = Vec3{float(2 * (x * y - z * w)), float(1 - 2 * (x * x + z * z)), float(2 * (y * z + x * w))};
        forward = Vec3{float(-2 * (x * z + y * w)), float(-2 * (y * z - x * w)), float(-(1 - 2 * (x * x + y * y)))};
        eye = v.positionKm;
        const auto [left, rightTan, down, upTan] = v.frustum;
        tanHalfFovY = 0.5f * (upTan - down);
        aspect = (rightTan - left) / (upTan - down);
        shiftX = 0.5f * (rightTan + left);
        shiftY = 0.5f * (upTan + down);
        return;
    }
    // Keep the elevation a hair away from ±90° so that the +z up vector never becomes parallel to the view.
    const double el = degToRad(std::clamp(camera.elevationDeg, -89.999, 89.999));
    const double az = degToRad(camera.azimuthDeg);
    const Vec3 offset{float(std::cos(el) * std::cos(az)), float(std::cos(el) * std::sin(az)), float(std::sin(el))};
    forward = normalize(offset * -1.0f);
    right = normalize(cross(forward, Vec3{0, 0, 1}));
    up = cross(right, forward);
    // A stereo eye: beside the orbit position, its window shifted so that the axis point at the
    // convergence distance projects to the image centre as it does for the orbit position.
    eye = camera.targetKm + offset * float(camera.distanceKm) + right * float(camera.eyeOffsetKm);
    shiftX = camera.convergenceKm > 0 ? float(-camera.eyeOffsetKm / camera.convergenceKm) : 0.0f;
    tanHalfFovY = float(std::tan(degToRad(camera.fovYDeg) * 0.5));
    aspect = float(double(width) * camera.pixelAspect / double(height));
}

ShellSegments intersectShell(Vec3 o, Vec3 d, float rInnerKm, float rOuterKm, bool throughCore)
{
    ShellSegments s;
    float a0, a1;
    if (!intersectSphere(o, d, rOuterKm, a0, a1) || a1 <= 0.0f)
        return s;
    a0 = std::max(a0, 0.0f);
    float c0, c1;
    if (!intersectSphere(o, d, rInnerKm, c0, c1) || c1 <= 0.0f) {
        s.count = 1;
        s.t0[0] = a0;
        s.t1[0] = a1;
        return s;
    }
    if (c0 > 0.0f) {
        s.coreT = c0;
        s.t0[0] = a0;
        s.t1[0] = c0;
        s.count = 1;
    } else {
        s.coreT = 0.0f;  // the eye is inside the core
    }
    if (throughCore && c1 < a1) {
        s.t0[s.count] = std::max(c1, 0.0f);
        s.t1[s.count] = a1;
        ++s.count;
    }
    return s;
}

}  // namespace raypc::render
