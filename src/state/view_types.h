// The small value types the state document names (state/render_state.h) and the renderer draws
// with: the camera's pose, opacity points, shading, the stereo mode and the map projections'
// names. Kept here, apart from the renderer, so that reading, checking and writing a state needs
// nothing from render/ (the commands that only read a state's settings do not link the renderer).
#pragma once

#include "core/vec3.h"

#include <array>
#include <optional>
#include <span>
#include <string_view>
#include <vector>

namespace raypc::state {

using Vec3 = Vec3f;  // core/vec3.h

// A general camera pose and frustum, as WebXR gives one per eye (an XRView's transform and
// projection matrix): the eye at positionKm, turned by the unit quaternion `orientation`
// [x, y, z, w] from camera axes to the contest frame, where the camera looks along its -z with +y
// up and +x right (the WebXR/OpenGL convention); the image spans the signed tangents
// frustum = [left, right, down, up] of the angles of its edges from the view axis (left < right,
// down < up; a symmetric 90° frustum is [-1, 1, -1, 1]). The image's width and height map onto
// the frustum whatever their ratio (a headset's pixels need not be square).
struct CameraView {
    Vec3 positionKm{};
    std::array<float, 4> orientation{0, 0, 0, 1};
    std::array<float, 4> frustum{-1, 1, -1, 1};

    // |orientation| may differ from 1 by this much (float JSON round trips); it is normalised.
    static constexpr float kUnitTolerance = 1e-3f;
    // Throws raypc::Error for a non-finite value, an orientation whose length is not 1 within
    // kUnitTolerance, or a degenerate frustum (left >= right or down >= up, or a tangent beyond 1e4).
    void validate() const;
};

struct OrbitCamera {
    double azimuthDeg = 30.0;
    double elevationDeg = 20.0;
    double distanceKm = 20000.0;  // from target to eye
    double fovYDeg = 40.0;        // vertical field of view
    Vec3 targetKm{};              // point looked at, km

    // One eye of a stereo pair (stereoEye sets these; the state document has no such keys): the eye
    // moved by eyeOffsetKm along the image's right axis (negative: to the left), and the image
    // window shifted so that points at convergenceKm along the view axis have no parallax.
    double eyeOffsetKm = 0;
    double convergenceKm = 0;  // <= 0: no shift (only with eyeOffsetKm = 0)
    // Width / height of one pixel: 2 renders each eye of a half-width side-by-side pair squeezed
    // into half the columns (a display stretches it back).
    double pixelAspect = 1;

    // Explicit views (state key camera.views): none, the orbit defines the camera; one, it replaces
    // the orbit's pose and frustum (the orbit keys stay, e.g. for the UI's navigation and the tubes'
    // minimum width); two, the left and right eye of a stereo pair (stereoEye picks one). The eye
    // offset, convergence and pixel aspect do not apply to an explicit view.
    std::vector<CameraView> views;

    // Throws raypc::Error if distance <= 0, the field of view is outside (0, 180), the eye
    // offset, convergence or pixel aspect are not usable, or a view is invalid (CameraView::validate).
    void validate() const;
};

// `position` is normalised over the value range (0 = range.min, 1 = range.max); opacity in [0, 1].
struct OpacityPoint {
    float position = 0, opacity = 0;
};

struct ShadingStyle {
    bool enabled = false;  // gradient shading of the volume (the core is always Lambert-shaded)
    Vec3 lightFromCamera{0.4f, 0.6f, 1.0f};  // towards the light in the camera frame: x right, y up, z to the viewer
    float ambient = 0.35f, diffuse = 0.65f;
    float specular = 0.2f, shininess = 24;  // Blinn-Phong highlight weight and exponent
    // Volumetric occlusion (shadow_volume.h): soft shadows from the light and ambient occlusion by
    // the volume, the tubes and the core, on the volume, the core and the tubes; with or without
    // `enabled`. Strength in [0, 1]: how much of the occluded light is taken away.
    bool shadows = false;
    float shadowStrength = 0.8f;
};

// How a state's picture shows the two eyes (state key stereo.mode).
enum class StereoMode {
    Off,             // one picture from the orbit camera
    SideBySide,      // left eye | right eye, each the state's width: 2W x H
    SideBySideHalf,  // left | right, each squeezed into half the width: W x H (a 3D display stretches it)
    Anaglyph,        // red-cyan, W x H: red from the left eye, green and blue from the right
};

std::string_view stereoModeName(StereoMode mode);  // "off", "side-by-side", "side-by-side-half", "anaglyph"
// Throws raypc::Error listing the names.
StereoMode parseStereoMode(std::string_view name);
const std::vector<StereoMode>& allStereoModes();

// The state's "stereo" object (docs/state.md). Restart class: it changes the cameras and the size.
struct StereoState {
    StereoMode mode = StereoMode::Off;
    float eyeSeparationKm = 600.0f;  // between the two eyes, km (about 1/35 of the default view distance)
    // Distance in front of the eyes of the zero-parallax plane (the screen), km; nullopt: the
    // camera's distance to its target (the target appears on the screen plane).
    std::optional<float> convergenceKm;
    bool enabled() const { return mode != StereoMode::Off; }
    double convergenceOr(double cameraDistanceKm) const { return convergenceKm ? *convergenceKm : cameraDistanceKm; }
};

enum class MapProjection { Equirectangular, Mollweide, Hammer, Robinson, Orthographic };

std::span<const MapProjection> allMapProjections();
std::string_view mapProjectionName(MapProjection projection);  // "mollweide", as the state writes it
std::string_view mapProjectionTitle(MapProjection projection);  // "Mollweide", as a figure writes it
// Throws raypc::Error listing the known names.
MapProjection parseMapProjection(std::string_view name);

// How a pair's second dataset takes the state's step (state key pair.steps, docs/compare.md): the
// same index, or its step nearest in model time to the first's.
enum class PairSteps { Time, Index };

std::span<const PairSteps> allPairSteps();
std::string_view pairStepsName(PairSteps steps);  // "time", "index"
// Throws raypc::Error listing the known names.
PairSteps parsePairSteps(std::string_view name);

}  // namespace raypc::state
