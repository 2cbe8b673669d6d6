#include "grid/coordinates.h"

#include <algorithm>
#include <cmath>

namespace raypc::grid {

const std::vector<CoordinateInfo>& coordinateInfos()
{
    static const std::vector<CoordinateInfo> infos = {
        {Coordinate::X, "x", "km"},           {Coordinate::Y, "y", "km"},
        {Coordinate::Z, "z", "km"},           {Coordinate::Lat, "lat", "degrees_north"},
        {Coordinate::Lon, "lon", "degrees_east"}, {Coordinate::Radius, "radius", "km"},
        {Coordinate::Depth, "depth", "km"}};
    return infos;
}

std::optional<Coordinate> findCoordinate(const std::string& name)
{
    for (const auto& c : coordinateInfos())
        if (c.name == name)
            return c.id;
    return std::nullopt;
}

CoordinateRange coordinateRange(const SphericalGrid& grid, Coordinate c)
{
    const double rMin = grid.rKm.front(), rMax = grid.rKm.back();
    // A regional grid: the range over its grid points of data (on its inner and outer shell), so that
    // an axis spans the region, not the globe its padding reaches.
    const auto overRegion = [&](auto value) {
        CoordinateRange range{INFINITY, -INFINITY};
        for (double lat : grid.latDeg)
            for (double lon : grid.lonDeg)
                if (grid.latHoldsData(lat) && grid.lonHoldsData(lon))
                    for (double r : {rMin, rMax}) {
                        const double v = value(sphericalToCartesianKm(lat, lon, r));
                        range.min = std::min(range.min, v), range.max = std::max(range.max, v);
                    }
        return range;
    };
    switch (c) {
    case Coordinate::X: return grid.regional() ? overRegion([](const Vec3d& p) { return p.x; }) : CoordinateRange{-rMax, rMax};
    case Coordinate::Y: return grid.regional() ? overRegion([](const Vec3d& p) { return p.y; }) : CoordinateRange{-rMax, rMax};
    case Coordinate::Z: return grid.regional() ? overRegion([](const Vec3d& p) { return p.z; }) : CoordinateRange{-rMax, rMax};
    case Coordinate::Lat: return grid.dataLatDeg ? CoordinateRange{(*grid.dataLatDeg)[0], (*grid.dataLatDeg)[1]} : CoordinateRange{-90, 90};
    case Coordinate::Lon:
        // A region across 0° keeps the whole axis: its longitudes are not one interval of 0..360.
        return grid.dataLonDeg && (*grid.dataLonDeg)[0] <= (*grid.dataLonDeg)[1]
                   ? CoordinateRange{(*grid.dataLonDeg)[0], (*grid.dataLonDeg)[1]}
                   : CoordinateRange{0, 360};
    case Coordinate::Radius: return {rMin, rMax};
    case Coordinate::Depth: return {kSurfaceRadiusKm - rMax, kSurfaceRadiusKm - rMin};
    }
    return {};
}

}  // namespace raypc::grid
