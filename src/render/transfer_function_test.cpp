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
    EXPECT_EQ(parseColorMap("cool-to-warm"), ColorMapId::CoolToWarm);
    EXPECT_THROW(parseColorMap("rainbow"), Error);
}

}  // namespace
}  // namespace raypc::render
