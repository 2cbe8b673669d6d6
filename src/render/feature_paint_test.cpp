// The features painted in the 3D view (feature_paint.h): the slots of the grid points, the derived
// volume that carries them, and a picture of two blobs in their own colours.
#include "render/feature_paint.h"

#include "render/color_map.h"
#include "state/color_maps.h"

#include "core/error.h"
#include "analysis/features.h"
#include "render/test_volumes.h"
#include "render/volume_renderer.h"

#include <gtest/gtest.h>

#include <cmath>

namespace raypc::render {
namespace {

using testing::makeGrid;
using testing::makeVolume;

// Two Gaussian blobs at mid-mantle depth: a large one at (0°N, 90°E) and a smaller one across the
// seam at (0°N, 0°E); "r" the radius (km).
float twoBlobs(double lat, double r, double lon)
{
    auto blob = [&](double lat0, double lon0, double sigmaDeg) {
        double dLon = std::abs(lon - lon0);
        dLon = std::min(dLon, 360 - dLon);
        const double d2 = (lat - lat0) * (lat - lat0) + dLon * dLon;
        return std::exp(-d2 / (2 * sigmaDeg * sigmaDeg)) * std::exp(-std::pow((r - 4900) / 400, 2));
    };
    return float(std::max(blob(0, 90, 14), blob(0, 0, 9)));
}

TEST(FeaturePaint, SlotsFollowTheLabelsAndSpreadOnePointBeyondThem)
{
    const grid::SphericalGrid g = makeGrid(4, 3, 8);
    std::vector<int32_t> labels(g.cellCount(), 0);
    labels[g.index(1, 1, 0)] = 1;   // beside the seam: its neighbour across it is column 7
    labels[g.index(2, 1, 4)] = 12;  // id 12: slot 2
    state::FeatureSettings s;
    s.colorById = true;
    const std::vector<float> slots = featurePaintField(g, g, labels, s);
    EXPECT_EQ(slots[g.index(1, 1, 0)], 1.0f);
    EXPECT_EQ(slots[g.index(2, 1, 4)], 2.0f);
    EXPECT_EQ(slots[g.index(1, 1, 7)], 1.0f);  // across the seam
    EXPECT_EQ(slots[g.index(1, 2, 0)], 1.0f);  // one radius out
    EXPECT_EQ(slots[g.index(2, 1, 5)], 2.0f);
    EXPECT_EQ(slots[g.index(0, 0, 2)], 0.0f);  // far from both
    // Highlighted alone: 12 in its colour, 1 grey; without colorById the highlight is amber.
    s.highlight = {12};
    const std::vector<float> h = featurePaintField(g, g, labels, s);
    EXPECT_EQ(h[g.index(1, 1, 0)], 0.0f);
    EXPECT_EQ(h[g.index(2, 1, 4)], 2.0f);
    s.colorById = false;
    EXPECT_EQ(featurePaintField(g, g, labels, s)[g.index(2, 1, 4)], 11.0f);
    // A coarser target takes the nearest label point's label.
    grid::SphericalGrid coarse = makeGrid(2, 3, 4);  // lon 0, 90, 180, 270
    coarse.latDeg = {-20, 20};                 // nearest label rows: 1 (-22.5°) and 2 (22.5°)
    s.colorById = true;
    s.highlight.clear();
    const std::vector<float> c = featurePaintField(coarse, g, labels, s);
    EXPECT_EQ(c[coarse.index(0, 1, 0)], 1.0f);  // -20°, lon 0: nearest label point is (row 1, col 0)
    EXPECT_EQ(c[coarse.index(1, 1, 2)], 2.0f);  // +20°, lon 180: (row 2, col 4)
    EXPECT_EQ(c[coarse.index(1, 0, 1)], 0.0f);  // +20°, lon 90, innermost: no feature there nor beside
    EXPECT_THROW(featurePaintField(g, g, std::vector<int32_t>(3, 0), s), Error);
}

TEST(FeaturePaint, ADerivedVolumeCarriesTheBaseVariablesAndOneMore)
{
    auto base = makeVolume(makeGrid(12, 9, 24), {{"f", twoBlobs}, {"r", [](double, double r, double) { return float(r); }}});
    std::vector<float> extra(base->grid().cellCount());
    for (size_t i = 0; i < extra.size(); ++i)
        extra[i] = float(i % 7);
    auto v = dataset::StepVolume::withVariable(base, extra);
    ASSERT_EQ(v->variableCount(), 3u);
    for (size_t var = 0; var < 2; ++var) {
        EXPECT_EQ(v->values(var), base->values(var));
        EXPECT_EQ(v->brickBounds(var), base->brickBounds(var));
    }
    EXPECT_EQ(v->value(2, 3, 4, 5), extra[base->grid().index(3, 4, 5)]);
    const float* b = v->brickBounds(2);
    for (size_t k = 0; k < v->bricks().brickCount(); ++k) {
        EXPECT_GE(b[2 * k], 0.0f);
        EXPECT_LE(b[2 * k + 1], 6.0f);
    }
    EXPECT_THROW(dataset::StepVolume::withVariable(base, std::vector<float>(5)), Error);
}

TEST(FeaturePaint, TwoBlobsAreDrawnInTheirOwnColours)
{
    auto base = makeVolume(makeGrid(48, 33, 96), {{"f", twoBlobs}});
    const std::vector<analysis::RangeFilter> brushes{{0, std::nullopt, {{0.3f, 2.0f}}}};
    const analysis::StepFeatures f = analysis::extractFeatures(*base, brushes);
    ASSERT_EQ(f.features.size(), 2u);
    state::FeatureSettings s;
    s.colorById = true;
    auto painted = dataset::StepVolume::withVariable(base, featurePaintField(base->grid(), base->grid(), f.labels, s));
    VolumeRenderer renderer(painted);
    RenderParams p;
    p.width = p.height = 96;
    p.camera.distanceKm = 19000;
    p.camera.fovYDeg = 42;
    p.camera.azimuthDeg = 45;  // between the two blobs (90°E and 0°E)
    p.brushes = brushes;
    applyFeaturePaint(p, 1);
    renderer.setParams(p);
    FrameBuffer frame(p.width, p.height);
    for (int i = 0; i < 4; ++i)
        renderer.renderPass(frame);
    const std::vector<float> rgba = frame.averagedRgba();
    // Pixels whose colour (divided by its brightness: shading scales it) is near feature 1's and
    // feature 2's palette colours.
    auto near = [&](Rgb c) {
        size_t n = 0;
        for (size_t i = 0; i < rgba.size(); i += 4) {
            const float a = rgba[i + 3];
            if (a < 0.3f)
                continue;
            const float r = rgba[i] / a, g = rgba[i + 1] / a, b = rgba[i + 2] / a;
            const float s1 = r + g + b, s2 = c.r + c.g + c.b;
            if (s1 <= 0)
                continue;
            if (std::abs(r / s1 - c.r / s2) < 0.05f && std::abs(g / s1 - c.g / s2) < 0.05f && std::abs(b / s1 - c.b / s2) < 0.05f)
                ++n;
        }
        return n;
    };
    const size_t first = near(featurePaintColor(1)), second = near(featurePaintColor(2));
    EXPECT_GT(first, 100u) << "feature 1 (the larger blob) in blue";
    EXPECT_GT(second, 30u) << "feature 2 (the blob across the seam) in orange";
    EXPECT_GT(first, second);
}

}  // namespace
}  // namespace raypc::render

