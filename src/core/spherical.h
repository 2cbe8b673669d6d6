// The planet's geometry and the Cartesian frame of the contest data.
//
// Conventions used everywhere in RayPC:
//   lat in degrees north (-90 south pole .. 90 north pole), lon in degrees east [0, 360),
//   r in km from the centre; x = r cos(lat) cos(lon), y = r cos(lat) sin(lon), z = r sin(lat).
// Cartesian positions are in km.
#pragma once

#include "core/vec3.h"

#include <algorithm>
#include <cmath>
#include <numbers>

namespace raypc {

inline constexpr double kCoreRadiusKm = 3485.0;     // core-mantle boundary
inline constexpr double kSurfaceRadiusKm = 6371.0;  // Earth's mean radius
inline constexpr double kSecondsPerMyr = 3.15576e13;  // Julian year * 1e6
inline constexpr double kMpsToCmPerYr = 3.15576e9;    // 1 m/s = 3.15576e9 cm/yr

inline constexpr double degToRad(double degrees) { return degrees * (std::numbers::pi / 180.0); }
inline constexpr double radToDeg(double radians) { return radians * (180.0 / std::numbers::pi); }

inline Vec3d sphericalToCartesianKm(double latDeg, double lonDeg, double rKm)
{
    const double lat = degToRad(latDeg), lon = degToRad(lonDeg);
    return {rKm * std::cos(lat) * std::cos(lon), rKm * std::cos(lat) * std::sin(lon), rKm * std::sin(lat)};
}

// Unit vectors east and north at (lat, lon) in the contest frame; at a pole, those of the meridian
// of `lonDeg` (north there points on over the pole).
struct EastNorth {
    Vec3d east, north;
};
inline EastNorth eastNorthAt(double latDeg, double lonDeg)
{
    const double la = degToRad(latDeg), lo = degToRad(lonDeg);
    return {Vec3d{-std::sin(lo), std::cos(lo), 0},
            Vec3d{-std::sin(la) * std::cos(lo), -std::sin(la) * std::sin(lo), std::cos(la)}};
}

struct SphericalPoint {
    double latDeg = 0, lonDeg = 0, rKm = 0;  // lon in [0, 360)
};

inline SphericalPoint cartesianToSpherical(const Vec3d& p)
{
    const double r = std::sqrt(p.x * p.x + p.y * p.y + p.z * p.z);
    if (r == 0.0)
        return {};
    double lon = radToDeg(std::atan2(p.y, p.x));
    if (lon < 0.0)
        lon += 360.0;
    if (lon >= 360.0)
        lon -= 360.0;
    return {radToDeg(std::asin(std::clamp(p.z / r, -1.0, 1.0))), lon, r};
}

// Wraps any longitude into [0, 360).
inline double wrapLonDeg(double lonDeg)
{
    double w = std::fmod(lonDeg, 360.0);
    if (w < 0.0)
        w += 360.0;
    return w >= 360.0 ? 0.0 : w;
}

// The angle between two longitudes the short way round, across the seam if shorter: [0, 180].
inline double lonSeparationDeg(double aDeg, double bDeg)
{
    const double d = std::fmod(std::abs(aDeg - bDeg), 360.0);
    return std::min(d, 360.0 - d);
}

}  // namespace raypc
