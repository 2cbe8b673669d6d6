#include "render/resolve_state.h"

#include "core/error.h"
#include "state/test_states.h"
#include "state/color_maps.h"
#include "render/transfer_function.h"

#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>

namespace raypc::render {
namespace {

using nlohmann::json;
using state::parseRenderState;
using state::RenderState;
using state::testing::refusalOf;

TEST(RenderState, ResolvesNamesAndRejectsUnknownOnes)
{
    const VariableCatalog catalog{{"temperature", "temperature anomaly"}, {{1000, 4000}, {-500, 200}}, {}};
    RenderState s;
    s.colorVariable = "temperature anomaly";
    s.colorMap = ColorMapId::BlueWhiteRed;
    s.brushes = {{"temperature", 1500, 2500}, {"lat", -30, 30}};
    const RenderParams p = resolveParams(s, catalog);
    EXPECT_EQ(p.colorVariable, 1);
    EXPECT_FLOAT_EQ(p.transfer.range.min, -500);  // centred map: symmetric default range
    EXPECT_FLOAT_EQ(p.transfer.range.max, 500);
    ASSERT_EQ(p.brushes.size(), 2u);
    EXPECT_EQ(p.brushes[0].variable, 0);
    EXPECT_EQ(*p.brushes[1].coordinate, grid::Coordinate::Lat);
    s.brushes = {{"pressure", 0, 1}};
    try {
        resolveParams(s, catalog);
        FAIL();
    } catch (const Error& e) {
        EXPECT_NE(std::string(e.what()).find("'pressure'"), std::string::npos);
    }
    s.brushes.clear();
    s.colorVariable = "nope";
    EXPECT_THROW(resolveParams(s, catalog), Error);
}

// Version 4: a brush name that repeats adds a range to its axis; the document round-trips as
// written; an older document repeating a name (which meant the intersection) is refused.
TEST(RenderState, RepeatedBrushNamesAreRangesOfOneAxis)
{
    const VariableCatalog catalog{{"temperature"}, {{1000, 4000}}, {}};
    const json doc = json::parse(R"({"version": 4, "brushes": [{"name": "depth", "min": 0, "max": 660},
        {"name": "temperature", "min": 1500, "max": 2500}, {"name": "depth", "min": 1500, "max": 2000}],
        "pathlines": {"filters": [{"name": "length", "min": 0, "max": 10}, {"name": "length", "min": 50, "max": 60}]}})");
    const RenderState s = parseRenderState(doc);
    ASSERT_EQ(s.brushes.size(), 3u);
    EXPECT_EQ(toJson(s)["brushes"], doc["brushes"]);
    EXPECT_EQ(toJson(s)["pathlines"]["filters"], doc["pathlines"]["filters"]);
    const RenderParams p = resolveParams(s, catalog);
    ASSERT_EQ(p.brushes.size(), 2u);
    EXPECT_EQ(*p.brushes[0].coordinate, grid::Coordinate::Depth);
    ASSERT_EQ(p.brushes[0].ranges.size(), 2u);
    EXPECT_FLOAT_EQ(p.brushes[0].ranges[1].min, 1500);
    EXPECT_EQ(p.brushes[1].variable, 0);

    json old = doc;
    old["version"] = 3;
    EXPECT_EQ(refusalOf(old), "STATE.json: brushes[2]: a second range on 'depth' needs version 4 (ranges on one axis are "
                            "OR-ed), the document says version 3");
    old["brushes"].erase(2);
    EXPECT_EQ(refusalOf(old), "STATE.json: pathlines.filters[1]: a second range on 'length' needs version 4 (ranges on one "
                            "axis are OR-ed), the document says version 3");
    old["pathlines"]["filters"].erase(1);
    EXPECT_EQ(refusalOf(old), "accepted");

    json reversed = doc;
    reversed["brushes"][2]["min"] = 3000;
    EXPECT_EQ(refusalOf(reversed), "STATE.json: brushes[2].min: min 3000 is greater than max 2000");
}