namespace raypc::render {
namespace {

// The legend of painted features names each colour: with colorById a tick per id 1..10 at the middle
// of its colour (the bar's colour there is that id's), else "rest" on grey and "highlighted" on amber.
// The rest of the selection (slot 0) is a dark neutral grey, a quarter of every diverging map's light
// neutral at most, so that under the same lighting a near-zero value (a stalled slab) is never
// taken for it (lit, the neutral turns grey); and fainter than a painted feature.
TEST(FeaturePaint, TheRestIsDarkerThanAnyDivergingNeutral)
{
    const Rgb rest = featurePaintColor(0);
    EXPECT_TRUE(rest.r == rest.g && rest.g == rest.b);
    for (ColorMapId m : state::allColorMaps())
        if (state::isDiverging(m)) {
            const Rgb n = sampleColorMap(m, 0.5f);
            EXPECT_LT(rest.r, 0.25f * (0.2126f * n.r + 0.7152f * n.g + 0.0722f * n.b)) << state::colorMapName(m);
        }
    EXPECT_LT(kFeatureRestOpacity, 0.1f);
}

TEST(FeaturePaint, TheLegendLabelsEachColourWithItsId)
{
    state::FeatureSettings byId;
    byId.colorById = true;
    const LegendSpec legend = featurePaintLegend(byId);
    ASSERT_EQ(legend.ticks.size(), 10u);
    const TransferFunction& tf = legend.colors;
    for (int id = 1; id <= 10; ++id) {
        const LegendSpec::Tick& t = legend.ticks[size_t(id - 1)];
        EXPECT_EQ(t.text, std::to_string(id));
        const Rgb c = tf.colorOf(tf.range.min + t.at * (tf.range.max - tf.range.min));
        const Rgb want = featurePaintColor(id);
        EXPECT_NEAR(c.r, want.r, 1e-5) << "id " << id;
        EXPECT_NEAR(c.g, want.g, 1e-5) << "id " << id;
        EXPECT_NEAR(c.b, want.b, 1e-5) << "id " << id;
    }
    state::FeatureSettings highlight;
    highlight.highlight = {3};
    const LegendSpec h = featurePaintLegend(highlight);
    ASSERT_EQ(h.ticks.size(), 2u);
    EXPECT_EQ(h.ticks[1].text, "highlighted");
    const Rgb amber = h.colors.colorOf(h.colors.range.min + h.ticks[1].at * (h.colors.range.max - h.colors.range.min));
    EXPECT_NEAR(amber.r, featurePaintColor(11).r, 1e-5);
    EXPECT_NEAR(amber.g, featurePaintColor(11).g, 1e-5);
}

}  // namespace
}  // namespace raypc::render
