// An orbiting perspective camera around the planet, and the ray geometry of the spherical shell.
//
// Positions are Cartesian km in the contest frame (core/spherical.h): x = r cos(lat) cos(lon), ...
// The camera orbits `target`: azimuth is measured in the x-y plane from +x towards +y (degrees),
// elevation from the x-y plane towards +z (degrees), the up direction is +z.
// Image pixel (0, 0) is the top-left corner; pixel centres are at (i + 0.5, j + 0.5).
// A stereo eye (stereoEye) is the same camera moved along the image's right axis with the image
// window shifted sideways (an off-axis, asymmetric frustum; the view axes stay parallel).
// An explicit view (CameraView, state key camera.views, e.g. one eye of a WebXR headset) replaces
// the orbit's pose and frustum by a general one: any position, orientation and asymmetric frustum.
//
// Thread safety: plain values; CameraFrame is immutable after construction.
#pragma once

#include "core/vec3.h"
#include "state/view_types.h"

#include <array>
#include <cmath>
#include <vector>

namespace raypc::render {

using Vec3 = Vec3f;  // core/vec3.h

// The camera's pose and frustum are the state's (state/view_types.h).
using state::CameraView;
using state::OrbitCamera;

// The orbit distance at which a sphere of `radiusKm` around the target fills `fill` (0..1) of the
// image's shorter side, for a vertical field of view of fovYDeg and an image of width x height
// pixels (a landscape image is bound by its height, a portrait one by its width), km.
double framingDistanceKm(double fovYDeg, int width, int height, double radiusKm, double fill);

enum class Eye { Left, Right };

// The camera of one eye of a stereo pair: parallel view axes, the eyes eyeSeparationKm apart
// (each half of it beside the original eye), and an asymmetric frustum whose zero-parallax plane
// lies convergenceKm in front of the eyes ("toe-in", rotating the eyes, would add vertical
// parallax away from the centre). A point at depth z (km along the view axis) then has the
// horizontal screen parallax eyeSeparationKm (1/convergenceKm - 1/z) in tangent units (right eye
// minus left eye; positive behind the zero-parallax plane). Throws raypc::Error unless
// eyeSeparationKm >= 0 and convergenceKm > 0. A camera with two explicit views gives the eye's
// view instead (the separation and convergence do not apply).
OrbitCamera stereoEye(const OrbitCamera& camera, Eye eye, double eyeSeparationKm, double convergenceKm);

// The camera resolved for one image size: eye and an orthonormal basis. The image window spans
// tangents [shiftX - tanHalfFovY aspect, shiftX + tanHalfFovY aspect] horizontally and
// [shiftY - tanHalfFovY, shiftY + tanHalfFovY] vertically.
struct CameraFrame {
    Vec3 eye, forward, right, up;
    float tanHalfFovY = 0, aspect = 1;  // orbit: aspect = width x pixelAspect / height
    float shiftX = 0;  // horizontal shift of the image window, tangent units (an off-axis frustum)
    float shiftY = 0;  // vertical shift (an explicit view's frustum)
    int width = 0, height = 0;

    CameraFrame() = default;
    // The orbit camera, or its explicit view (it must have at most one: stereoEye picks an eye's).
    CameraFrame(const OrbitCamera& camera, int width, int height);

    // Unit direction through image position (px, py) in pixels (continuous; centre of pixel i is i + 0.5).
    Vec3 direction(float px, float py) const
    {
        const float sx = (2.0f * px / float(width) - 1.0f) * tanHalfFovY * aspect + shiftX;
        const float sy = (1.0f - 2.0f * py / float(height)) * tanHalfFovY + shiftY;
        return normalize(forward + right * sx + up * sy);
    }

    // The inverse of direction: image position (px, py) of point p (km) and its distance from the
    // eye; false when p is not in front of the eye.
    bool project(Vec3 p, float& px, float& py, float& distanceKm) const
    {
        const Vec3 d = p - eye;
        const float z = dot(d, forward);
        if (z <= 1e-3f)
            return false;
        const float sx = (dot(d, right) / z - shiftX) / (tanHalfFovY * aspect);
        const float sy = (dot(d, up) / z - shiftY) / tanHalfFovY;
        px = (sx + 1.0f) * 0.5f * float(width);
        py = (1.0f - sy) * 0.5f * float(height);
        distanceKm = std::sqrt(dot(d, d));
        return true;
    }
};

// Intersection of the ray o + t d (|d| = 1) with the sphere of radius `radiusKm` around the origin.
// Returns false on a miss; otherwise t0 <= t1 (either may be negative).
inline bool intersectSphere(Vec3 o, Vec3 d, float radiusKm, float& t0, float& t1)
{
    // Solved around the closest approach (t = -b) so that grazing rays far from the origin keep precision.
    const float b = dot(o, d);
    const Vec3 closest = o - d * b;
    const float h2 = radiusKm * radiusKm - dot(closest, closest);
    if (h2 < 0.0f)
        return false;
    const float h = std::sqrt(h2);
    t0 = -b - h;
    t1 = -b + h;
    return true;
}

// The parts of a ray inside the shell rInner <= |p| <= rOuter, for t >= 0.
// Segment 0 is [enter, leave or core entry]; segment 1 (behind the core) exists only when the
// ray passes through the core and `throughCore` is set. `coreT` is the first core hit (t >= 0) or -1.
struct ShellSegments {
    int count = 0;
    float t0[2]{}, t1[2]{};
    float coreT = -1;
};
ShellSegments intersectShell(Vec3 o, Vec3 d, float rInnerKm, float rOuterKm, bool throughCore);

}  // namespace raypc::render