// Version 4: the UI's axes in display order round-trip; null is the UI's default; a name twice, an
// empty name or a version-3 document with axes are refused naming the key.
TEST(RenderState, DefaultOpacityIsAVForMapsCentredOnZero)
{
    const VariableCatalog catalog{{"temperature anomaly"}, {{-500, 200}}, {}};
    RenderState s = parseRenderState(json{{"version", 1}, {"color", {{"colorMap", "blue-white-red"}}}});
    EXPECT_TRUE(s.opacity.empty());
    const TransferFunction tf = resolveParams(s, catalog).transfer;
    auto opacityAt = [&](float position) {
        const auto& o = tf.opacity;
        for (size_t i = 1; i < o.size(); ++i)
            if (position <= o[i].position)
                return o[i - 1].opacity + (position - o[i - 1].position) / (o[i].position - o[i - 1].position) *
                                              (o[i].opacity - o[i - 1].opacity);
        return o.back().opacity;
    };
    EXPECT_FLOAT_EQ(opacityAt(0.5f), 0.0f);  // value 0: transparent
    EXPECT_FLOAT_EQ(opacityAt(0.0f), opacityAt(1.0f));  // equal magnitudes, equal opacity
    EXPECT_GT(opacityAt(0.0f), 0.0f);
    // Other maps keep the ramp; an explicit opacity is kept; toJson writes the effective default.
    s.colorMap = ColorMapId::Viridis;
    EXPECT_FLOAT_EQ(resolveParams(s, catalog).transfer.opacity.front().opacity, 0.0f);
    s.colorMap = ColorMapId::BlueWhiteRed;
    EXPECT_EQ(toJson(s)["color"]["opacity"].size(), 3u);
    s.opacity = {{0, 0.2f}, {1, 0.2f}};
    EXPECT_FLOAT_EQ(resolveParams(s, catalog).transfer.opacity[0].opacity, 0.2f);
}
// The first view shows what the dataset has: the temperature anomaly, else the first variable's shell
// anomaly (a tomography model's vs), else the first variable.
TEST(RenderState, DefaultViewIsTheTemperatureAnomalyElseTheFirstVariablesAnomaly)
{
    VariableCatalog tomography;
    tomography.names = {"vs", "vs anomaly", "vs anomaly %"};
    tomography.ranges = {{4.3f, 6.5f}, {-0.1f, 0.1f}, {-2.3f, 2.3f}};
    EXPECT_EQ(defaultState(tomography).colorVariable, "vs anomaly");
    EXPECT_EQ(defaultState(tomography).colorMap, ColorMapId::BlueWhiteRed);  // either side of zero

    VariableCatalog flow;  // the velocity first: it has no anomaly
    flow.names = {"vx", "vy", "vz", "viscosity", "radial velocity", "viscosity anomaly", "viscosity anomaly %"};
    flow.ranges.assign(flow.names.size(), {-1.0f, 1.0f});
    EXPECT_EQ(defaultState(flow).colorVariable, "viscosity anomaly");

    VariableCatalog contest;
    contest.names = {"temperature", "thermal conductivity", "temperature anomaly", "thermal conductivity anomaly"};
    contest.ranges.assign(contest.names.size(), {-1.0f, 1.0f});
    EXPECT_EQ(defaultState(contest).colorVariable, "temperature anomaly");

    VariableCatalog plain;
    plain.names = {"density"};
    plain.ranges = {{3000.0f, 5000.0f}};
    EXPECT_EQ(defaultState(plain).colorVariable, "density");
}
// One default colour range per variable, so that a preset and the default view never show one
// variable over two ranges: the default view and a preset that names no
// range resolve to the same one, render::defaultColorRange of the variable's statistics (robust and
// symmetric for centred maps); a document naming a range keeps it.
TEST(RenderState, TheDefaultViewAndThePresetsShareTheDefaultRange)
{
    VariableCatalog catalog;
    catalog.names = {"temperature", "temperature anomaly"};
    catalog.ranges = {{1000, 4000}, {-269.8f, 451.8f}};
    std::vector<double> h(dataset::kHistogramBins, 0.0);
    const double width = (451.8 + 269.8) / dataset::kHistogramBins;
    for (int i = 0; i < dataset::kHistogramBins; ++i)
        h[size_t(i)] = std::abs(-269.8 + width * (i + 0.5)) < 190 ? 1.0 : 0.002;
    catalog.histograms = {std::vector<double>(dataset::kHistogramBins, 1.0 / dataset::kHistogramBins), h};
    const RenderState first = defaultState(catalog);
    EXPECT_EQ(first.colorVariable, "temperature anomaly");
    EXPECT_FALSE(first.colorRange.has_value()) << "the default view names a range of its own";
    const dataset::ValueRange viewRange = resolveParams(first, catalog).transfer.range;
    EXPECT_FLOAT_EQ(viewRange.min, -200);
    EXPECT_FLOAT_EQ(viewRange.max, 200);
    const RenderState preset = parseRenderState(json{
        {"version", 3}, {"color", {{"variable", "temperature anomaly"}, {"colorMap", "blue-white-red"}}}});
    const dataset::ValueRange presetRange = resolveParams(preset, catalog).transfer.range;
    EXPECT_FLOAT_EQ(presetRange.min, viewRange.min);
    EXPECT_FLOAT_EQ(presetRange.max, viewRange.max);
    const RenderState stored = parseRenderState(json{
        {"version", 3},
        {"color", {{"variable", "temperature anomaly"}, {"colorMap", "blue-white-red"}, {"range", {-300, 300}}}}});
    EXPECT_FLOAT_EQ(resolveParams(stored, catalog).transfer.range.max, 300);
}

// The presets take the default range: none of the example states with a map centred on zero names
// a colour range of its own (it would differ from the default view's, as ±300 K did from ±451.8 K).
TEST(RenderState, PresetsOnCentredMapsNameNoColourRange)
{
    int checked = 0;
    for (const auto& entry : std::filesystem::directory_iterator(std::filesystem::path(RAYPC_SOURCE_DIR) / "examples")) {
        if (entry.path().extension() != ".json")
            continue;
        std::ifstream in(entry.path());
        const json doc = json::parse(in);
        if (!doc.contains("color"))
            continue;
        const json& color = doc["color"];
        const ColorMapId map = state::parseColorMap(color.value("colorMap", "viridis"));
        if (!state::isCentredOnZero(map))
            continue;
        ++checked;
        EXPECT_FALSE(color.contains("range")) << entry.path().filename() << " names color.range " << color["range"];
    }
    EXPECT_GE(checked, 9);
}

}  // namespace
}  // namespace raypc::render
