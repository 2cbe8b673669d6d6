// The coordinates that can be brushed and plotted like variables (x, y, z, lat, lon, radius, depth),
// and the one definition of their value at a point and of their range on a grid. Selection,
// pathline filtering, both render kernels and the server's dataset description use these.
//
// Units and conventions as in core/spherical.h: km for x, y, z, radius and depth (depth =
// kSurfaceRadiusKm - radius), degrees north for lat, degrees east in [0, 360) for lon.
#pragma once

#include "core/spherical.h"
#include "grid/grid.h"

#include <optional>
#include <string>
#include <vector>

namespace raypc::grid {

enum class Coordinate { X, Y, Z, Lat, Lon, Radius, Depth };

struct CoordinateInfo {
    Coordinate id;
    std::string name;   // "x", "y", "z", "lat", "lon", "radius", "depth"
    std::string units;  // "km", "degrees_north" or "degrees_east"
};
// In the order of the parallel-coordinates sample's columns (dataset.h).
const std::vector<CoordinateInfo>& coordinateInfos();
// The coordinate named `name`, if any.
std::optional<Coordinate> findCoordinate(const std::string& name);

// Every coordinate is an affine function of one component of a point known in both forms,
// Cartesian (x, y, z in km) and spherical (lat, lon in degrees, lon in [0, 360), r in km):
// value = scale * component + offset. This table is the one definition of the coordinates' values;
// the render kernels apply it to their lanes (they pick the component and do one multiply-add).
enum class PointComponent { X, Y, Z, LatDeg, LonDeg, RKm };
struct CoordinateDefinition {
    PointComponent component;
    double scale = 1, offset = 0;
};
constexpr CoordinateDefinition coordinateDefinition(Coordinate c)
{
    switch (c) {
    case Coordinate::X: return {PointComponent::X};
    case Coordinate::Y: return {PointComponent::Y};
    case Coordinate::Z: return {PointComponent::Z};
    case Coordinate::Lat: return {PointComponent::LatDeg};
    case Coordinate::Lon: return {PointComponent::LonDeg};
    case Coordinate::Radius: return {PointComponent::RKm};
    case Coordinate::Depth: return {PointComponent::RKm, -1.0, kSurfaceRadiusKm};
    }
    return {PointComponent::X};  // unreachable: every enumerator is handled
}

// The value of `c` at (latDeg, lonDeg, rKm); lon is wrapped into [0, 360).
inline double coordinateValue(Coordinate c, double latDeg, double lonDeg, double rKm)
{
    const double lon = wrapLonDeg(lonDeg);
    const CoordinateDefinition d = coordinateDefinition(c);
    double v = 0;
    switch (d.component) {
    case PointComponent::X: v = sphericalToCartesianKm(latDeg, lon, rKm).x; break;
    case PointComponent::Y: v = sphericalToCartesianKm(latDeg, lon, rKm).y; break;
    case PointComponent::Z: v = sphericalToCartesianKm(latDeg, lon, rKm).z; break;
    case PointComponent::LatDeg: v = latDeg; break;
    case PointComponent::LonDeg: v = lon; break;
    case PointComponent::RKm: v = rKm; break;
    }
    return d.scale * v + d.offset;
}

struct CoordinateRange {
    double min = 0, max = 0;
};
// The range of `c` over the shell the grid covers (r from rKm.front() to rKm.back(); the whole
// sphere in lat and lon): x, y, z within ±rKm.back(), lat -90..90, lon 0..360. A regional grid's
// (grid.h, dataLatDeg and dataLonDeg): over its data's extent (x, y, z over its grid points of data;
// lon 0..360 when the region crosses 0°).
CoordinateRange coordinateRange(const SphericalGrid& grid, Coordinate c);

}  // namespace raypc::grid
