#include "state/view_types.h"

#include "core/error.h"
#include "core/strings.h"

#include <algorithm>
#include <cmath>
#include <string>

namespace raypc::state {
namespace {

constexpr MapProjection kAll[] = {MapProjection::Equirectangular, MapProjection::Mollweide, MapProjection::Hammer,
                                  MapProjection::Robinson, MapProjection::Orthographic};

}  // namespace

void CameraView::validate() const
{
    const auto finite = [](auto values) {
        return std::all_of(values.begin(), values.end(), [](float x) { return std::isfinite(x); });
    };
    if (!finite(std::array<float, 3>{positionKm.x, positionKm.y, positionKm.z}) || !finite(orientation) ||
        !finite(frustum))
        fail("camera view: expected finite numbers");
    const double length = std::sqrt(double(orientation[0]) * orientation[0] + double(orientation[1]) * orientation[1] +
                                    double(orientation[2]) * orientation[2] + double(orientation[3]) * orientation[3]);
    if (!(std::abs(length - 1.0) <= kUnitTolerance))
        fail("camera view orientation [{}, {}, {}, {}]: length {}, expected a unit quaternion (within {})", orientation[0],
             orientation[1], orientation[2], orientation[3], length, kUnitTolerance);
    const auto [left, right, down, up] = frustum;
    if (!(left < right && down < up) || std::max({std::abs(left), std::abs(right), std::abs(down), std::abs(up)}) > 1e4f)
        fail("camera view frustum [{}, {}, {}, {}]: expected tangents [left, right, down, up] with left < right, "
             "down < up, each within ±10000",
             left, right, down, up);
}

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
    if (views.size() > 2)
        fail("camera views: {} views, expected at most 2 (one, or a stereo pair's left and right eye)", views.size());
    for (const CameraView& v : views)
        v.validate();
}

std::string_view stereoModeName(StereoMode mode)
{
    switch (mode) {
    case StereoMode::Off: return "off";
    case StereoMode::SideBySide: return "side-by-side";
    case StereoMode::SideBySideHalf: return "side-by-side-half";
    case StereoMode::Anaglyph: return "anaglyph";
    }
    return "off";
}

const std::vector<StereoMode>& allStereoModes()
{
    static const std::vector<StereoMode> modes{StereoMode::Off, StereoMode::SideBySide, StereoMode::SideBySideHalf,
                                               StereoMode::Anaglyph};
    return modes;
}

StereoMode parseStereoMode(std::string_view name)
{
    std::string known;
    if (const auto mode = findByName(name, allStereoModes(), stereoModeName, known))
        return *mode;
    fail("stereo mode '{}' is unknown, expected one of: {}", name, known);
}

std::span<const MapProjection> allMapProjections() { return kAll; }

std::string_view mapProjectionName(MapProjection projection)
{
    switch (projection) {
    case MapProjection::Equirectangular: return "equirectangular";
    case MapProjection::Mollweide: return "mollweide";
    case MapProjection::Hammer: return "hammer";
    case MapProjection::Robinson: return "robinson";
    case MapProjection::Orthographic: return "orthographic";
    }
    return "?";
}

std::string_view mapProjectionTitle(MapProjection projection)
{
    switch (projection) {
    case MapProjection::Equirectangular: return "equirectangular";
    case MapProjection::Mollweide: return "Mollweide";
    case MapProjection::Hammer: return "Hammer";
    case MapProjection::Robinson: return "Robinson";
    case MapProjection::Orthographic: return "orthographic";
    }
    return "?";
}

MapProjection parseMapProjection(std::string_view name)
{
    std::string known;
    if (const auto projection = findByName(name, allMapProjections(), mapProjectionName, known))
        return *projection;
    fail("unknown map projection '{}'; expected one of: {}", name, known);
}

namespace {
constexpr PairSteps kAllPairSteps[] = {PairSteps::Time, PairSteps::Index};
}

std::span<const PairSteps> allPairSteps() { return kAllPairSteps; }

std::string_view pairStepsName(PairSteps steps)
{
    return steps == PairSteps::Index ? "index" : "time";
}

PairSteps parsePairSteps(std::string_view name)
{
    std::string known;
    if (const auto steps = findByName(name, allPairSteps(), pairStepsName, known))
        return *steps;
    fail("unknown step matching '{}'; expected one of: {}", name, known);
}

}  // namespace raypc::state
