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
    if (!std::isfinite(eyeOffsetKm) || !std::isfinite(convergenceKm) || (eyeOffsetKm != 0 && !(convergenceKm > 0)))
        fail("camera eye offset {} km, convergence {} km: expected finite numbers and a positive convergence",
             eyeOffsetKm, convergenceKm);
    if (!(pixelAspect > 0) || !std::isfinite(pixelAspect))
        fail("camera pixel aspect {}: expected a positive number", pixelAspect);
}

OrbitCamera stereoEye(const OrbitCamera& camera, Eye eye, double eyeSeparationKm, double convergenceKm)
{
    if (!(eyeSeparationKm >= 0) || !std::isfinite(eyeSeparationKm))
        fail("stereo eye separation: {} km, expected a distance >= 0", eyeSeparationKm);
    if (!(convergenceKm > 0) || !std::isfinite(convergenceKm))
        fail("stereo convergence distance: {} km, expected a positive distance", convergenceKm);
    OrbitCamera e = camera;
    e.eyeOffsetKm = (eye == Eye::Left ? -0.5 : 0.5) * eyeSeparationKm;
    e.convergenceKm = convergenceKm;
    return e;
}

CameraFrame::CameraFrame(const OrbitCamera& camera, int width_, int height_) : width(width_), height(height_)
{
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
