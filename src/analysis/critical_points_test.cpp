#include "analysis/critical_points.h"

#include "core/error.h"
#include "core/spherical.h"
#include "io/netcdf_reader.h"
#include "analysis/persistence.h"
#include "grid/test_util.h"

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include <cmath>
#include <fstream>
#include <functional>
#include <random>

namespace raypc::analysis {
namespace {

using testing::centredGrid;
using testing::fillGrid;

// A Gaussian blob in Cartesian km (the contest fixture's shape).
std::vector<float> blob(const grid::SphericalGrid& g, double latDeg, double lonDeg, double rKm, double sigmaKm)
{
    return fillGrid(g, [&](size_t a, size_t b, size_t k) {
        return testing::gaussianBlob(g, a, b, k, latDeg, lonDeg, rKm, sigmaKm);
    });
}

std::vector<CriticalPoint> ofKind(const std::vector<CriticalPoint>& points, CriticalKind kind)
{
    std::vector<CriticalPoint> out;
    for (const auto& p : points)
        if (p.kind == kind)
            out.push_back(p);
    return out;
}

// Maxima of a blob field where it is not flat: far from the blob exp() underflows to 0 and the
// ties there are broken by index, which makes maxima of value 0.
std::vector<CriticalPoint> blobMaxima(const std::vector<CriticalPoint>& points)
{
    std::vector<CriticalPoint> out;
    for (const auto& p : ofKind(points, CriticalKind::Maximum))
        if (p.value > 1e-3f)
            out.push_back(p);
    return out;
}

int eulerSum(const grid::SphericalGrid& g, const std::vector<float>& v)
{
    int sum = 0;
    for (size_t i = 0; i < g.cellCount(); ++i)
        sum += lowerStarEulerContribution(g, v, i);
    return sum;
}

// Counting every simplex at its highest vertex gives the Euler characteristic of the triangulated
// domain, [lat rows] x [radii] x circle = 0, for any field: a check that the links (14 neighbours,
// their edges and triangles, wrapping across the seam, cut at the boundaries) fit together.
TEST(CriticalPoints, LowerStarsSumToTheSolidTorusEulerCharacteristic)
{
    const grid::SphericalGrid g = centredGrid(6, 5, 8);
    std::mt19937 rng(7);
    std::uniform_int_distribution<int> small(0, 3);  // many ties: Simulation of Simplicity decides
    std::uniform_real_distribution<float> real(-1, 1);
    EXPECT_EQ(eulerSum(g, fillGrid(g, [&](size_t, size_t, size_t) { return small(rng); })), 0);
    EXPECT_EQ(eulerSum(g, fillGrid(g, [&](size_t, size_t, size_t) { return real(rng); })), 0);
    EXPECT_EQ(eulerSum(g, std::vector<float>(g.cellCount(), 1.0f)), 0);
    // An interior vertex above all its neighbours: its lower link is the whole link, a sphere
    // (14 vertices - 36 edges + 24 triangles = 2), so it contributes 1 - 2.
    auto peak = fillGrid(g, [&](size_t a, size_t b, size_t c) { return a == 2 && b == 2 && c == 3 ? 1.0 : 0.0; });
    EXPECT_EQ(lowerStarEulerContribution(g, peak, g.index(2, 2, 3)), -1);
    // Below all its neighbours: the empty lower link contributes 1.
    for (auto& x : peak)
        x = -x;
    EXPECT_EQ(lowerStarEulerContribution(g, peak, g.index(2, 2, 3)), 1);
}

// With Simulation of Simplicity by index, a constant field is ordered by index: the sweep starts
// at index 0 (the minimum) and closes the first lon ring at index nLon-1 (a 1-saddle: its lower
// neighbours are the columns on either side, not connected in its link). Symmetrically, read from
// the top, the last index is the maximum and the first vertex of the last ring a 2-saddle (its
// upper neighbours are the columns on either side). Nothing else is critical.
TEST(CriticalPoints, ConstantFieldHasOnlyWhatSimulationOfSimplicityImplies)
{
    const grid::SphericalGrid g = centredGrid(6, 5, 8);
    const auto points = findCriticalPoints(g, std::vector<float>(g.cellCount(), 3.0f));
    ASSERT_EQ(points.size(), 4u);
    EXPECT_EQ(points[0].index, 0u);
    EXPECT_EQ(points[0].kind, CriticalKind::Minimum);
    EXPECT_EQ(points[1].index, g.nLon() - 1);
    EXPECT_EQ(points[1].kind, CriticalKind::Saddle1);
    EXPECT_EQ(points[2].index, g.cellCount() - g.nLon());
    EXPECT_EQ(points[2].kind, CriticalKind::Saddle2);
    EXPECT_EQ(points[3].index, g.cellCount() - 1);
    EXPECT_EQ(points[3].kind, CriticalKind::Maximum);
}

TEST(CriticalPoints, SingleGaussianHasOneMaximumAtItsCentre)
{
    const grid::SphericalGrid g = centredGrid(18, 21, 36);
    const auto values = blob(g, 25, 100, 4900, 800);  // (25, 100, 4909) is a grid point
    const auto maxima = blobMaxima(findCriticalPoints(g, values));
    ASSERT_EQ(maxima.size(), 1u);
    EXPECT_DOUBLE_EQ(maxima[0].latDeg, 25);
    EXPECT_DOUBLE_EQ(maxima[0].lonDeg, 100);
    EXPECT_NEAR(maxima[0].rKm, 4900, 0.5 * (g.rKm[1] - g.rKm[0]));
    EXPECT_EQ(maxima[0].lowerComponents, 1);
    EXPECT_EQ(maxima[0].upperComponents, 0);
}

// f = dLat² - 2 dR² + 3 dLon² around a vertex (index offsets): the lower link is the two
// opposite caps along r, so a 1-saddle; -f turns it into a 2-saddle. The coefficients differ so
// that no neighbour ties the centre (f(±1, ±1, 0) = -1, f(0, ±1, ±1) = 1).
TEST(CriticalPoints, QuadraticSaddlesOfBothKinds)
{
    const grid::SphericalGrid g = centredGrid(9, 9, 12);
    const size_t a0 = 4, b0 = 4, c0 = 6;
    for (const double sign : {1.0, -1.0}) {
        const auto values = fillGrid(g, [&](size_t a, size_t b, size_t c) {
            const double x = double(a) - a0, y = double(b) - b0, z = double(c) - c0;
            return sign * (x * x - 2 * y * y + 3 * z * z);
        });
        const auto points = findCriticalPoints(g, values);
        const auto it = std::find_if(points.begin(), points.end(),
                                     [&](const CriticalPoint& p) { return p.index == g.index(a0, b0, c0); });
        ASSERT_NE(it, points.end());
        EXPECT_EQ(it->kind, sign > 0 ? CriticalKind::Saddle1 : CriticalKind::Saddle2);
        EXPECT_EQ(sign > 0 ? it->lowerComponents : it->upperComponents, 2);
        // Nothing else is critical in the interior near it (the antipodal columns, where dLon jumps
        // from -6 to 5, are not smooth).
        for (const auto& p : points) {
            const size_t a = p.index / (g.nLon() * g.nR()), b = (p.index / g.nLon()) % g.nR(), c = p.index % g.nLon();
            if (p.index != it->index && a > 0 && a + 1 < g.nLat() && b > 0 && b + 1 < g.nR() && c >= 3 && c <= 9)
                ADD_FAILURE() << "unexpected interior " << criticalKindName(p.kind) << " at " << a << "," << b << ","
                              << c;
        }
    }
}

// The seam is an ordinary place: a blob centred on lon 0 or straddling it gives one maximum,
// in the right column, and no critical points from the wrap.
TEST(CriticalPoints, MaximumOnAndAcrossTheLonSeam)
{
    const grid::SphericalGrid g = centredGrid(18, 21, 36);
    for (const double lon : {0.0, 355.0, 357.0}) {
        const auto values = blob(g, -15, lon, 5200, 700);
        const auto maxima = blobMaxima(findCriticalPoints(g, values));
        ASSERT_EQ(maxima.size(), 1u) << lon;
        EXPECT_LE(lonSeparationDeg(maxima[0].lonDeg, lon), 5.0) << lon;  // within half a column
        EXPECT_DOUBLE_EQ(maxima[0].latDeg, -15);
    }
}

// Poles: the outermost row is a boundary of the triangulation. A blob next to the pole, or centred
// on it (all of the ring ties, Simulation of Simplicity picks one), gives one maximum on that row.
TEST(CriticalPoints, MaximumNextToAndOnAPole)
{
    const grid::SphericalGrid g = centredGrid(18, 21, 36);
    for (const double lat : {85.0, 88.0, -88.0, 90.0, -90.0}) {
        auto values = blob(g, lat, 40, 4500, 700);
        if (std::abs(lat) == 90) {
            // Centred on the pole: |p - c|² depends on lat and r only, so each ring ties exactly.
            const double rc = 4500, pole = lat > 0 ? 1 : -1;
            values = fillGrid(g, [&](size_t a, size_t b, size_t) {
                const double r = g.rKm[b];
                const double d2 = r * r + rc * rc - 2 * r * rc * pole * std::sin(degToRad(g.latDeg[a]));
                return std::exp(-d2 / (2 * 700.0 * 700.0));
            });
        }
        const auto maxima = blobMaxima(findCriticalPoints(g, values));
        ASSERT_EQ(maxima.size(), 1u) << lat;
        EXPECT_DOUBLE_EQ(maxima[0].latDeg, lat > 0 ? 85.0 : -85.0) << lat;
        if (std::abs(lat) < 90) {
            EXPECT_DOUBLE_EQ(maxima[0].lonDeg, 40);
        }
        EXPECT_GT(maxima[0].value, 0.85f) << lat;  // 5° (393 km) from the pole at most
        EXPECT_NEAR(maxima[0].rKm, 4500, g.rKm[1] - g.rKm[0]) << lat;
    }
}

TEST(CriticalPoints, SelectionKeepsTheSignificantAndCaps)
{
    std::vector<CriticalPoint> points;
    auto add = [&](CriticalKind kind, float value) {
        CriticalPoint p;
        p.index = points.size();
        p.kind = kind;
        p.value = value;
        points.push_back(p);
    };
    add(CriticalKind::Maximum, 100);   // kept
    add(CriticalKind::Maximum, 10);    // below the threshold
    add(CriticalKind::Maximum, -80);   // a maximum inside a cold region is not a hot feature
    add(CriticalKind::Minimum, -90);   // kept
    add(CriticalKind::Minimum, 60);    // a minimum inside a hot region
    add(CriticalKind::Saddle1, 30);    // kept
    add(CriticalKind::Saddle2, -29);   // below
    CriticalPointFilter filter;
    filter.minAbsValue = 30;
    filter.minFractionOfMaxAbs = 0.1;  // 0.1 * 100 = 10 < 30
    filter.saddles = true;             // not the default since seeds are chosen by persistence
    auto kept = selectSignificant(points, 100, filter);
    ASSERT_EQ(kept.size(), 3u);
    EXPECT_EQ(kept[0].value, 100);  // most extreme first
    EXPECT_EQ(kept[1].value, -90);
    EXPECT_EQ(kept[2].value, 30);
    filter.saddles = false;
    EXPECT_EQ(selectSignificant(points, 100, filter).size(), 2u);
    filter.maxCount = 1;
    EXPECT_EQ(selectSignificant(points, 100, filter).size(), 1u);
    filter = {};
    filter.minFractionOfMaxAbs = 0.95;  // threshold 95: only the 100
    EXPECT_EQ(selectSignificant(points, 100, filter).size(), 1u);
    // Noise: thousands of tiny extrema are capped.
    std::mt19937 rng(1);
    std::uniform_real_distribution<float> u(-1, 1);
    const grid::SphericalGrid g = centredGrid(18, 21, 36);
    std::vector<float> noise(g.cellCount());
    for (auto& x : noise)
        x = u(rng);
    const auto all = findCriticalPoints(g, noise);
    EXPECT_GT(all.size(), 1000u);
    EXPECT_EQ(selectSignificant(all, 1.0, CriticalPointFilter{}).size(), 200u);
}

// The contest fixture (written by Python, analytic truth.json): two hot and two cold blobs whose
// anomaly is taken relative to each shell's mean. Under both seed rules, a maximum at each positive
// blob and a minimum at each negative one, at the blob's position at the step's time, and no other
// significant extremum; by persistence (the default) nothing else at all, and the global pair's
// ends (the 400 K and -350 K blobs) first.
TEST(CriticalPoints, ContestFixtureBlobs)
{
    const auto truth = nlohmann::json::parse(std::ifstream(testing::contestLayoutDir() / "truth.json"));
    const double omega = truth["omega_rad_per_s"], u0 = truth["u0_m_per_s"], dt = truth["dt_myr"];
    const auto files = io::listSnapshotFiles({testing::contestLayoutDir()});
    ASSERT_EQ(files.size(), 3u);
    for (size_t step = 0; step < files.size(); ++step) {
        const grid::Snapshot snap = io::readSnapshot(files[step]);
        const auto& g = snap.grid;
        const auto& values = snap.find("temperature anomaly")->values;
        const auto all = findCriticalPoints(g, values);
        for (const SeedRule rule : {SeedRule::Value, SeedRule::Persistence}) {
            CriticalPointFilter filter;
            filter.rule = rule;
            filter.saddles = rule == SeedRule::Value;  // as before persistence
            const auto kept = selectSeeds(g, values, all, filter).seeds;
            const double ts = step * dt * kSecondsPerMyr;
            const double dLat = g.latDeg[1] - g.latDeg[0], dR = g.rKm[1] - g.rKm[0], dLon = g.lonDeg[1] - g.lonDeg[0];
            size_t extrema = 0;
            for (const auto& p : kept)
                extrema += p.kind == CriticalKind::Maximum || p.kind == CriticalKind::Minimum;
            const std::string where = fmt::format("step {}, {} rule", step, seedRuleName(rule));
            EXPECT_EQ(extrema, truth["blobs_lat_lon_rkm_amp_sigma"].size()) << where;
            for (const auto& b : truth["blobs_lat_lon_rkm_amp_sigma"]) {
                const double lat = b[0], lon = double(b[1]) + radToDeg(omega * ts), r = double(b[2]) + u0 * ts / 1000;
                const CriticalKind want = double(b[3]) > 0 ? CriticalKind::Maximum : CriticalKind::Minimum;
                int found = 0;
                for (const auto& p : kept)
                    if (p.kind == want && std::abs(p.latDeg - lat) <= dLat && lonSeparationDeg(p.lonDeg, lon) <= dLon &&
                        std::abs(p.rKm - r) <= dR)
                        ++found;
                EXPECT_EQ(found, 1) << where << ", blob at " << lat << ", " << lon << ", " << r;
            }
            if (rule == SeedRule::Persistence) {
                ASSERT_EQ(kept.size(), extrema) << where;
                EXPECT_GT(kept[0].value, 300) << where;
                EXPECT_LT(kept[1].value, -250) << where;
            }
        }
    }
}

TEST(CriticalPoints, RejectsWrongSizes)
{
    const grid::SphericalGrid g = centredGrid(6, 5, 8);
    EXPECT_THROW(findCriticalPoints(g, std::vector<float>(10)), Error);
    EXPECT_THROW(findCriticalPoints(centredGrid(1, 5, 8), std::vector<float>(40)), Error);
}

}  // namespace
}  // namespace raypc::analysis
