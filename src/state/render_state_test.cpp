#include "state/render_state.h"

#include "core/error.h"
#include "state/test_states.h"

#include <gtest/gtest.h>

namespace raypc::state {
namespace {

using nlohmann::json;
using testing::refusalOf;

TEST(RenderState, RoundTripsThroughJson)
{
    RenderState s;
    s.camera.azimuthDeg = 12;
    s.width = 300;
    s.colorVariable = "temperature anomaly";
    s.colorMap = ColorMapId::BlueWhiteRed;
    s.colorRange = dataset::ValueRange{-300, 300};
    s.brushes = {{"temperature", 1000, 2000}, {"depth", 0, 660}};
    s.level = 1;
    s.core.variable = "temperature";
    s.shading.enabled = true;
    const RenderState t = parseRenderState(toJson(s));
    EXPECT_EQ(toJson(t), toJson(s));
    EXPECT_EQ(t.brushes.size(), 2u);
    EXPECT_EQ(*t.level, 1);
    RenderState autoLevel;
    EXPECT_FALSE(parseRenderState(toJson(autoLevel)).level.has_value());
}

TEST(RenderState, UnknownKeysAndBadValuesNameTheKey)
{
    json j = toJson(RenderState{});
    j["camera"]["zoom"] = 2;
    EXPECT_NE(refusalOf(j).find("camera.zoom: unknown key"), std::string::npos) << refusalOf(j);
    j = toJson(RenderState{});
    j["camera"]["distanceKm"] = -3;
    EXPECT_NE(refusalOf(j).find("camera.distanceKm"), std::string::npos) << refusalOf(j);
    j = toJson(RenderState{});
    j["color"]["colorMap"] = "rainbow";
    EXPECT_NE(refusalOf(j).find("color.colorMap"), std::string::npos) << refusalOf(j);
    j = toJson(RenderState{});
    j["brushes"] = json::array({{{"name", "x"}, {"min", 3}, {"max", 1}}});
    EXPECT_NE(refusalOf(j).find("brushes[0].min"), std::string::npos) << refusalOf(j);
    j = toJson(RenderState{});
    j.erase("version");
    EXPECT_NE(refusalOf(j).find("version"), std::string::npos);
    j["version"] = 99;
    EXPECT_NE(refusalOf(j).find("not supported"), std::string::npos);
    j = toJson(RenderState{});
    j["level"] = 7;
    EXPECT_NE(refusalOf(j).find("level"), std::string::npos);
    // Finite in JSON but beyond float32 (a fuzzing finding: it became inf, written back as null).
    j = toJson(RenderState{});
    j["brushes"] = json::array({{{"name", "lat"}, {"min", -90}, {"max", 9e60}}});
    EXPECT_NE(refusalOf(j).find("brushes[0].max: 9e+60 is beyond the float32 range"), std::string::npos) << refusalOf(j);
    j = toJson(RenderState{});
    j["color"]["range"] = json::array({-1e30, 1e60});
    EXPECT_NE(refusalOf(j).find("color.range"), std::string::npos) << refusalOf(j);
}

TEST(RenderState, AxesRoundTripAndAreChecked)
{
    EXPECT_EQ(toJson(RenderState{})["axes"], nullptr);
    const json doc = json::parse(R"({"version": 4, "axes": ["depth", "temperature", "radius"]})");
    const RenderState s = parseRenderState(doc);
    ASSERT_TRUE(s.axes.has_value());
    EXPECT_EQ(*s.axes, (std::vector<std::string>{"depth", "temperature", "radius"}));
    EXPECT_EQ(toJson(s)["axes"], doc["axes"]);
    EXPECT_EQ(refusalOf(json::parse(R"({"version": 4, "axes": ["depth", "lat", "depth"]})")),
              "STATE.json: axes: expected each name once, found \"depth\" twice");
    EXPECT_EQ(refusalOf(json::parse(R"({"version": 4, "axes": ["depth", ""]})")),
              "STATE.json: axes: expected non-empty names, found \"\"");
    EXPECT_EQ(refusalOf(json::parse(R"({"version": 3, "axes": ["depth"]})")),
              "STATE.json: axes: needs version 4, the document says version 3");
    EXPECT_FALSE(parseRenderState(json::parse(R"({"version": 4, "axes": null})")).axes.has_value());
}
}  // namespace
}  // namespace raypc::state
