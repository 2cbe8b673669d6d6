#include "grid/coordinates.h"

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
    switch (c) {
    case Coordinate::X:
    case Coordinate::Y:
    case Coordinate::Z: return {-rMax, rMax};
    case Coordinate::Lat: return {-90, 90};
    case Coordinate::Lon: return {0, 360};
    case Coordinate::Radius: return {rMin, rMax};
    case Coordinate::Depth: return {kSurfaceRadiusKm - rMax, kSurfaceRadiusKm - rMin};
    }
    return {};
}

}  // namespace raypc::grid
