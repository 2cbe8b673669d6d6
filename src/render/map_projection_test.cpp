// The map projections against d3-geo and d3-geo-projection's values at the same points
// (tests/data/projections/d3-projections.json, written once by node from the UI's packages).
#include "render/map_projection.h"

#include "core/error.h"

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include <cmath>
#include <fstream>

namespace raypc::render {
namespace {

nlohmann::json d3Cases()
{
    std::ifstream in(std::string(RAYPC_SOURCE_DIR) + "/tests/data/projections/d3-projections.json");
    EXPECT_TRUE(in.good()) << "tests/data/projections/d3-projections.json is missing";
    return nlohmann::json::parse(in)["cases"];
}

// The angular distance between two points, degrees.
double degreesApart(double lon1, double lat1, double lon2, double lat2)
{
    const double r = M_PI / 180;
    const double c = std::sin(lat1 * r) * std::sin(lat2 * r) + std::cos(lat1 * r) * std::cos(lat2 * r) * std::cos((lon1 - lon2) * r);
    return std::acos(std::clamp(c, -1.0, 1.0)) / r;
}

TEST(MapProjection, ForwardEqualsD3)
{
    size_t compared = 0;
    for (const auto& c : d3Cases()) {
        const Projector p(state::parseMapProjection(c["projection"].get<std::string>()), c["centralMeridianDeg"], c["centralLatitudeDeg"]);
        for (const auto& f : c["forward"]) {
            const double lon = f[0], lat = f[1], x = f[2], y = f[3];
            const auto xy = p.forward(lon, lat);
            ASSERT_TRUE(xy) << c["projection"] << " hides " << lon << ", " << lat << ", which d3 shows";
            // d3's Mollweide stops its Newton iteration short at the poles, whose x is 0: 2e-5 off.
            const double tolerance = std::abs(lat) == 90 && c["projection"] == "mollweide" ? 1e-4 : 1e-9;
            // On the antimeridian of the centre a point may go to either edge.
            const bool onSeam = std::abs(std::abs(std::remainder(lon - double(c["centralMeridianDeg"]), 360.0)) - 180) < 1e-9;
            if (onSeam)
                EXPECT_NEAR(std::abs((*xy)[0]), std::abs(x), tolerance) << c["projection"] << " |x| at " << lon << ", " << lat;
            else
                EXPECT_NEAR((*xy)[0], x, tolerance) << c["projection"] << " x at " << lon << ", " << lat << " centre " << c["centralMeridianDeg"];
            EXPECT_NEAR((*xy)[1], y, 1e-9) << c["projection"] << " y at " << lon << ", " << lat << " centre " << c["centralMeridianDeg"];
            ++compared;
        }
    }
    EXPECT_GT(compared, 800u);
}

TEST(MapProjection, InverseEqualsD3AndUndoesForward)
{
    size_t compared = 0;
    for (const auto& c : d3Cases()) {
        const Projector p(state::parseMapProjection(c["projection"].get<std::string>()), c["centralMeridianDeg"], c["centralLatitudeDeg"]);
        for (const auto& f : c["inverse"]) {
            const double x = f[0], y = f[1], lon = f[2], lat = f[3];
            const auto ll = p.inverse(x, y);
            ASSERT_TRUE(ll) << c["projection"] << " finds nothing at " << x << ", " << y;
            // d3's Robinson inverse stops at 1e-12 of its iteration: about 1e-7 degrees.
            EXPECT_LT(degreesApart((*ll)[0], (*ll)[1], lon, lat), 1e-6) << c["projection"] << " at " << x << ", " << y;
            ++compared;
        }
        for (const auto& f : c["forward"]) {
            const double lon = f[0], lat = f[1];
            const auto ll = p.inverse(f[2], f[3]);
            ASSERT_TRUE(ll) << c["projection"] << " finds nothing at the image of " << lon << ", " << lat;
            EXPECT_LT(degreesApart((*ll)[0], (*ll)[1], lon, lat), 1e-6) << c["projection"] << " round trip of " << lon << ", " << lat;
        }
    }
    EXPECT_GT(compared, 600u);
}

TEST(MapProjection, OutsideTheSphereIsNothing)
{
    for (MapProjection m : state::allMapProjections()) {
        const Projector p(m, 0);
        const auto e = p.extent();
        EXPECT_FALSE(p.inverse(e.xMax * 1.01, 0)) << state::mapProjectionName(m);
        EXPECT_FALSE(p.inverse(0, e.yMax * 1.01)) << state::mapProjectionName(m);
        EXPECT_TRUE(p.inverse(0.99 * e.xMax, 0)) << state::mapProjectionName(m);
        // Corners lie outside every projection but the equirectangular one.
        EXPECT_EQ(bool(p.inverse(0.99 * e.xMax, 0.99 * e.yMax)), m == MapProjection::Equirectangular) << state::mapProjectionName(m);
    }
    EXPECT_FALSE(Projector(MapProjection::Orthographic, 0).forward(180, 0));
    EXPECT_THROW(state::parseMapProjection("mercator"), Error);
    EXPECT_THROW(Projector(MapProjection::Hammer, 200), Error);
}

}  // namespace
}  // namespace raypc::render
