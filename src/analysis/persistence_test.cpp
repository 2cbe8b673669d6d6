#include "analysis/persistence.h"

#include "core/error.h"
#include "core/spherical.h"
#include "grid/test_util.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <functional>
#include <map>
#include <numbers>
#include <numeric>
#include <random>
#include <set>
#include <tuple>

namespace raypc::analysis {
namespace {

using testing::centredGrid;
using testing::fillGrid;
using testing::gaussianBlob;

struct Blob {
    size_t iLat, iR, iLon;  // centred on this grid point
    double amplitude, sigmaKm;
};

// Sum of blobs centred on grid points, plus uniform noise in [-noise, noise].
std::vector<float> blobField(const grid::SphericalGrid& g, const std::vector<Blob>& blobs, double noise, unsigned seed = 1)
{
    std::mt19937 rng(seed);
    std::uniform_real_distribution<double> u(-noise, noise);
    return fillGrid(g, [&](size_t a, size_t b, size_t c) {
        double sum = noise > 0 ? u(rng) : 0.0;
        for (const auto& bl : blobs)
            sum += bl.amplitude *
                   gaussianBlob(g, a, b, c, g.latDeg[bl.iLat], g.lonDeg[bl.iLon], g.rKm[bl.iR], bl.sigmaKm);
        return sum;
    });
}

// Field `kind` of three on `g`: 0 small integers 0..maxInteger (many ties, which Simulation of
// Simplicity decides by index), 1 uniform in [-1, 1), 2 `smooth` of the indices (lat, r, lon) and
// a uniform number in [-1, 1).
std::vector<float> testField(const grid::SphericalGrid& g, int kind, std::mt19937& rng, int maxInteger,
                             const std::function<double(size_t, size_t, size_t, double)>& smooth)
{
    std::uniform_int_distribution<int> small(0, maxInteger);
    std::uniform_real_distribution<float> real(-1, 1);
    return fillGrid(g, [&](size_t a, size_t b, size_t c) {
        if (kind == 0)
            return double(small(rng));
        if (kind == 1)
            return double(real(rng));
        return smooth(a, b, c, real(rng));
    });
}

std::vector<PersistencePair> above(const std::vector<PersistencePair>& pairs, double threshold)
{
    std::vector<PersistencePair> out;
    for (const auto& p : pairs)
        if (p.persistence() > threshold)
            out.push_back(p);
    return out;
}

// Grid steps between two indices along each axis (lon on the circle).
std::array<size_t, 3> stepsApart(const grid::SphericalGrid& g, size_t i, size_t j)
{
    const size_t nLon = g.nLon(), nR = g.nR();
    auto split = [&](size_t k) { return std::array<size_t, 3>{k / (nLon * nR), (k / nLon) % nR, k % nLon}; };
    const auto a = split(i), b = split(j);
    auto apart = [](size_t x, size_t y) { return x > y ? x - y : y - x; };
    return {apart(a[0], b[0]), apart(a[1], b[1]), std::min(apart(a[2], b[2]), nLon - apart(a[2], b[2]))};
}

bool near(const grid::SphericalGrid& g, size_t i, size_t j, size_t steps = 1)
{
    const auto d = stepsApart(g, i, j);
    return d[0] <= steps && d[1] <= steps && d[2] <= steps;
}

// The textbook algorithm, independent of the forest shortcut: every vertex in (value, index)
// order, union with every lower neighbour (Freudenthal: offsets whose components are all >= 0 or
// all <= 0), elder rule at each merge. Returns (kind, birth index, death index) of every pair.
std::multiset<std::tuple<int, size_t, size_t>> textbookPairs(const grid::SphericalGrid& g, const std::vector<float>& v)
{
    const size_t n = g.cellCount();
    std::vector<size_t> order(n);
    std::iota(order.begin(), order.end(), 0);
    auto lowerThan = [&](size_t a, size_t b) { return v[a] < v[b] || (v[a] == v[b] && a < b); };
    std::multiset<std::tuple<int, size_t, size_t>> out;
    for (const bool up : {false, true}) {
        std::sort(order.begin(), order.end(),
                  [&](size_t a, size_t b) { return up ? lowerThan(b, a) : lowerThan(a, b); });
        std::vector<size_t> parent(n), rank(n);
        for (size_t k = 0; k < n; ++k)
            rank[order[k]] = k;
        std::vector<bool> seen(n, false);
        std::iota(parent.begin(), parent.end(), 0);
        auto find = [&](size_t x) {
            while (parent[x] != x)
                x = parent[x] = parent[parent[x]];
            return x;
        };
        for (const size_t x : order) {
            const long a = long(x / (g.nLon() * g.nR())), b = long((x / g.nLon()) % g.nR()), c = long(x % g.nLon());
            for (int da = -1; da <= 1; ++da)
                for (int db = -1; db <= 1; ++db)
                    for (int dc = -1; dc <= 1; ++dc) {
                        const bool allNonNeg = da >= 0 && db >= 0 && dc >= 0, allNonPos = da <= 0 && db <= 0 && dc <= 0;
                        if (!(allNonNeg || allNonPos) || (da == 0 && db == 0 && dc == 0))
                            continue;
                        if (a + da < 0 || a + da >= long(g.nLat()) || b + db < 0 || b + db >= long(g.nR()))
                            continue;
                        const size_t lon = size_t(c + dc + long(g.nLon())) % g.nLon();
                        const size_t y = g.index(size_t(a + da), size_t(b + db), lon);
                        if (!seen[y])
                            continue;
                        const size_t rx = find(x), ry = find(y);
                        if (rx == ry)
                            continue;
                        // Roots are their components' first vertices. The younger dies at x, unless
                        // it is x itself, not yet in any component (x then just joins y's).
                        const size_t older = rank[rx] < rank[ry] ? rx : ry, younger = older == rx ? ry : rx;
                        if (younger != x)
                            out.insert(up ? std::tuple<int, size_t, size_t>{1, x, younger}
                                          : std::tuple<int, size_t, size_t>{0, younger, x});
                        parent[younger] = older;
                    }
            seen[x] = true;
        }
    }
    return out;
}

// The forest shortcut gives exactly the pairs of the plain sweep, on fields with many ties (so
// Simulation of Simplicity decides), on smooth and on rough ones, and across the seam. The pair
// counts agree with the critical points: (#minima - 1) + (#maxima - 1) + 1.
TEST(Persistence, SameAsTheTextbookSweep)
{
    std::mt19937 rng(3);
    for (const auto& g :
         {centredGrid(6, 5, 8), centredGrid(7, 6, 3), centredGrid(12, 9, 16), centredGrid(20, 15, 30)}) {
        for (int field = 0; field < 3; ++field) {
            const auto v = testField(g, field, rng, 4, [&](size_t a, size_t b, size_t c, double noise) {
                return std::sin(0.9 * a) * std::cos(1.7 * b) + std::sin(2 * std::numbers::pi * c / g.nLon()) + 0.05 * noise;
            });
            const auto pairs = persistencePairs(g, v);
            std::multiset<std::tuple<int, size_t, size_t>> got;
            size_t globals = 0;
            for (const auto& p : pairs) {
                EXPECT_LE(p.birth, p.death);
                EXPECT_EQ(p.birth, v[p.birthIndex]);
                EXPECT_EQ(p.death, v[p.deathIndex]);
                if (p.kind == PairKind::Global)
                    ++globals;
                else
                    got.insert({int(p.kind), p.birthIndex, p.deathIndex});
            }
            EXPECT_EQ(globals, 1u);
            EXPECT_EQ(got, textbookPairs(g, v))
                << "grid " << g.nLat() << "x" << g.nR() << "x" << g.nLon() << ", field " << field;
            std::map<CriticalKind, size_t> counts;
            for (const auto& p : findCriticalPoints(g, v))
                ++counts[p.kind];
            size_t minPairs = 0, maxPairs = 0;
            for (const auto& p : pairs) {
                minPairs += p.kind == PairKind::MinimumSaddle;
                maxPairs += p.kind == PairKind::SaddleMaximum;
            }
            EXPECT_EQ(minPairs + 1, counts[CriticalKind::Minimum]);
            EXPECT_EQ(maxPairs + 1, counts[CriticalKind::Maximum]);
            // By decreasing persistence.
            for (size_t k = 1; k < pairs.size(); ++k)
                EXPECT_GE(pairs[k - 1].persistence(), pairs[k].persistence());
        }
    }
}

// Gaussian blobs of known amplitudes on small noise: exactly one pair per blob stands above a
// threshold above the noise, at the blob's centre, with the blob's amplitude as persistence (the
// blob rises from a background at noise level); the global maximum and minimum form the
// essential pair, whose persistence is the range.
TEST(Persistence, BlobsOnNoiseGiveOnePairEachWithTheirAmplitude)
{
    const grid::SphericalGrid g = centredGrid(36, 41, 72);
    const std::vector<Blob> blobs = {{24, 20, 12, 1000, 600}, {10, 14, 40, 600, 600}, {18, 32, 62, 300, 600},
                                     {16, 8, 26, -800, 600},  {30, 28, 50, -400, 600}};
    const double noise = 0.5;
    const auto v = blobField(g, blobs, noise);
    const auto pairs = persistencePairs(g, v);
    EXPECT_GT(pairs.size(), 1000u);  // the noise makes many pairs ...
    const auto strong = above(pairs, 10 * noise);  // ... all below a threshold above its level
    ASSERT_EQ(strong.size(), 4u);
    auto centre = [&](const Blob& b) { return g.index(b.iLat, b.iR, b.iLon); };
    // The essential pair: the 1000 K maximum and the -800 K minimum.
    EXPECT_EQ(strong[0].kind, PairKind::Global);
    EXPECT_TRUE(near(g, strong[0].deathIndex, centre(blobs[0])));
    EXPECT_TRUE(near(g, strong[0].birthIndex, centre(blobs[3])));
    EXPECT_NEAR(strong[0].persistence(), 1800, 0.01 * 1800);
    // The others: (saddle, 600 K maximum), (-400 K minimum, saddle), (saddle, 300 K maximum).
    const std::vector<std::pair<PairKind, size_t>> want = {
        {PairKind::SaddleMaximum, 1}, {PairKind::MinimumSaddle, 4}, {PairKind::SaddleMaximum, 2}};
    for (size_t k = 0; k < want.size(); ++k) {
        const auto& p = strong[k + 1];
        const Blob& b = blobs[want[k].second];
        EXPECT_EQ(p.kind, want[k].first) << k;
        EXPECT_TRUE(near(g, p.extremumIndex(), centre(b))) << k;
        EXPECT_NEAR(p.persistence(), std::abs(b.amplitude), 0.01 * std::abs(b.amplitude)) << k;
        // The saddle lies in the background, not on the blob.
        const size_t saddle = p.kind == PairKind::MinimumSaddle ? p.deathIndex : p.birthIndex;
        EXPECT_LT(std::abs(v[saddle]), 2 * noise) << k;
    }
    // Seeds: the five extrema, by decreasing persistence (the essential pair's two first).
    CriticalPointFilter filter;
    parsePersistenceThreshold("10", filter);
    const auto all = findCriticalPoints(g, v);
    const auto sel = selectSeeds(g, v, all, filter);
    EXPECT_EQ(sel.threshold, 10);
    ASSERT_EQ(sel.seeds.size(), 5u);
    const std::vector<size_t> order = {0, 3, 1, 4, 2};
    for (size_t k = 0; k < order.size(); ++k) {
        EXPECT_TRUE(near(g, sel.seeds[k].index, centre(blobs[order[k]]))) << k;
        EXPECT_EQ(sel.seeds[k].kind, blobs[order[k]].amplitude > 0 ? CriticalKind::Maximum : CriticalKind::Minimum);
    }
    EXPECT_NEAR(sel.seeds[4].persistence, 300, 3);
    // A threshold between the amplitudes drops the weaker blobs; 20% of the 1800 K range is 360 K.
    parsePersistenceThreshold("20%", filter);
    const auto fewer = selectSeeds(g, v, all, filter);
    EXPECT_NEAR(fewer.threshold, 0.2 * strong[0].persistence(), 1e-9);
    EXPECT_EQ(fewer.seeds.size(), 4u);  // 1000, -800, 600, -400
    // With saddles: each non-essential kept extremum brings its saddle.
    filter.saddles = true;
    const auto withSaddles = selectSeeds(g, v, all, filter);
    ASSERT_EQ(withSaddles.seeds.size(), 6u);
    size_t saddles = 0;
    for (const auto& s : withSaddles.seeds)
        saddles += s.kind != CriticalKind::Maximum && s.kind != CriticalKind::Minimum;
    EXPECT_EQ(saddles, 2u);
    filter.maxCount = 3;
    EXPECT_EQ(selectSeeds(g, v, all, filter).seeds.size(), 3u);
}

// Noise alone: every pair, the essential one included, has at most the noise's range as
// persistence, so a threshold above the noise level selects nothing.
TEST(Persistence, NoiseAloneGivesNoPairAboveItsLevel)
{
    const grid::SphericalGrid g = centredGrid(18, 21, 36);
    const double noise = 2.0;
    const auto v = blobField(g, {}, noise, 7);
    const auto pairs = persistencePairs(g, v);
    EXPECT_GT(pairs.size(), 500u);
    EXPECT_LE(pairs.front().persistence(), 2 * noise);
    CriticalPointFilter filter;
    parsePersistenceThreshold("4.5", filter);
    EXPECT_TRUE(selectSeeds(g, v, findCriticalPoints(g, v), filter).seeds.empty());
    // Relative to the range, the threshold follows the noise: noise alone then does make seeds.
    parsePersistenceThreshold("5%", filter);
    EXPECT_GT(selectSeeds(g, v, findCriticalPoints(g, v), filter).seeds.size(), 10u);
}

// Two blobs on one radial column, A1 = 1000 K and A2 = 600 K, 1300 km apart: the smaller one's
// maximum dies at the saddle between them, the minimum of A1 exp(-x²/2σ²) + A2 exp(-(D-x)²/2σ²)
// along the segment (found here by golden-section search), where the PL saddle is the column's
// grid point nearest to it.
TEST(Persistence, TwoBlobsPairTheSmallerWithTheSaddleBetweenThem)
{
    const grid::SphericalGrid g = centredGrid(36, 41, 72);
    const Blob big{20, 8, 30, 1000, 400}, small{20, 26, 30, 600, 400};
    const auto v = blobField(g, {big, small}, 0);
    const double d = g.rKm[small.iR] - g.rKm[big.iR], s2 = 2 * 400.0 * 400.0;
    auto line = [&](double x) { return 1000 * std::exp(-x * x / s2) + 600 * std::exp(-(d - x) * (d - x) / s2); };
    double lo = 0, hi = d;
    for (int k = 0; k < 200; ++k) {
        const double m1 = lo + (hi - lo) * 0.381966, m2 = hi - (hi - lo) * 0.381966;
        if (line(m1) < line(m2))
            hi = m2;
        else
            lo = m1;
    }
    const double saddleX = 0.5 * (lo + hi), saddleValue = line(saddleX);
    const double analytic = line(d) - saddleValue;  // the smaller blob's peak (with the other's tail) minus the saddle
    ASSERT_GT(saddleValue, 1.0);  // a real pass between the blobs, not the empty background

    const auto pairs = above(persistencePairs(g, v), 1.0);
    ASSERT_EQ(pairs.size(), 2u);
    EXPECT_EQ(pairs[0].kind, PairKind::Global);
    EXPECT_EQ(pairs[0].deathIndex, g.index(big.iLat, big.iR, big.iLon));
    const auto& p = pairs[1];
    EXPECT_EQ(p.kind, PairKind::SaddleMaximum);
    EXPECT_EQ(p.deathIndex, g.index(small.iLat, small.iR, small.iLon));
    EXPECT_EQ(p.birthKind, CriticalKind::Saddle2);
    EXPECT_NEAR(p.persistence(), analytic, 0.01 * analytic);
    // The saddle sits on the column, at the grid radius nearest to the analytic one.
    const size_t iR = (p.birthIndex / g.nLon()) % g.nR();
    EXPECT_EQ(p.birthIndex, g.index(big.iLat, iR, big.iLon));
    EXPECT_LE(std::abs(g.rKm[iR] - (g.rKm[big.iR] + saddleX)), g.rKm[1] - g.rKm[0]);
}

// The essential class: a field that only rises with radius has one minimum and one maximum that
// matter (the others are ties broken by index, of zero persistence); they form the global pair,
// whose persistence is the range, and it is the only pair with positive persistence.
TEST(Persistence, GlobalPairOfARamp)
{
    const grid::SphericalGrid g = centredGrid(6, 5, 8);
    const auto v = fillGrid(g, [&](size_t, size_t b, size_t) { return g.rKm[b]; });
    const auto pairs = persistencePairs(g, v);
    const auto positive = above(pairs, 0);
    ASSERT_EQ(positive.size(), 1u);
    EXPECT_EQ(positive[0].kind, PairKind::Global);
    EXPECT_EQ(positive[0].birthIndex, 0u);                   // lowest index of the inner shell
    EXPECT_EQ(positive[0].deathIndex, g.cellCount() - 1);  // highest of the outer shell
    EXPECT_DOUBLE_EQ(positive[0].persistence(), float(kSurfaceRadiusKm) - float(kCoreRadiusKm));
    EXPECT_EQ(positive[0].birthKind, CriticalKind::Minimum);
    EXPECT_EQ(positive[0].deathKind, CriticalKind::Maximum);
}

// The seam and the poles are ordinary places: a blob across lon 0 or centred on a pole is one
// feature with one pair of its amplitude (at the pole: the value of the outermost row, where
// the blob is highest on the grid), not two halves joined far away.
TEST(Persistence, BlobAcrossTheSeamAndOnThePoles)
{
    const grid::SphericalGrid g = centredGrid(36, 41, 72);  // lat rows at ±87.5, lon columns every 5°
    const double sigma = 700, rBlob = g.rKm[20];
    const Blob reference{12, 20, 36, 1000, 600};  // the global maximum, far from both
    for (const double lon : {0.0, 357.5}) {
        auto v = blobField(g, {reference}, 0.5);
        for (size_t a = 0; a < g.nLat(); ++a)
            for (size_t b = 0; b < g.nR(); ++b)
                for (size_t c = 0; c < g.nLon(); ++c)
                    v[g.index(a, b, c)] += float(500 * gaussianBlob(g, a, b, c, g.latDeg[24], lon, rBlob, sigma));
        const auto strong = above(persistencePairs(g, v), 10);
        ASSERT_EQ(strong.size(), 2u) << lon;
        const auto& p = strong[1];
        EXPECT_EQ(p.kind, PairKind::SaddleMaximum);
        const size_t iLon = p.deathIndex % g.nLon();
        EXPECT_TRUE(iLon == 0 || iLon == g.nLon() - 1) << lon << ": column " << iLon;
        // At 357.5° the blob is centred between two columns, 2.5° (~220 km at this radius and latitude) from either.
        const double peak = 500 * gaussianBlob(g, 24, 20, iLon, g.latDeg[24], lon, rBlob, sigma);
        EXPECT_NEAR(p.persistence(), peak, 0.01 * peak) << lon;
    }
    for (const double pole : {90.0, -90.0}) {
        // Centred on the pole: |p - c|² depends on lat and r only, so each ring ties exactly.
        auto v = blobField(g, {reference}, 0.5);
        const double rc = rBlob;
        for (size_t a = 0; a < g.nLat(); ++a)
            for (size_t b = 0; b < g.nR(); ++b)
                for (size_t c = 0; c < g.nLon(); ++c) {
                    const double r = g.rKm[b];
                    const double sinLat = (pole > 0 ? 1 : -1) * std::sin(degToRad(g.latDeg[a]));
                    const double d2 = r * r + rc * rc - 2 * r * rc * sinLat;
                    v[g.index(a, b, c)] += float(500 * std::exp(-d2 / (2 * sigma * sigma)));
                }
        const auto strong = above(persistencePairs(g, v), 10);
        ASSERT_EQ(strong.size(), 2u) << pole;
        const auto& p = strong[1];
        const size_t iLat = p.deathIndex / (g.nLon() * g.nR());
        EXPECT_EQ(iLat, pole > 0 ? g.nLat() - 1 : 0u) << pole;
        const double ring = 2 * rc * std::sin(degToRad(2.5) / 2);  // chord from the pole to the outermost row
        const double peak = 500 * std::exp(-ring * ring / (2 * sigma * sigma));
        EXPECT_NEAR(p.persistence(), peak, 0.01 * peak) << pole;
    }
}

TEST(Persistence, ThresholdOptions)
{
    CriticalPointFilter f;
    EXPECT_EQ(f.rule, SeedRule::Persistence);
    parsePersistenceThreshold("5%", f);
    EXPECT_DOUBLE_EQ(f.minPersistence, 0.05);
    EXPECT_TRUE(f.persistenceIsFraction);
    parsePersistenceThreshold("30", f);
    EXPECT_DOUBLE_EQ(f.minPersistence, 30);
    EXPECT_FALSE(f.persistenceIsFraction);
    parsePersistenceThreshold("0", f);
    EXPECT_EQ(f.minPersistence, 0);
    for (const char* bad : {"", "%", "abc", "-3", "150%", "5 %", "30K", "nan", "1e999"})
        EXPECT_THROW(parsePersistenceThreshold(bad, f), Error) << bad;
    try {
        parsePersistenceThreshold("abc", f);
    } catch (const Error& e) {
        EXPECT_NE(std::string(e.what()).find("--cp-persistence"), std::string::npos);
    }
    EXPECT_EQ(parseSeedRule("value"), SeedRule::Value);
    EXPECT_EQ(parseSeedRule("persistence"), SeedRule::Persistence);
    EXPECT_THROW(parseSeedRule("top"), Error);
    f.minPersistence = -1;
    EXPECT_THROW(checkCriticalPointFilter(f), Error);
}

// The value rule is still there: selectSeeds then applies selectSignificant.
TEST(Persistence, ValueRuleIsTheOldSelection)
{
    const grid::SphericalGrid g = centredGrid(18, 21, 36);
    const auto v = blobField(g, {{6, 10, 5, 100, 600}, {12, 4, 20, -50, 600}}, 1.0);
    const auto all = findCriticalPoints(g, v);
    CriticalPointFilter f;
    f.rule = SeedRule::Value;
    f.saddles = true;
    const auto sel = selectSeeds(g, v, all, f);
    float maxAbs = 0;
    for (const float x : v)
        maxAbs = std::max(maxAbs, std::abs(x));
    const auto old = selectSignificant(all, maxAbs, f);
    ASSERT_EQ(sel.seeds.size(), old.size());
    for (size_t k = 0; k < old.size(); ++k)
        EXPECT_EQ(sel.seeds[k].index, old[k].index);
    EXPECT_DOUBLE_EQ(sel.threshold, significanceThreshold(f, maxAbs));
}

// The one pass over the links (criticalStructure) gives the points of findCriticalPoints and the
// pairs of persistencePairs, field for field, on noise with blobs (thousands of each, every kind),
// and the seeds both ways chosen are the same, by either rule.
TEST(Persistence, OnePassGivesThePointsAndPairsOfBoth)
{
    const grid::SphericalGrid g = centredGrid(36, 41, 72);
    const auto v = blobField(g, {{24, 20, 12, 1000, 600}, {16, 8, 26, -800, 600}, {2, 30, 70, 300, 600}}, 0.5, 3);
    const CriticalStructure one = criticalStructure(g, v);
    const auto points = findCriticalPoints(g, v);
    const auto pairs = persistencePairs(g, v);
    ASSERT_GT(points.size(), 1000u);
    ASSERT_EQ(one.points.size(), points.size());
    std::set<CriticalKind> kinds;
    for (size_t k = 0; k < points.size(); ++k) {
        const CriticalPoint &a = one.points[k], &b = points[k];
        kinds.insert(b.kind);
        EXPECT_TRUE(a.index == b.index && a.kind == b.kind && a.value == b.value &&
                    a.lowerComponents == b.lowerComponents && a.upperComponents == b.upperComponents &&
                    a.latDeg == b.latDeg && a.lonDeg == b.lonDeg && a.rKm == b.rKm)
            << "point " << k << " at index " << b.index;
    }
    EXPECT_GE(kinds.size(), 4u);
    ASSERT_EQ(one.pairs.size(), pairs.size());
    for (size_t k = 0; k < pairs.size(); ++k)
        EXPECT_TRUE(one.pairs[k].kind == pairs[k].kind && one.pairs[k].birthIndex == pairs[k].birthIndex &&
                    one.pairs[k].deathIndex == pairs[k].deathIndex)
            << "pair " << k;
    for (const SeedRule rule : {SeedRule::Persistence, SeedRule::Value}) {
        CriticalPointFilter f;
        f.rule = rule;
        f.saddles = true;
        const auto a = selectSeedsFrom(g, v, one, f), b = selectSeeds(g, v, points, f);
        ASSERT_EQ(a.seeds.size(), b.seeds.size());
        EXPECT_GT(a.seeds.size(), 1u);
        EXPECT_EQ(a.threshold, b.threshold);
        for (size_t k = 0; k < a.seeds.size(); ++k)
            EXPECT_TRUE(a.seeds[k].index == b.seeds[k].index && a.seeds[k].persistence == b.seeds[k].persistence) << k;
    }
}

// The one pass works the rows off the boundaries and the seam neighbour by neighbour (InteriorRow):
// on fields with many ties (Simulation of Simplicity decides by index), rough and smooth, its
// critical points are those findCriticalPoints finds vertex by vertex, and its pairs the plain
// sweep's.
TEST(Persistence, InteriorRowsGiveWhatEachVertexAloneGives)
{
    std::mt19937 rng(7);
    for (const auto& g : {centredGrid(5, 4, 3), centredGrid(9, 7, 13), centredGrid(16, 11, 24)}) {
        for (int field = 0; field < 3; ++field) {
            const auto v = testField(g, field, rng, 2, [](size_t a, size_t b, size_t c, double) {
                return std::round(4 * (std::sin(0.9 * a) * std::cos(1.7 * b) + std::sin(0.5 * c))) / 4;
            });
            const CriticalStructure one = criticalStructure(g, v);
            const auto points = findCriticalPoints(g, v);
            ASSERT_EQ(one.points.size(), points.size()) << "field " << field;
            for (size_t k = 0; k < points.size(); ++k)
                EXPECT_TRUE(one.points[k].index == points[k].index && one.points[k].kind == points[k].kind &&
                            one.points[k].lowerComponents == points[k].lowerComponents &&
                            one.points[k].upperComponents == points[k].upperComponents)
                    << "field " << field << ", point " << k << " at index " << points[k].index;
            std::multiset<std::tuple<int, size_t, size_t>> got;
            for (const auto& p : one.pairs)
                if (p.kind != PairKind::Global)
                    got.insert({int(p.kind), p.birthIndex, p.deathIndex});
            EXPECT_EQ(got, textbookPairs(g, v)) << "field " << field;
        }
    }
}

TEST(Persistence, RejectsWrongSizes)
{
    const grid::SphericalGrid g = centredGrid(6, 5, 8);
    EXPECT_THROW(persistencePairs(g, std::vector<float>(10)), Error);
    EXPECT_THROW(persistencePairs(centredGrid(6, 1, 8), std::vector<float>(48)), Error);
    EXPECT_THROW(selectSeeds(g, std::vector<float>(10), {}, CriticalPointFilter{}), Error);
}

}  // namespace
}  // namespace raypc::analysis
