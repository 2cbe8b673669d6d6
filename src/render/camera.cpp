#include "render/camera.h"

#include "core/error.h"
#include "core/spherical.h"

#include <algorithm>

namespace raypc::render {

void OrbitCamera::validate() const
{
    if (!(distanceKm > 0.0) || !std::isfinite(distanceKm))
        fail("camera distance: {} km, expected a positive distance", distanceKm);
    if (!(fovYDeg > 0.0 && fovYDeg < 180.0))
        fail("camera field of view: {} degrees, expected a value in (0, 180)", fovYDeg);
    if (!std::isfinite(azimuthDeg) || !std::isfinite(elevationDeg))
        fail("camera azimuth/elevation must be finite numbers");
}

CameraFrame::CameraFrame(const OrbitCamera& camera, int width_, int height_) : width(width_), height(height_)
{
    // Keep the elevation a hair away from ±90° so that the +z up vector never becomes parallel to the view.
    const double el = degToRad(std::clamp(camera.elevationDeg, -89.999, 89.999));
    const double az = degToRad(camera.azimuthDeg);
    const Vec3 offset{float(std::cos(el) * std::cos(az)), float(std::cos(el) * std::sin(az)), float(std::sin(el))};
    eye = camera.targetKm + offset * float(camera.distanceKm);
    forward = normalize(offset * -1.0f);
    right = normalize(cross(forward, Vec3{0, 0, 1}));
    up = cross(right, forward);
    tanHalfFovY = float(std::tan(degToRad(camera.fovYDeg) * 0.5));
    aspect = float(width) / float(height);
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
