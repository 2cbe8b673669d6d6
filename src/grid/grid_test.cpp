#include "dataset/bricks.h"
#include "dataset/dataset.h"
#include "grid/grid.h"
#include "grid/sampler.h"
#include "grid/test_util.h"

#include "core/error.h"
#include "core/spherical.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <numbers>
#include <random>

namespace raypc::grid {
namespace {

using testing::centredGrid;

TEST(Grid, DualCellsFillTheShellExactly)
{
    const double shell = 4.0 / 3.0 * std::numbers::pi *
                         (std::pow(kSurfaceRadiusKm, 3) - std::pow(kCoreRadiusKm, 3));
    EXPECT_NEAR(centredGrid(36, 41, 72).totalVolumeKm3() / shell, 1.0, 1e-12);
    // Non-uniform radii and a grid that includes the poles still tile the shell.
    SphericalGrid g = centredGrid(5, 4, 7);
    g.rKm = {3485, 3600, 5000, 6371};
    g.latDeg = {-90, -45, 0, 45, 90};
    EXPECT_NEAR(g.totalVolumeKm3() / shell, 1.0, 1e-12);
}

TEST(Grid, CoarsenedHalvesEachAxisAndKeepsOddEnds)
{
    const SphericalGrid fine = centredGrid(5, 7, 9);
    const SphericalGrid coarse = fine.coarsened();
    EXPECT_EQ(coarse.nLat(), 3u);
    EXPECT_EQ(coarse.nR(), 4u);
    EXPECT_EQ(coarse.nLon(), 5u);
    EXPECT_DOUBLE_EQ(coarse.latDeg[0], 0.5 * (fine.latDeg[0] + fine.latDeg[1]));
    EXPECT_DOUBLE_EQ(coarse.latDeg[2], fine.latDeg[4]);  // the odd last row stays alone
    EXPECT_DOUBLE_EQ(coarse.lonDeg[4], fine.lonDeg[8]);
    EXPECT_NO_THROW(coarse.validate("coarse"));
}

TEST(Grid, ValidateRejectsUnsortedGrids)
{
    SphericalGrid g = centredGrid(4, 3, 8);
    EXPECT_NO_THROW(g.validate("ok"));
    SphericalGrid unsorted = g;
    std::swap(unsorted.rKm[0], unsorted.rKm[1]);
    EXPECT_THROW(unsorted.validate("unsorted"), Error);
    SphericalGrid beyondPole = g;
    beyondPole.latDeg.back() = 90.5;
    EXPECT_THROW(beyondPole.validate("beyond the pole"), Error);
    SphericalGrid lon360 = g;
    lon360.lonDeg.back() = 360.0;
    EXPECT_THROW(lon360.validate("lon 360"), Error);
}

// A regional grid padded to the globe: its rows and columns outside the data's extent weigh nothing,
// so volumes, statistics and selections are the region's; the rest are the global grid's dual cells.
TEST(Grid, RegionalGridsHaveVolumeOnlyWhereTheirDataAre)
{
    SphericalGrid g;
    g.latDeg = {-90, -43, -11, 5, 13, 17, 19, 20, 21, 22, 23, 24, 25, 26, 28, 32, 40, 56, 90};
    g.rKm = {5000, 5500, 6000};
    g.lonDeg = {0, 10, 20, 60, 180, 300, 340, 350};  // data from 340 across 0 to 20 degrees east
    g.dataLatDeg = std::array<double, 2>{20, 25};
    g.dataLonDeg = std::array<double, 2>{340, 20};
    EXPECT_NO_THROW(g.validate("regional"));
    EXPECT_TRUE(g.regional());
    const auto w = g.volumeFactors();
    for (size_t i = 0; i < g.nLat(); ++i)
        EXPECT_EQ(w.lat[i] > 0, g.latDeg[i] >= 20 && g.latDeg[i] <= 25) << "lat " << g.latDeg[i];
    for (size_t i = 0; i < g.nLon(); ++i)
        EXPECT_EQ(w.lon[i] > 0, g.lonDeg[i] <= 20 || g.lonDeg[i] >= 340) << "lon " << g.lonDeg[i];
    EXPECT_FALSE(g.lonHoldsData(300));
    EXPECT_TRUE(g.lonHoldsData(355));  // within the extent, though no column lies there
    // The region's volume: its rows' dual cells (half a spacing beyond the outermost), its columns'.
    const double latPart = std::sin(degToRad(25.5)) - std::sin(degToRad(19.5));
    const auto lonEdges = g.lonEdgesDeg();
    double lonPart = 0;
    for (size_t i = 0; i < g.nLon(); ++i)
        if (g.lonHoldsData(g.lonDeg[i]))
            lonPart += degToRad(lonEdges[i + 1] - lonEdges[i]);
    EXPECT_NEAR(g.totalVolumeKm3(), latPart * lonPart * (std::pow(6000.0, 3) - std::pow(5000.0, 3)) / 3, 1e-6 * g.totalVolumeKm3());
    // The extent survives coarsening, and a grid without one is global.
    EXPECT_EQ(g.coarsened().dataLatDeg, g.dataLatDeg);
    EXPECT_FALSE(centredGrid(4, 3, 8).regional());
}

// Every trilinear value a sample can take lies within the bounds of the brick it falls in,
// including pole caps and the lon seam, at odd sizes.
TEST(Bricks, BoundsContainEveryInterpolatedValue)
{
    const SphericalGrid g = centredGrid(13, 11, 21);
    std::mt19937 rng(7);
    std::normal_distribution<float> noise;
    std::vector<float> values(g.cellCount());
    for (auto& v : values)
        v = noise(rng);
    const BrickLayout layout = BrickLayout::forGrid(g, 4);
    std::vector<float> bounds(2 * layout.brickCount());
    dataset::computeBrickBounds(g, layout, values, bounds);
    const GridSampler sampler(g);
    std::uniform_real_distribution<double> u(0, 1);
    for (int i = 0; i < 200000; ++i) {
        const double lat = -90 + 180 * u(rng), lon = 360 * u(rng);
        const double r = kCoreRadiusKm + (kSurfaceRadiusKm - kCoreRadiusKm) * u(rng);
        const auto at = sampler.locate(lat, lon, r);
        ASSERT_TRUE(at);
        const double v = sampler.sample(values.data(), *at);
        const size_t b = layout.index(at->lat0 / 4, at->r0 / 4, at->lon0 / 4);
        ASSERT_GE(v, bounds[2 * b] - 1e-5) << lat << " " << lon << " " << r;
        ASSERT_LE(v, bounds[2 * b + 1] + 1e-5) << lat << " " << lon << " " << r;
    }
}

TEST(Bricks, VolumesDeriveBoundsOfSmallerBricksOnceAndKeepThem)
{
    Snapshot snap;
    snap.grid = centredGrid(13, 11, 21);
    std::mt19937 rng(3);
    std::normal_distribution<float> noise;
    Field f{"f", "1", std::vector<float>(snap.grid.cellCount())};
    for (auto& v : f.values)
        v = noise(rng);
    snap.fields = {f};
    const auto volume = dataset::StepVolume::fromSnapshot(snap, 8);
    EXPECT_EQ(volume->brickBounds(0, 8), volume->brickBounds(0));
    const BrickLayout layout = BrickLayout::forGrid(snap.grid, 2);
    std::vector<float> expected(2 * layout.brickCount());
    dataset::computeBrickBounds(snap.grid, layout, f.values, expected);
    const float* derived = volume->brickBounds(0, 2);
    EXPECT_EQ(std::vector<float>(derived, derived + expected.size()), expected);
    EXPECT_EQ(volume->brickBounds(0, 2), derived);  // kept, not recomputed
}

// Central differences per degree / km: exact for fields linear in each coordinate (also one-sided at
// the outermost rows and radii), second-order for sin(lon) and continuous across the seam; on a
// stretched radial axis the difference is taken over the real spacing.
TEST(Grid, NodeGradientIsTheCentralDifferenceInEachGridDirection)
{
    SphericalGrid g = centredGrid(9, 7, 36);
    for (size_t i = 0; i < g.nR(); ++i)
        g.rKm[i] = 3485 + 2886 * std::pow(double(i) / double(g.nR() - 1), 1.7);  // stretched
    std::vector<float> f(g.cellCount());
    for (size_t a = 0; a < g.nLat(); ++a)
        for (size_t b = 0; b < g.nR(); ++b)
            for (size_t c = 0; c < g.nLon(); ++c)
                f[g.index(a, b, c)] = float(2 * g.latDeg[a] - 0.5 * g.rKm[b] + 100 * std::sin(degToRad(g.lonDeg[c])));
    const NodeGradient n = nodeGradient(g, f.data());
    const double h = degToRad(g.lonDeg[1] - g.lonDeg[0]);
    for (size_t a = 0; a < g.nLat(); ++a)
        for (size_t b = 0; b < g.nR(); ++b)
            for (size_t c = 0; c < g.nLon(); ++c) {
                const size_t i = g.index(a, b, c);
                EXPECT_NEAR(n.perDegLat()[i], 2.0, 2e-4) << a << "," << b << "," << c;
                EXPECT_NEAR(n.perKmR()[i], -0.5, 2e-5) << a << "," << b << "," << c;
                // d/dlon of 100 sin(lon) per degree, times sin(h)/h for the central difference.
                const double want = 100 * std::cos(degToRad(g.lonDeg[c])) * degToRad(1.0) * std::sin(h) / h;
                EXPECT_NEAR(n.perDegLon()[i], want, 2e-4) << a << "," << b << "," << c;
            }
    // The volume keeps what it computed.
    Snapshot snap;
    snap.grid = g;
    snap.fields = {{"f", "1", f}};
    const auto volume = dataset::StepVolume::fromSnapshot(snap, 8);
    EXPECT_EQ(&volume->nodeGradient(0), &volume->nodeGradient(0));
    EXPECT_TRUE(std::equal(n.perKmR(), n.perKmR() + n.count, volume->nodeGradient(0).perKmR()));
}

TEST(Sampler, ReproducesTrilinearFunctionsAndIsContinuousAtSeamAndPoles)
{
    const SphericalGrid g = centredGrid(18, 9, 36);
    // A field linear in r: trilinear interpolation is exact in r.
    std::vector<float> linearR(g.cellCount()), byLon(g.cellCount());
    for (size_t a = 0; a < g.nLat(); ++a)
        for (size_t b = 0; b < g.nR(); ++b)
            for (size_t c = 0; c < g.nLon(); ++c) {
                linearR[g.index(a, b, c)] = static_cast<float>(g.rKm[b]);
                byLon[g.index(a, b, c)] = static_cast<float>(std::cos(degToRad(g.lonDeg[c])));
            }
    const GridSampler s(g);
    EXPECT_NEAR(s.sample(linearR.data(), *s.locate(12.3, 45.6, 4321.0)), 4321.0, 1e-3);
    EXPECT_FALSE(s.locate(0, 0, 3000.0));
    EXPECT_FALSE(s.locate(0, 0, 7000.0));
    // The seam: approaching 360 from below equals approaching 0 from above.
    const double below = s.sample(byLon.data(), *s.locate(10, 359.9999, 5000));
    const double above = s.sample(byLon.data(), *s.locate(10, 0.0001, 5000));
    EXPECT_NEAR(below, above, 1e-4);
    // Halfway between the last column (350°) and the first (0°), linear in index space.
    EXPECT_NEAR(s.sample(byLon.data(), *s.locate(10, 355, 5000)), 0.5 * (std::cos(degToRad(350.0)) + 1.0), 1e-6);
    // At a pole every longitude gives the same value (the ring mean).
    const double p0 = s.sample(byLon.data(), *s.locate(90, 0, 5000));
    const double p1 = s.sample(byLon.data(), *s.locate(90, 137, 5000));
    EXPECT_NEAR(p0, p1, 1e-9);
    EXPECT_NEAR(p0, 0.0, 1e-6);  // the ring mean of cos(lon)
    // Just inside the cap, values are near the outermost row's.
    EXPECT_NEAR(s.sample(byLon.data(), *s.locate(g.latDeg.back() + 1e-6, 0, 5000)), 1.0, 1e-6);
}

// The constant-time bracket of an evenly spaced axis finds what a binary search finds, at nodes,
// between them, at and beyond the ends; an uneven axis is searched.
TEST(Sampler, AxisBracketEqualsBinarySearch)
{
    std::vector<double> even, uneven;
    for (int i = 0; i < 180; ++i)
        even.push_back(-89.5 + i);
    for (int i = 0; i < 50; ++i)
        uneven.push_back(3480 + 60.0 * i + 0.3 * i * i);
    auto reference = [](const std::vector<double>& c, double x) {
        const auto it = std::upper_bound(c.begin(), c.end(), x);
        const size_t i = it == c.begin() ? 0 : std::min(c.size() - 2, size_t(it - c.begin()) - 1);
        return std::pair{i, std::clamp((x - c[i]) / (c[i + 1] - c[i]), 0.0, 1.0)};
    };
    std::mt19937 rng(7);
    for (const auto* c : {&even, &uneven}) {
        const GridSampler::Axis axis(*c);
        std::vector<double> xs{c->front(), c->back(), c->front() - 5, c->back() + 5, -1e300, 1e300};
        for (const double node : *c)
            xs.insert(xs.end(), {node, std::nextafter(node, -1e300), std::nextafter(node, 1e300)});
        std::uniform_real_distribution<double> u(c->front() - 1, c->back() + 1);
        for (int k = 0; k < 10000; ++k)
            xs.push_back(u(rng));
        for (const double x : xs) {
            const auto [i, t] = axis.bracket(x);
            const auto [iRef, tRef] = reference(*c, x);
            ASSERT_EQ(i, iRef) << "x = " << x;
            ASSERT_EQ(t, tRef) << "x = " << x;
        }
    }
}

// locate(lat, lon, r) is its two parts combined; sampleLateral on a shell's values is the
// trilinear value at that shell's radius.
TEST(Sampler, PartsCombineToLocateAndAShellSamplesAsTheVolume)
{
    const SphericalGrid g = centredGrid(18, 9, 36);
    std::vector<float> f(g.cellCount());
    for (size_t a = 0; a < g.nLat(); ++a)
        for (size_t b = 0; b < g.nR(); ++b)
            for (size_t c = 0; c < g.nLon(); ++c)
                f[g.index(a, b, c)] = float(std::sin(0.3 * double(a)) * g.rKm[b] + std::cos(0.2 * double(c)));
    const GridSampler s(g);
    const double r = 4321.0;
    const auto radial = *s.locateRadius(r);
    std::vector<double> shell(g.nLat() * g.nLon());
    for (size_t a = 0; a < g.nLat(); ++a)
        for (size_t c = 0; c < g.nLon(); ++c) {
            const double lo = f[g.index(a, radial.r0, c)], hi = f[g.index(a, radial.r1, c)];
            shell[a * g.nLon() + c] = lo + (hi - lo) * radial.tR;
        }
    for (const auto& [lat, lon] : {std::pair{12.3, 45.6}, {89.99, 200.0}, {-90.0, 0.0}, {0.0, 359.9}, {-45.0, -10.0}}) {
        const auto whole = *s.locate(lat, lon, r);
        const auto combined = GridSampler::combine(*s.locateLatLon(lat, lon), radial);
        EXPECT_EQ(whole.lat0, combined.lat0);
        EXPECT_EQ(whole.lon1, combined.lon1);
        EXPECT_EQ(whole.tLon, combined.tLon);
        EXPECT_EQ(whole.poleWeight, combined.poleWeight);
        const double onShell =
            s.sampleLateral([&](size_t a, size_t c) { return shell[a * g.nLon() + c]; }, *s.locateLatLon(lat, lon));
        EXPECT_NEAR(onShell, s.sample(f.data(), whole), 1e-9 * 5000) << lat << ", " << lon;
    }
    EXPECT_FALSE(s.locateRadius(3000));
    EXPECT_FALSE(s.locateLatLon(90.5, 0));
}

}  // namespace
}  // namespace raypc::grid
