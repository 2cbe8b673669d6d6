#include "analysis/selection.h"

#include "core/error.h"
#include "core/spherical.h"
#include "io/netcdf_reader.h"
#include "preprocess/preprocess.h"
#include "grid/test_util.h"

#include <gtest/gtest.h>

#include <cmath>
#include <numbers>

namespace raypc::analysis {
namespace {

// The mean of a variable per radius is weighted by the points' dual-cell volumes: the latitude
// over the northern hemisphere averages to the area-weighted pi/2 - 1 radians (32.70°), not to
// the plain mean of its rows (45°), and over the whole shell to 0; in shells with nothing
// selected the selected mean is NaN.
TEST(Selection, MeansPerRadiusAreVolumeWeighted)
{
    grid::Snapshot snap;
    snap.grid = testing::centredGrid(90, 5, 36);
    snap.fields.push_back({"lat", "degree", testing::fillGrid(snap.grid, [&](size_t a, size_t, size_t) { return snap.grid.latDeg[a]; })});
    const auto volume = dataset::StepVolume::fromSnapshot(snap);
    const std::vector<RangeFilter> north{{-1, grid::Coordinate::Lat, {{0.0f, 90.0f}}},
                                         {-1, grid::Coordinate::Radius, {{0.0f, float(snap.grid.rKm[3])}}}};
    const SelectionStats s = selectedVolume(*volume, north, 0);
    ASSERT_EQ(s.selectedMeanByRadius.size(), snap.grid.nR());
    const double expected = (std::numbers::pi / 2 - 1) * 180 / std::numbers::pi;  // 32.70°
    for (size_t iR = 0; iR < snap.grid.nR(); ++iR) {
        EXPECT_NEAR(s.shellMeanByRadius[iR], 0.0, 1e-9);
        if (iR <= 3)
            EXPECT_NEAR(s.selectedMeanByRadius[iR], expected, 0.05) << iR;  // 2° rows: the midpoint rule's error
        else
            EXPECT_TRUE(std::isnan(s.selectedMeanByRadius[iR])) << iR;
    }
    EXPECT_TRUE(selectedVolume(*volume, north).shellMeanByRadius.empty());
    EXPECT_THROW(selectedVolume(*volume, north, 1), Error);
}

TEST(Selection, ExactVolumesOfAnalyticSelections)
{
    grid::Snapshot snap = io::readSnapshot(testing::contestLayoutDir() / "spherical001.nc");
    preprocess::addDerivedVariables(snap);
    const auto volume = dataset::StepVolume::fromSnapshot(snap);
    const double shell = 4.0 / 3.0 * std::numbers::pi * (std::pow(6371.0, 3) - std::pow(3485.0, 3));

    const auto all = selectedVolume(*volume, {});
    EXPECT_NEAR(all.fractionOfMantle, 1.0, 1e-12);
    EXPECT_NEAR(all.volumeKm3 / shell, 1.0, 1e-12);

    // North of 60°: the rows 62.5..87.5 end at the 60° edge, so this is exact.
    const RangeFilter north{-1, grid::Coordinate::Lat, {{60.0f, 90.0f}}};
    EXPECT_NEAR(selectedVolume(*volume, std::span(&north, 1)).fractionOfMantle, (1 - std::sin(std::numbers::pi / 3)) / 2,
                1e-9);

    // Depth <= 660 km: the radii >= 5711 km; their dual cells start halfway below the first one.
    const RangeFilter upper{-1, grid::Coordinate::Depth, {{0.0f, 660.0f}}};
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
    const std::vector<RangeFilter> both = {{ur, std::nullopt, {{0.15f, 0.16f}}}, upper};
    EXPECT_NEAR(selectedVolume(*volume, both).volumeKm3, up.volumeKm3, 1e-9 * shell);
    const RangeFilter none{ur, std::nullopt, {{0.2f, 0.3f}}};
    EXPECT_EQ(selectedVolume(*volume, std::span(&none, 1)).volumeKm3, 0.0);

    const RangeFilter inverted{ur, std::nullopt, {{1.0f, 0.0f}}};
    EXPECT_THROW(selectedVolume(*volume, std::span(&inverted, 1)), Error);
    const RangeFilter missing{42, std::nullopt, {{0.0f, 1.0f}}};
    EXPECT_THROW(selectedVolume(*volume, std::span(&missing, 1)), Error);
}

// Several ranges on one axis select their union: disjoint ranges add up, overlapping ones select
// what their merged range selects; names that repeat in a list of NamedRanges become one axis.
TEST(Selection, RangesOnOneAxisSelectTheirUnion)
{
    grid::Snapshot snap = io::readSnapshot(testing::contestLayoutDir() / "spherical001.nc");
    const auto volume = dataset::StepVolume::fromSnapshot(snap);
    std::vector<std::string> names;
    for (const auto& field : snap.fields)
        names.push_back(field.name);
    auto fraction = [&](const std::vector<NamedRange>& ranges) {
        return selectedVolume(*volume, resolveRangeFilters(std::span<const std::string>(names), ranges)).fractionOfMantle;
    };
    // The lat rows (2.5° apart, at ±1.25°, ±3.75°, ...) have dual-cell edges at multiples of 2.5°,
    // so ranges ending there select exactly the caps and bands between them.
    const double cap = (1 - std::sin(std::numbers::pi / 3)) / 2;  // north of 60°
    const double north = fraction({{"lat", 60, 90}}), south = fraction({{"lat", -90, -60}});
    EXPECT_NEAR(north, cap, 1e-9);
    EXPECT_NEAR(south, cap, 1e-9);
    EXPECT_NEAR(fraction({{"lat", 60, 90}, {"lat", -90, -60}}), 2 * cap, 1e-9);
    EXPECT_NEAR(fraction({{"lat", -90, -60}, {"depth", 0, 6371}, {"lat", 60, 90}}), 2 * cap, 1e-9);
    // Overlapping: [0, 30] or [20, 60] is [0, 60], the band sin 60° / 2.
    EXPECT_NEAR(fraction({{"lat", 0, 30}, {"lat", 20, 60}}), std::sin(std::numbers::pi / 3) / 2, 1e-9);
    EXPECT_NEAR(fraction({{"lat", 0, 30}, {"lat", 20, 60}}), fraction({{"lat", 0, 60}}), 1e-12);
    // A range inside another changes nothing; AND over axes still holds (north cap and depth <= 660).
    EXPECT_NEAR(fraction({{"lat", 60, 90}, {"lat", 70, 80}}), north, 1e-12);
    EXPECT_LT(fraction({{"lat", 60, 90}, {"depth", 0, 660}, {"lat", -90, -60}}), 2 * cap * 0.5);

    const auto filters = resolveRangeFilters(std::span<const std::string>(names),
                                             std::vector<NamedRange>{{"lat", 60, 90}, {"depth", 0, 660}, {"lat", -90, -60}});
    ASSERT_EQ(filters.size(), 2u);
    EXPECT_EQ(*filters[0].coordinate, grid::Coordinate::Lat);
    ASSERT_EQ(filters[0].ranges.size(), 2u);
    EXPECT_EQ(filters[0].ranges[1].min, -90.0f);
    EXPECT_TRUE(filters[0].contains(-70) && filters[0].contains(89) && !filters[0].contains(0));

    // min > max names the range by its index in the list.
    try {
        resolveRangeFilters(std::span<const std::string>(names),
                            std::vector<NamedRange>{{"lat", 60, 90}, {"depth", 0, 660}, {"lat", -60, -90}}, "brushes");
        FAIL() << "expected an error";
    } catch (const Error& e) {
        EXPECT_STREQ(e.what(), "brushes[2] (lat): min -60 is greater than max -90");
    }
    const RangeFilter noRange{-1, grid::Coordinate::Lat, {}};
    EXPECT_THROW(selectedVolume(*volume, std::span(&noRange, 1)), Error);
}

// Split by classes of points, the selection's volume is the same as without classes; a class that
// is a lat cap holds exactly the cap's volume, and its selected part the cap's share of the selection.
TEST(Selection, VolumesByClassAddUpToTheSelection)
{
    grid::Snapshot snap = io::readSnapshot(testing::contestLayoutDir() / "spherical001.nc");
    const auto volume = dataset::StepVolume::fromSnapshot(snap);
    const grid::SphericalGrid& g = snap.grid;
    const double shell = g.totalVolumeKm3();
    // Class 0: south of -60°, 1: north of 60° (the lat rows' dual cells end at multiples of 2.5°),
    // 2: the rest.
    std::vector<uint32_t> classes(g.cellCount());
    for (size_t iLat = 0; iLat < g.nLat(); ++iLat)
        for (size_t iR = 0; iR < g.nR(); ++iR)
            for (size_t iLon = 0; iLon < g.nLon(); ++iLon)
                classes[g.index(iLat, iR, iLon)] = g.latDeg[iLat] < -60 ? 0 : g.latDeg[iLat] > 60 ? 1 : 2;
    const RangeFilter upper{-1, grid::Coordinate::Depth, {{0.0f, 660.0f}}};
    const auto whole = selectedVolume(*volume, std::span(&upper, 1));
    const ClassVolumes byClass = selectedVolumeByClass(*volume, std::span(&upper, 1), classes, 3);
    ASSERT_EQ(byClass.totalKm3.size(), 3u);
    const double cap = (1 - std::sin(std::numbers::pi / 3)) / 2;
    EXPECT_NEAR(byClass.totalKm3[0] / shell, cap, 1e-9);
    EXPECT_NEAR(byClass.totalKm3[1] / shell, cap, 1e-9);
    EXPECT_NEAR((byClass.totalKm3[0] + byClass.totalKm3[1] + byClass.totalKm3[2]) / shell, 1.0, 1e-12);
    EXPECT_NEAR((byClass.selectedKm3[0] + byClass.selectedKm3[1] + byClass.selectedKm3[2]) / shell,
                whole.volumeKm3 / shell, 1e-12);
    EXPECT_NEAR(byClass.selectedKm3[1] / whole.volumeKm3, cap, 1e-9);

    // Bad labellings are refused by name.
    std::vector<uint32_t> shortList(classes.begin(), classes.end() - 1);
    EXPECT_THROW(selectedVolumeByClass(*volume, std::span(&upper, 1), shortList, 3), Error);
    try {
        selectedVolumeByClass(*volume, std::span(&upper, 1), classes, 2);
        FAIL() << "expected an error";
    } catch (const Error& e) {
        EXPECT_NE(std::string(e.what()).find("class 2, expected < 2"), std::string::npos) << e.what();
    }
    const RangeFilter noRange{-1, grid::Coordinate::Lat, {}};
    EXPECT_THROW(selectedVolumeByClass(*volume, std::span(&noRange, 1), classes, 3), Error);
}

}  // namespace
}  // namespace raypc::analysis
