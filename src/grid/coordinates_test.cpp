// The one definition of the coordinates (grid/coordinates.h) and the one brush resolver
// (analysis/selection.h): analytic values, the lon seam, ranges on a grid, and the resolver's messages.
#include "core/error.h"
#include "grid/coordinates.h"
#include "analysis/selection.h"

#include <gtest/gtest.h>

#include <cmath>

namespace raypc::grid {
namespace {

TEST(Coordinates, ValuesAtKnownPoints)
{
    // On the equator at lon 90° the point lies on +y.
    EXPECT_NEAR(coordinateValue(Coordinate::X, 0, 90, 5000), 0.0, 1e-9);
    EXPECT_NEAR(coordinateValue(Coordinate::Y, 0, 90, 5000), 5000.0, 1e-9);
    EXPECT_NEAR(coordinateValue(Coordinate::Z, 90, 0, 4000), 4000.0, 1e-9);
    EXPECT_NEAR(coordinateValue(Coordinate::Z, -30, 123, 6000), -3000.0, 1e-9);
    EXPECT_DOUBLE_EQ(coordinateValue(Coordinate::Depth, 12, 34, 5711), 660.0);
    EXPECT_DOUBLE_EQ(coordinateValue(Coordinate::Radius, 12, 34, 5711), 5711.0);
    EXPECT_DOUBLE_EQ(coordinateValue(Coordinate::Lat, -45, 34, 5711), -45.0);
    // Lon is reported in [0, 360) whatever the caller passes (the seam).
    EXPECT_DOUBLE_EQ(coordinateValue(Coordinate::Lon, 0, -10, 5000), 350.0);
    EXPECT_DOUBLE_EQ(coordinateValue(Coordinate::Lon, 0, 360, 5000), 0.0);
    EXPECT_NEAR(coordinateValue(Coordinate::X, 0, -10, 5000), coordinateValue(Coordinate::X, 0, 350, 5000), 1e-9);
}

TEST(Coordinates, DefinitionsAreAffineInOneComponent)
{
    // What the kernels apply: scale * component + offset equals coordinateValue.
    const double lat = 37, lon = 211, r = 5123;
    const Vec3d p = sphericalToCartesianKm(lat, lon, r);
    for (const auto& info : coordinateInfos()) {
        const CoordinateDefinition d = coordinateDefinition(info.id);
        const double component[] = {p.x, p.y, p.z, lat, lon, r};
        EXPECT_NEAR(d.scale * component[int(d.component)] + d.offset, coordinateValue(info.id, lat, lon, r), 1e-9)
            << info.name;
    }
}

TEST(Coordinates, RangesCoverTheShellOfTheGrid)
{
    SphericalGrid g;
    g.latDeg = {-60, 0, 60};
    g.rKm = {3485, 5000, 6371};
    g.lonDeg = {0, 120, 240};
    EXPECT_DOUBLE_EQ(coordinateRange(g, Coordinate::Depth).min, 0.0);
    EXPECT_DOUBLE_EQ(coordinateRange(g, Coordinate::Depth).max, 6371.0 - 3485.0);
    EXPECT_DOUBLE_EQ(coordinateRange(g, Coordinate::Radius).min, 3485.0);
    EXPECT_DOUBLE_EQ(coordinateRange(g, Coordinate::X).min, -6371.0);
    EXPECT_DOUBLE_EQ(coordinateRange(g, Coordinate::Lat).max, 90.0);  // the caps reach the poles
    EXPECT_DOUBLE_EQ(coordinateRange(g, Coordinate::Lon).max, 360.0);
}

// A regional grid's axes span its data: lat and lon the extent, x, y, z its points of data (here
// lat 0..60, lon 0..90 on radii 3485..6371: x = r cos lat cos lon from 0 to 6371, z up to 6371 sin 60).
TEST(Coordinates, ARegionalGridsRangesAreItsRegions)
{
    SphericalGrid g;
    g.latDeg = {-90, -30, 0, 30, 60, 90};
    g.rKm = {3485, 6371};
    g.lonDeg = {0, 45, 90, 180, 270};
    g.dataLatDeg = std::array<double, 2>{0, 60};
    g.dataLonDeg = std::array<double, 2>{0, 90};
    EXPECT_DOUBLE_EQ(coordinateRange(g, Coordinate::Lat).min, 0.0);
    EXPECT_DOUBLE_EQ(coordinateRange(g, Coordinate::Lat).max, 60.0);
    EXPECT_DOUBLE_EQ(coordinateRange(g, Coordinate::Lon).max, 90.0);
    EXPECT_NEAR(coordinateRange(g, Coordinate::X).max, 6371.0, 1e-9);
    EXPECT_NEAR(coordinateRange(g, Coordinate::X).min, 0.0, 1e-9);
    EXPECT_NEAR(coordinateRange(g, Coordinate::Z).max, 6371.0 * std::sqrt(3.0) / 2, 1e-9);
    EXPECT_NEAR(coordinateRange(g, Coordinate::Z).min, 0.0, 1e-9);
    // Across 0°: the whole lon axis.
    g.dataLonDeg = std::array<double, 2>{270, 45};
    EXPECT_DOUBLE_EQ(coordinateRange(g, Coordinate::Lon).min, 0.0);
    EXPECT_DOUBLE_EQ(coordinateRange(g, Coordinate::Lon).max, 360.0);
}

TEST(Brushes, OneResolverForVariablesAndCoordinates)
{
    const std::vector<std::string> names = {"temperature", "depth"};  // a variable shadows a coordinate
    const std::vector<analysis::NamedRange> ranges = {{"temperature", 1, 2}, {"lat", -10, 10}, {"depth", 0, 5}};
    const auto filters = analysis::resolveRangeFilters(std::span<const std::string>(names), ranges);
    ASSERT_EQ(filters.size(), 3u);
    EXPECT_EQ(filters[0].variable, 0);
    EXPECT_FALSE(filters[0].coordinate);
    EXPECT_EQ(filters[1].coordinate, Coordinate::Lat);
    EXPECT_EQ(filters[2].variable, 1);

    const std::vector<analysis::NamedRange> unknown = {{"lat", 0, 1}, {"pressure", 0, 1}};
    try {
        analysis::resolveRangeFilters(std::span<const std::string>(names), unknown, "brushes");
        FAIL() << "an unknown name was accepted";
    } catch (const Error& e) {
        const std::string m = e.what();
        EXPECT_NE(m.find("brushes[1] (pressure): unknown variable or coordinate 'pressure'"), std::string::npos) << m;
        EXPECT_NE(m.find("variables: temperature, depth"), std::string::npos) << m;
        EXPECT_NE(m.find("coordinates: x, y, z, lat, lon, radius, depth"), std::string::npos) << m;
    }
    const std::vector<analysis::NamedRange> reversed = {{"lat", 5, 1}};
    EXPECT_THROW(analysis::resolveRangeFilters(std::span<const std::string>(names), reversed, "--range"), Error);
}

}  // namespace
}  // namespace raypc::grid
