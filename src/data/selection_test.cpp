#include "data/selection.h"

#include "core/error.h"
#include "core/spherical.h"
#include "data/netcdf_reader.h"
#include "data/preprocess.h"
#include "data/test_util.h"

#include <gtest/gtest.h>

#include <cmath>
#include <numbers>

namespace raypc {
namespace {

TEST(Selection, ExactVolumesOfAnalyticSelections)
{
    Snapshot snap = readSnapshot(testing::contestLayoutDir() / "spherical001.nc");
    addDerivedVariables(snap);
    const auto volume = StepVolume::fromSnapshot(snap);
    const double shell = 4.0 / 3.0 * std::numbers::pi * (std::pow(6371.0, 3) - std::pow(3485.0, 3));

    const auto all = selectedVolume(*volume, {});
    EXPECT_NEAR(all.fractionOfMantle, 1.0, 1e-12);
    EXPECT_NEAR(all.volumeKm3 / shell, 1.0, 1e-12);

    // North of 60°: the rows 62.5..87.5 end at the 60° edge, so this is exact.
    const RangeFilter north{-1, Coordinate::Lat, 60.0f, 90.0f};
    EXPECT_NEAR(selectedVolume(*volume, std::span(&north, 1)).fractionOfMantle, (1 - std::sin(std::numbers::pi / 3)) / 2,
                1e-9);

    // Depth <= 660 km: the radii >= 5711 km; their dual cells start halfway below the first one.
    const RangeFilter upper{-1, Coordinate::Depth, 0.0f, 660.0f};
    const auto& r = snap.grid.rKm;
    size_t first = 0;
    while (r[first] < 6371.0 - 660.0)
        ++first;
    const double edge = 0.5 * (r[first - 1] + r[first]);
    const auto up = selectedVolume(*volume, std::span(&upper, 1));
    EXPECT_NEAR(up.volumeKm3, 4.0 / 3.0 * std::numbers::pi * (std::pow(6371.0, 3) - std::pow(edge, 3)), 1e-6 * shell);
    for (size_t i = 0; i < first; ++i)
        EXPECT_EQ(up.volumeByRadiusKm3[i], 0.0);
    EXPECT_GT(up.volumeByRadiusKm3.back(), 0.0);
    // Shells above 660 km are selected whole; the shells add up to the mantle.
    EXPECT_NEAR(up.volumeByRadiusKm3.back(), up.shellVolumeByRadiusKm3.back(), 1e-9 * shell);
    double shells = 0;
    for (double v : up.shellVolumeByRadiusKm3)
        shells += v;
    EXPECT_NEAR(shells / shell, 1.0, 1e-12);

    // The radial velocity is u0 everywhere (truth.json): a range around it selects all, one
    // beside it nothing; combined with the depth cut, the cut alone remains.
    const int ur = 8;
    ASSERT_EQ(snap.fields[ur].name, "radial velocity");
    const std::vector<RangeFilter> both = {{ur, std::nullopt, 0.15f, 0.16f}, upper};
    EXPECT_NEAR(selectedVolume(*volume, both).volumeKm3, up.volumeKm3, 1e-9 * shell);
    const RangeFilter none{ur, std::nullopt, 0.2f, 0.3f};
    EXPECT_EQ(selectedVolume(*volume, std::span(&none, 1)).volumeKm3, 0.0);

    const RangeFilter inverted{ur, std::nullopt, 1.0f, 0.0f};
    EXPECT_THROW(selectedVolume(*volume, std::span(&inverted, 1)), Error);
    const RangeFilter missing{42, std::nullopt, 0.0f, 1.0f};
    EXPECT_THROW(selectedVolume(*volume, std::span(&missing, 1)), Error);
}

}  // namespace
}  // namespace raypc
