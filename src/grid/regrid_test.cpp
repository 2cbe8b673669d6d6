#include "grid/regrid.h"

#include "grid/test_util.h"

#include <gtest/gtest.h>

#include <cmath>

namespace raypc::grid {
namespace {

using testing::centredGrid;
using testing::fillGrid;

TEST(Regrid, SameGridCopiesPointForPoint)
{
    const SphericalGrid g = centredGrid(6, 5, 8);
    const auto values = fillGrid(g, [](size_t a, size_t b, size_t c) { return a * 100.0 + b * 10.0 + c + 0.25; });
    EXPECT_EQ(regrid(g, values.data(), g), values);
    EXPECT_DOUBLE_EQ(coveredFraction(g, g), 1.0);
}

// Trilinear in the source's coordinates reproduces a field linear in lat and r exactly between
// rows and shells (away from the pole caps), whatever the target's spacing.
TEST(Regrid, LinearFieldExactInsideTheSource)
{
    const SphericalGrid source = centredGrid(36, 41, 72);
    const auto values = fillGrid(source, [&](size_t a, size_t b, size_t) {
        return 0.5 * source.latDeg[a] + 0.01 * source.rKm[b];
    });
    SphericalGrid target = centredGrid(17, 13, 30);
    target.latDeg.front() = -80;  // inside the source's outermost rows: no pole cap
    target.latDeg.back() = 80;
    const auto out = regrid(source, values.data(), target);
    for (size_t a = 0; a < target.nLat(); ++a)
        for (size_t b = 0; b < target.nR(); ++b)
            for (size_t c = 0; c < target.nLon(); ++c)
                ASSERT_NEAR(out[target.index(a, b, c)], 0.5 * target.latDeg[a] + 0.01 * target.rKm[b], 2e-3)
                    << a << " " << b << " " << c;
}

// Between the last column (350°) and the first (0° = 360°) values blend across the seam.
TEST(Regrid, BlendsAcrossTheLonSeam)
{
    const SphericalGrid source = centredGrid(4, 3, 36);
    const auto values = fillGrid(source, [](size_t, size_t, size_t c) { return c == 0 ? 10.0 : c == 35 ? 20.0 : 0.0; });
    SphericalGrid target = source;
    target.lonDeg = {355.0, 357.5};
    const auto out = regrid(source, values.data(), target);
    EXPECT_NEAR(out[target.index(1, 1, 0)], 15.0, 1e-5);
    EXPECT_NEAR(out[target.index(1, 1, 1)], 12.5, 1e-5);
}

// In a pole cap every longitude meets the row's ring mean at the pole.
TEST(Regrid, PoleIsTheRingMean)
{
    const SphericalGrid source = centredGrid(10, 3, 8);
    const auto values = fillGrid(source, [](size_t, size_t, size_t c) { return double(c); });  // ring mean 3.5
    SphericalGrid target = source;
    target.latDeg = {-90.0, 90.0};
    const auto out = regrid(source, values.data(), target);
    for (size_t c = 0; c < target.nLon(); ++c) {
        EXPECT_NEAR(out[target.index(0, 0, c)], 3.5, 1e-5);
        EXPECT_NEAR(out[target.index(1, 2, c)], 3.5, 1e-5);
    }
}

// Shells outside the source's radii and a regional source's padding are missing, not extrapolated.
TEST(Regrid, OutsideTheSourceIsMissing)
{
    SphericalGrid source = centredGrid(18, 11, 36);
    source.rKm = {4000, 4500, 5000, 5500, 6000};
    const auto values = fillGrid(source, [](size_t, size_t, size_t) { return 1.0; });
    const SphericalGrid target = centredGrid(18, 11, 36);  // 3485 … 6371 km
    const auto out = regrid(source, values.data(), target);
    for (size_t b = 0; b < target.nR(); ++b) {
        const bool inside = target.rKm[b] >= 4000 && target.rKm[b] <= 6000;
        const float v = out[target.index(9, b, 0)];
        if (inside)
            EXPECT_FLOAT_EQ(v, 1.0f) << target.rKm[b];
        else
            EXPECT_TRUE(std::isnan(v)) << target.rKm[b];
    }
    const double covered = coveredFraction(source, target);
    EXPECT_GT(covered, 0.2);
    EXPECT_LT(covered, 0.8);

    SphericalGrid regional = centredGrid(18, 11, 36);
    regional.dataLatDeg = std::array<double, 2>{-25.0, 25.0};
    regional.dataLonDeg = std::array<double, 2>{100.0, 150.0};
    const auto inRegion = fillGrid(regional, [&](size_t a, size_t, size_t c) {
        return regional.holdsData(a, c) ? 2.0 : std::nan("");
    });
    const auto fromRegion = regrid(regional, inRegion.data(), target);
    EXPECT_FLOAT_EQ(fromRegion[target.index(9, 5, 12)], 2.0f);  // 5° N, 120° E
    EXPECT_TRUE(std::isnan(fromRegion[target.index(9, 5, 0)]));   // 0° E
    EXPECT_TRUE(std::isnan(fromRegion[target.index(0, 5, 12)]));  // 85° S
    EXPECT_LT(coveredFraction(regional, target), 0.1);

    SphericalGrid elsewhere = centredGrid(18, 11, 36);
    elsewhere.rKm = {3000, 3100, 3200};
    EXPECT_EQ(coveredFraction(elsewhere, target), 0.0);
}

}  // namespace
}  // namespace raypc::grid
