#include "state/state_schema.h"

#include "core/error.h"
#include "state/render_state.h"
#include "state/test_states.h"

#include <gtest/gtest.h>

namespace raypc::state {
namespace {

using nlohmann::json;
using testing::refusalOf;

// Every key toJson writes is in the schema with toJson(RenderState{})'s value as its default, and
// in the docs table; the schema has no key toJson does not write.
void expectDescribed(const json& written, const json& schema, const std::string& path, const std::string& table)
{
    ASSERT_TRUE(schema.contains("properties")) << path;
    EXPECT_EQ(schema["properties"].size(), written.size()) << path;
    for (auto it = written.begin(); it != written.end(); ++it) {
        const std::string key = path.empty() ? it.key() : path + "." + it.key();
        ASSERT_TRUE(schema["properties"].contains(it.key())) << key << " is written by toJson but not in the schema";
        const json& property = schema["properties"][it.key()];
        EXPECT_TRUE(property.contains("description")) << key;
        if (it->is_object()) {
            expectDescribed(*it, property, key, table);
        } else {
            EXPECT_NE(table.find("| `" + key + "` |"), std::string::npos) << key << " has no row in the table";
            if (key != "version") {
                EXPECT_EQ(property.value("default", json()), *it) << key;
            }
        }
    }
}

TEST(StateSchema, DescribesEveryKeyWithItsDefault)
{
    const json schema = stateJsonSchema();
    EXPECT_EQ(schema["required"], json::array({"version"}));
    EXPECT_FALSE(schema["additionalProperties"].get<bool>());
    expectDescribed(toJson(RenderState{}), schema, "", stateFieldTable());
}

TEST(StateSchema, CarriesTheParsersBoundsAndVersions)
{
    const json schema = stateJsonSchema();
    const json& camera = schema["properties"]["camera"]["properties"];
    EXPECT_EQ(camera["elevationDeg"]["minimum"], -90);
    EXPECT_EQ(camera["elevationDeg"]["maximum"], 90);
    EXPECT_EQ(schema["properties"]["version"]["enum"], json::array({1, 2, 3, 4, 5, 6, 7, 8, 9, 10, 11, 12, 13}));
    EXPECT_EQ(kRenderStateVersion, 13);
    EXPECT_EQ(schema["properties"]["brushes"]["items"]["required"], json::array({"name", "min", "max"}));
    // A version-1 document may not have pathlines, as parseRenderState says.
    ASSERT_TRUE(schema.contains("allOf"));
    EXPECT_EQ(schema["allOf"][0]["if"]["properties"]["version"]["const"], 1);
    EXPECT_EQ(schema["allOf"][0]["then"]["properties"]["pathlines"]["description"], "needs version 2");
    EXPECT_THROW(parseRenderState(json{{"version", 1}, {"pathlines", json::object()}}), Error);
    // Version 3 added the reference geometry and the legend: refused in a version-2 document.
    EXPECT_EQ(schema["allOf"][1]["if"]["properties"]["version"]["const"], 2);
    EXPECT_EQ(schema["allOf"][1]["then"]["properties"]["reference"]["description"], "needs version 3");
    EXPECT_THROW(parseRenderState(json{{"version", 2}, {"legend", true}}), Error);
    // Version 5 added stereo.
    EXPECT_EQ(schema["allOf"][3]["if"]["properties"]["version"]["const"], 4);
    EXPECT_EQ(schema["allOf"][3]["then"]["properties"]["stereo"]["description"], "needs version 5");
    // Version 6 added the shadows: refused in a version-5 document, naming the key.
    EXPECT_EQ(schema["allOf"][4]["if"]["properties"]["version"]["const"], 5);
    EXPECT_EQ(schema["allOf"][4]["then"]["properties"]["shading"]["properties"]["shadows"]["description"],
              "needs version 6");
    try {
        parseRenderState(json::parse(R"({"version": 5, "shading": {"shadows": true}})"));
        ADD_FAILURE() << "a version-5 document with shading.shadows was accepted";
    } catch (const Error& e) {
        EXPECT_NE(std::string(e.what()).find("shading.shadows"), std::string::npos) << e.what();
    }
    // Version 8 added "show the selection": refused in a version-7 document, read in a version-8 one.
    EXPECT_EQ(schema["allOf"][6]["if"]["properties"]["version"]["const"], 7);
    EXPECT_EQ(schema["allOf"][6]["then"]["properties"]["selection"]["description"], "needs version 8");
    EXPECT_THROW(parseRenderState(json::parse(R"({"version": 7, "selection": {"show": true}})")), Error);
    EXPECT_THROW(parseRenderState(json::parse(R"({"version": 8, "selection": {"minOpacity": 1.5}})")), Error);
    const RenderState shown = parseRenderState(json::parse(R"({"version": 8, "selection": {"show": true, "minOpacity": 0.3}})"));
    EXPECT_TRUE(shown.selection.show);
    EXPECT_FLOAT_EQ(shown.selection.minOpacity, 0.3f);
    EXPECT_FALSE(RenderState{}.selection.show);
    const RenderState s = parseRenderState(json::parse(
        R"({"version": 3, "legend": true, "reference": {"shells": {"visible": true, "depthsKm": [660]}, "lineWidthPx": 2}})"));
    EXPECT_TRUE(s.legend);
    EXPECT_TRUE(s.reference.shells.visible);
    EXPECT_EQ(s.reference.shells.depthsKm, std::vector<float>{660.0f});
    EXPECT_FLOAT_EQ(s.reference.lineWidthPx, 2.0f);
    EXPECT_THROW(parseRenderState(json::parse(R"({"version": 3, "reference": {"shells": {"depthsKm": [-5]}}})")), Error);
    EXPECT_THROW(parseRenderState(json::parse(R"({"version": 3, "reference": {"graticule": {"spacingDeg": 0}}})")), Error);
    EXPECT_THROW(parseRenderState(json::parse(R"({"version": 3, "reference": {"moon": {}}})")), Error);
}

TEST(StateSchema, NullKeepsTheDefaultOfStringKeys)
{
    // Strings the schema allows to be null ("the default") parse to the default.
    const RenderState s = parseRenderState(json::parse(
        R"({"version": 2, "color": {"variable": null}, "core": {"variable": null}, "pathlines": {"colorBy": null, "colorMap": null}})"));
    EXPECT_EQ(s.colorVariable, "");
    EXPECT_EQ(s.core.variable, "");
    EXPECT_EQ(s.pathlines.colorBy, "age");
    EXPECT_FALSE(s.pathlines.colorMap.has_value());
    const json schema = stateJsonSchema();
    const json& pl = schema["properties"]["pathlines"]["properties"];
    EXPECT_EQ(pl["colorBy"]["type"], json::array({"string", "null"}));
    EXPECT_EQ(pl["colorMap"]["enum"].back(), nullptr);
}

TEST(StateSchema, ShadowsRoundTripAndBadValuesNameTheKey)
{
    const RenderState s = parseRenderState(json::parse(R"({"version": 6, "shading": {"shadows": true, "shadowStrength": 0.6}})"));
    EXPECT_TRUE(s.shading.shadows);
    EXPECT_FLOAT_EQ(s.shading.shadowStrength, 0.6f);
    const RenderState back = parseRenderState(toJson(s));
    EXPECT_TRUE(back.shading.shadows);
    EXPECT_FLOAT_EQ(back.shading.shadowStrength, 0.6f);
    EXPECT_FALSE(parseRenderState(json{{"version", 6}}).shading.shadows);  // off unless asked for
    auto refusal = [](const char* text) { return refusalOf(json::parse(text)); };
    EXPECT_NE(refusal(R"({"version": 6, "shading": {"shadowStrength": 1.5}})").find("shading.shadowStrength"), std::string::npos);
    EXPECT_NE(refusal(R"({"version": 6, "shading": {"shadowStrength": -0.1}})").find("shading.shadowStrength"), std::string::npos);
    EXPECT_NE(refusal(R"({"version": 6, "shading": {"shadows": "yes"}})").find("shading.shadows"), std::string::npos);
}

// Version 10: the feature settings round-trip; bad values and a version-9 document with them are
// refused naming the key.
TEST(StateSchema, FeatureSettingsRoundTripAndBadValuesNameTheKey)
{
    const RenderState s = parseRenderState(json::parse(
        R"({"version": 10, "features": {"minVolumeKm3": 1e7, "depthsKm": [660, 1600], "bandHalfWidthKm": 80, "level": 1, "minOverlapShare": 0.3}})"));
    EXPECT_FLOAT_EQ(s.features.minVolumeKm3, 1e7f);
    EXPECT_EQ(s.features.depthsKm, (std::vector<float>{660, 1600}));
    EXPECT_FLOAT_EQ(s.features.bandHalfWidthKm, 80);
    EXPECT_EQ(s.features.level, 1);
    EXPECT_FLOAT_EQ(s.features.minOverlapShare, 0.3f);
    const RenderState back = parseRenderState(toJson(s));
    EXPECT_EQ(back.features.depthsKm, s.features.depthsKm);
    EXPECT_EQ(back.features.level, 1);
    // Version 12: which depth times the stalls.
    const RenderState deepest = parseRenderState(json::parse(R"({"version": 12, "features": {"stallBy": "deepest"}})"));
    EXPECT_EQ(deepest.features.stallBy, analysis::StallMeasure::Deepest);
    EXPECT_EQ(parseRenderState(toJson(deepest)).features.stallBy, analysis::StallMeasure::Deepest);
    EXPECT_EQ(s.features.stallBy, analysis::StallMeasure::MeanDepth) << "the default";
    EXPECT_THROW(parseRenderState(json::parse(R"({"version": 11, "features": {"stallBy": "deepest"}})")), Error);
    EXPECT_THROW(parseRenderState(json::parse(R"({"version": 12, "features": {"stallBy": "tip"}})")), Error);
    const RenderState plain = parseRenderState(json{{"version", 9}});  // the defaults
    EXPECT_EQ(plain.features.depthsKm, (std::vector<float>{410, 660, 1000, 1600}));
    EXPECT_FLOAT_EQ(plain.features.bandHalfWidthKm, 50);
    auto refusal = [](const char* text) { return refusalOf(json::parse(text)); };
    EXPECT_NE(refusal(R"({"version": 10, "features": {"level": 3}})").find("features.level"), std::string::npos);
    EXPECT_NE(refusal(R"({"version": 10, "features": {"minVolumeKm3": -1}})").find("features.minVolumeKm3"), std::string::npos);
    EXPECT_NE(refusal(R"({"version": 10, "features": {"depthsKm": [7000]}})").find("features.depthsKm"), std::string::npos);
    EXPECT_NE(refusal(R"({"version": 9, "features": {"level": 0}})").find("features"), std::string::npos);
}

// Version 13: a pair of datasets (docs/compare.md) round-trips, null is one dataset, bad ones are
// refused naming the key.
TEST(StateSchema, PairRoundTripsAndBadPairsAreRefused)
{
    EXPECT_FALSE(RenderState{}.pair.has_value());
    EXPECT_TRUE(toJson(RenderState{})["pair"].is_null());
    const RenderState s = parseRenderState(json::parse(R"({"version": 13, "pair": {"dataset": "runs/b.raypc", "steps": "index"}})"));
    ASSERT_TRUE(s.pair.has_value());
    EXPECT_EQ(s.pair->dataset, "runs/b.raypc");
    EXPECT_EQ(s.pair->steps, PairSteps::Index);
    const RenderState back = parseRenderState(toJson(s));
    ASSERT_TRUE(back.pair.has_value());
    EXPECT_EQ(back.pair->dataset, "runs/b.raypc");
    EXPECT_EQ(back.pair->steps, PairSteps::Index);
    EXPECT_EQ(parseRenderState(json::parse(R"({"version": 13, "pair": {"dataset": "b"}})")).pair->steps, PairSteps::Time)
        << "the default";
    EXPECT_FALSE(parseRenderState(json::parse(R"({"version": 13, "pair": null})")).pair.has_value());
    auto refusal = [](const char* text) { return refusalOf(json::parse(text)); };
    EXPECT_NE(refusal(R"({"version": 12, "pair": {"dataset": "b"}})").find("pair: needs version 13"), std::string::npos);
    EXPECT_NE(refusal(R"({"version": 13, "pair": {"steps": "time"}})").find("pair.dataset: missing"), std::string::npos);
    EXPECT_NE(refusal(R"({"version": 13, "pair": {"dataset": ""}})").find("pair.dataset"), std::string::npos);
    EXPECT_NE(refusal(R"({"version": 13, "pair": {"dataset": "b", "steps": "seconds"}})").find("pair.steps"), std::string::npos);
    EXPECT_NE(refusal(R"({"version": 13, "pair": "b"})").find("pair: expected an object or null"), std::string::npos);
}

// Version 7: explicit camera views (WebXR eyes) round-trip; bad ones are refused naming the key.
TEST(StateSchema, CameraViewsRoundTripAndBadViewsAreRefused)
{
    const json view = json::parse(R"({"positionKm": [20000, -5, 7.5], "orientation": [0.5, 0.5, 0.5, 0.5],
                                      "frustum": [-0.25, 0.5, -0.125, 0.375]})");  // exact in float32
    json doc{{"version", 7}, {"camera", {{"views", json::array({view})}}}};
    const RenderState s = parseRenderState(doc);
    ASSERT_EQ(s.camera.views.size(), 1u);
    EXPECT_EQ(s.camera.views[0].positionKm.y, -5.0f);
    EXPECT_EQ(s.camera.views[0].orientation[3], 0.5f);
    EXPECT_EQ(s.camera.views[0].frustum[1], 0.5f);
    const json written = toJson(s)["camera"]["views"];
    EXPECT_EQ(written, json::array({view})) << written.dump();
    EXPECT_EQ(parseRenderState(toJson(s)).camera.views.size(), 1u);
    EXPECT_EQ(toJson(RenderState{})["camera"]["views"], json::array());  // the orbit camera
    // Two views: a stereo pair's eyes, only with stereo on; one view only without.
    json pair = doc;
    pair["camera"]["views"] = json::array({view, view});
    EXPECT_NE(refusalOf(pair).find("camera.views: 2 views with stereo.mode \"off\""), std::string::npos)
        << refusalOf(pair);
    pair["stereo"] = {{"mode", "side-by-side"}};
    EXPECT_EQ(parseRenderState(pair).camera.views.size(), 2u);
    doc["stereo"] = {{"mode", "anaglyph"}};
    EXPECT_NE(refusalOf(doc).find("camera.views"), std::string::npos);
    doc.erase("stereo");
    // Older documents have no views.
    doc["version"] = 6;
    EXPECT_NE(refusalOf(doc).find("camera.views: needs version 7"), std::string::npos) << refusalOf(doc);
    doc["version"] = 7;
    // A quaternion that is not a unit beyond the tolerance; one within it is accepted.
    doc["camera"]["views"][0]["orientation"] = {0.5, 0.5, 0.5, 0.51};
    EXPECT_NE(refusalOf(doc).find("camera.views[0]: camera view orientation"), std::string::npos) << refusalOf(doc);
    EXPECT_NE(refusalOf(doc).find("expected a unit quaternion"), std::string::npos);
    doc["camera"]["views"][0]["orientation"] = {0.5, 0.5, 0.5, 0.5004};
    EXPECT_EQ(refusalOf(doc), "accepted");
    doc["camera"]["views"][0]["orientation"] = {0, 0, 0, 0};
    EXPECT_NE(refusalOf(doc).find("expected a unit quaternion"), std::string::npos);
    doc["camera"]["views"][0]["orientation"] = {0.5, 0.5, 0.5, 0.5};
    // Degenerate frusta: left >= right, down >= up.
    for (const json& frustum : {json{0.5, -0.2, -0.1, 0.4}, json{0.3, 0.3, -0.1, 0.4}, json{-0.2, 0.5, 0.4, 0.4}}) {
        doc["camera"]["views"][0]["frustum"] = frustum;
        EXPECT_NE(refusalOf(doc).find("camera.views[0]: camera view frustum"), std::string::npos) << refusalOf(doc);
        EXPECT_NE(refusalOf(doc).find("left < right, down < up"), std::string::npos);
    }
    doc["camera"]["views"][0]["frustum"] = {-0.2, 0.5, -0.1};
    EXPECT_NE(refusalOf(doc).find("camera.views[0].frustum: expected an array of 4 numbers"), std::string::npos)
        << refusalOf(doc);
    doc["camera"]["views"][0].erase("frustum");
    EXPECT_NE(refusalOf(doc).find("camera.views[0].frustum: missing"), std::string::npos) << refusalOf(doc);
}

}  // namespace
}  // namespace raypc::state
