#include "render/transfer_function.h"

#include "core/error.h"

#include <gtest/gtest.h>

#include <cmath>

namespace raypc::render {
namespace {

TEST(TransferFunction, OpacityIsPerUnitDistance)
{
    TransferFunction tf;
    tf.opacity = {{0, 0.3f}, {1, 0.3f}};
    tf.opacityUnitKm = 50;
    const TransferTable t = TransferTable::bake(tf);
    const float sigma = t.sigmaPerKm[500];
    // One step of the unit distance gives the stated opacity; two half steps compose to the same.
    EXPECT_NEAR(1 - std::exp(-sigma * 50), 0.3f, 1e-6);
    const float half = 1 - std::exp(-sigma * 25);
    EXPECT_NEAR(1 - (1 - half) * (1 - half), 0.3f, 1e-6);
}

TEST(TransferFunction, PiecewiseLinearAndTransparentRanges)
{
    TransferFunction tf;
    tf.range = {-10, 10};
    tf.opacity = {{0, 0}, {0.5f, 0}, {0.75f, 1}, {1, 1}};
    EXPECT_FLOAT_EQ(tf.opacityAt(0.625f), 0.5f);
    const TransferTable t = TransferTable::bake(tf);
    EXPECT_TRUE(t.transparentOver(-10, -0.1f));
    EXPECT_TRUE(t.transparentOver(-50, -20));  // clamped below the range
    EXPECT_FALSE(t.transparentOver(-1, 0.5f));
    EXPECT_FALSE(t.transparentOver(20, 30));  // clamped above: opaque end
    EXPECT_TRUE(std::isfinite(t.sigmaPerKm.back()));
}

TEST(TransferFunction, BadInputsThrow)
{
    TransferFunction tf;
    tf.range = {1, 1};
    EXPECT_THROW(tf.validate(), Error);
    tf.range = {0, 1};
    tf.opacity = {{0.5f, 0}, {0.2f, 1}};
    EXPECT_THROW(tf.validate(), Error);
    tf.opacity = {{0, 1.5f}};
    EXPECT_THROW(tf.validate(), Error);
}

TEST(ColorMap, KnownEndsAndCentredZero)
{
    const Rgb v0 = sampleColorMap(ColorMapId::Viridis, 0), v1 = sampleColorMap(ColorMapId::Viridis, 1);
    EXPECT_NEAR(v0.r, 0.267, 1e-3);
    EXPECT_NEAR(v1.g, 0.906, 1e-3);
    const Rgb black = sampleColorMap(ColorMapId::Inferno, 0);
    EXPECT_LT(black.r + black.g + black.b, 0.02);
    const Rgb mid = sampleColorMap(ColorMapId::CoolToWarm, 0.5f);
    EXPECT_NEAR(mid.r, mid.b, 1e-3);
    // Blue-white-red: value 0 is white even for an asymmetric range.
    TransferFunction tf;
    tf.colorMap = ColorMapId::BlueWhiteRed;
    tf.range = {-1, 3};
    const TransferTable t = TransferTable::bake(tf);
    const int zero = t.indexOf(0);
    EXPECT_GT(t.red[zero], 0.9f);
    EXPECT_GT(t.blue[zero], 0.9f);
    EXPECT_GT(t.blue[0], t.red[0]);
    EXPECT_GT(t.red.back(), t.blue.back());
    EXPECT_EQ(state::parseColorMap("cool-to-warm"), ColorMapId::CoolToWarm);
    EXPECT_THROW(state::parseColorMap("rainbow"), Error);
}

// The perceptually uniform maps come from the shared table with their published end colours
// (Crameri 8.0.1: batlow 1,25,89 .. 250,204,250 in 8 bits; cmocean thermal starts near-black blue),
// and the diverging ones are centred on 0.
TEST(ColorMap, ScientificMapsFromTheSharedTable)
{
    const Rgb b0 = sampleColorMap(ColorMapId::Batlow, 0), b1 = sampleColorMap(ColorMapId::Batlow, 1);
    EXPECT_NEAR(b0.r * 255, 1, 0.6);
    EXPECT_NEAR(b0.g * 255, 25, 0.6);
    EXPECT_NEAR(b0.b * 255, 89, 0.6);
    EXPECT_NEAR(b1.r * 255, 250, 0.6);
    EXPECT_NEAR(b1.g * 255, 204, 0.6);
    EXPECT_NEAR(b1.b * 255, 250, 0.6);
    const Rgb t0 = sampleColorMap(ColorMapId::Thermal, 0);
    EXPECT_LT(t0.r + t0.g + t0.b, 0.4f);
    for (ColorMapId m : {ColorMapId::Vik, ColorMapId::Roma, ColorMapId::Balance, ColorMapId::BlueWhiteRed}) {
        EXPECT_TRUE(state::isCentredOnZero(m)) << state::colorMapName(m);
        EXPECT_TRUE(state::isDiverging(m)) << state::colorMapName(m);
    }
    for (ColorMapId m : {ColorMapId::Batlow, ColorMapId::Lajolla, ColorMapId::Thermal, ColorMapId::Viridis})
        EXPECT_FALSE(state::isDiverging(m)) << state::colorMapName(m);
    for (ColorMapId m : state::allColorMaps())
        EXPECT_EQ(state::parseColorMap(state::colorMapName(m)), m);
    EXPECT_EQ(state::allColorMaps().size(), 11u);
}

// One default colour range per variable (robust to a few extreme points): for centred maps ±the 99.5th percentile of
// |value| rounded up to a nice number, at most ±the larger magnitude; the exact range otherwise.
TEST(DefaultColorRange, RobustSymmetricPercentileRoundedUp)
{
    // Uniform over [-1, 3]: the fraction with |v| > m is (3 - m) / 4 for m in [1, 3], so the 99.5th
    // percentile of |v| is 2.98.
    const std::vector<double> uniform(dataset::kHistogramBins, 1.0 / dataset::kHistogramBins);
    EXPECT_NEAR(absQuantile({-1, 3}, uniform, 0.995), 2.98, 1e-4);
    EXPECT_NEAR(absQuantile({-1, 3}, uniform, 0.5), 1.0, 1e-4);  // (3 - m) / 4 + (1 - m) / 4 = 0.5 at m = 1
    const dataset::ValueRange u = defaultColorRange({-1, 3}, true, uniform);
    EXPECT_FLOAT_EQ(u.min, -3);
    EXPECT_FLOAT_EQ(u.max, 3);
    EXPECT_FLOAT_EQ(niceCeil(271.08f), 300);
    EXPECT_FLOAT_EQ(niceCeil(2.98f), 3);
    EXPECT_FLOAT_EQ(niceCeil(0.0123f), 0.015f);
    EXPECT_FLOAT_EQ(niceCeil(4), 4);
    EXPECT_FLOAT_EQ(niceCeil(8.5f), 10);

    // A temperature anomaly of [-269.8, 451.8] K whose bulk lies within ±200 K and whose hottest
    // 0.2 % reach 451.8 K (a few plume conduits): ±200 K, not ±451.8 K.
    const dataset::ValueRange values{-269.8f, 451.8f};
    std::vector<double> h(dataset::kHistogramBins, 0.0);
    const double width = (values.max - values.min) / dataset::kHistogramBins;
    for (int i = 0; i < dataset::kHistogramBins; ++i) {
        const double mid = values.min + width * (i + 0.5);
        h[size_t(i)] = std::abs(mid) < 190 ? 1.0 : 0.002;
    }
    const dataset::ValueRange t = defaultColorRange(values, true, h);
    EXPECT_FLOAT_EQ(t.min, -t.max);
    EXPECT_FLOAT_EQ(t.max, 200);
    // The statistics' overload is the same rule.
    dataset::VariableStats stats;
    stats.range = values;
    stats.histogram = h;
    EXPECT_FLOAT_EQ(defaultColorRange(stats, true).max, 200);
    // A nice number beyond the data is cut at the larger magnitude; without a histogram, ±it.
    std::vector<double> edge(dataset::kHistogramBins, 0.0);
    edge.back() = 1;
    EXPECT_FLOAT_EQ(defaultColorRange({-10, 450}, true, edge).max, 450);
    EXPECT_FLOAT_EQ(defaultColorRange(values, true).max, 451.8f);
    // Other maps: the exact range; a constant one widened.
    EXPECT_FLOAT_EQ(defaultColorRange(values, false, h).min, -269.8f);
    EXPECT_FLOAT_EQ(defaultColorRange(values, false, h).max, 451.8f);
    EXPECT_FLOAT_EQ(defaultColorRange({2, 2}, false, h).max, 2.5f);
    EXPECT_FLOAT_EQ(defaultColorRange({2, 2}, true, h).max, 2);
}

TEST(TransferFunction, ColorPointsReversedAndLogScale)
{
    TransferFunction tf;
    tf.range = {0, 10};
    tf.colorPoints = {{0, {1, 0, 0}}, {0.5f, {0, 1, 0}}, {1, {0, 0, 1}}};
    EXPECT_NEAR(tf.colorOf(0).r, 1, 1e-6);
    EXPECT_NEAR(tf.colorOf(2.5f).r, 0.5, 1e-6);
    EXPECT_NEAR(tf.colorOf(2.5f).g, 0.5, 1e-6);
    EXPECT_NEAR(tf.colorOf(10).b, 1, 1e-6);
    tf.reversed = true;
    EXPECT_NEAR(tf.colorOf(0).b, 1, 1e-6);
    EXPECT_NEAR(tf.colorOf(10).r, 1, 1e-6);
    // Log scale: 1 .. 1000, the value 10 sits a third of the way, 100 two thirds.
    tf.reversed = false;
    tf.range = {1, 1000};
    tf.logScale = true;
    EXPECT_NEAR(tf.positionOf(10), 1.0 / 3, 1e-5);
    EXPECT_NEAR(tf.positionOf(100), 2.0 / 3, 1e-5);
    EXPECT_NEAR(tf.colorOf(std::sqrt(1000.0f)).g, 1, 1e-4);  // the middle point, green
    tf.opacity = {{0, 0}, {1, 1}};
    const TransferTable t = TransferTable::bake(tf);
    const float sigma100 = t.sigmaPerKm[t.indexOf(100)];
    EXPECT_NEAR(1 - std::exp(-sigma100 * tf.opacityUnitKm), 2.0 / 3, 0.01);  // opacity at u = 2/3
    // Bad colour points and a log scale over a range through zero are refused.
    tf.range = {-1, 1};
    EXPECT_THROW(tf.validate(), Error);
    tf.logScale = false;
    EXPECT_NO_THROW(tf.validate());
    tf.colorPoints = {{0.5f, {0, 0, 0}}, {0.2f, {1, 1, 1}}};
    EXPECT_THROW(tf.validate(), Error);
    tf.colorPoints = {{0, {0, 0, 0}}, {1, {1, 2, 1}}};
    EXPECT_THROW(tf.validate(), Error);
}

}  // namespace
}  // namespace raypc::render
