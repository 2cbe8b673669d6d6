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
