// Truth of the shell comparisons (shell_compare.h, spherical_harmonics.h) on analytic fields: the
// 4π-normalised real harmonics Ȳ_lm, written here from the associated Legendre functions of the C++
// standard library (std::assoc_legendre), not from libsharp.
#include "analysis/shell_compare.h"

#include "core/error.h"
#include "core/spherical.h"
#include "grid/test_util.h"

#include <gtest/gtest.h>

#include <cmath>
#include <numbers>

namespace raypc::analysis {
namespace {

constexpr double kDeg = std::numbers::pi / 180.0;

// Ȳ_lm at (lat, lon) degrees: sqrt((2 - δ_m0)(2l + 1)(l - m)!/(l + m)!) P_lm(sin lat) cos(m lon) for
// m >= 0, sin(|m| lon) for m < 0; 1/4π ∫ Ȳ_lm² dΩ = 1.
double ybar(int l, int m, double latDeg, double lonDeg)
{
    const int am = std::abs(m);
    double ratio = 1;  // (l - |m|)! / (l + |m|)!
    for (int k = l - am + 1; k <= l + am; ++k)
        ratio /= k;
    const double norm = std::sqrt((am == 0 ? 1.0 : 2.0) * (2 * l + 1) * ratio);
    const double p = std::assoc_legendre(unsigned(l), unsigned(am), std::sin(latDeg * kDeg));
    return norm * p * (m >= 0 ? std::cos(am * lonDeg * kDeg) : std::sin(am * lonDeg * kDeg));
}

// A sum of amplitude x Ȳ_lm on every shell (the same on each, scaled by 1 + iR so that shells differ).
struct Term {
    int l, m;
    double amplitude;
};
std::vector<float> harmonics(const grid::SphericalGrid& g, std::initializer_list<Term> terms, double lonShiftDeg = 0)
{
    std::vector<Term> t(terms);
    return testing::fillGrid(g, [&](size_t iLat, size_t iR, size_t iLon) {
        double v = 0;
        for (const Term& term : t)
            v += term.amplitude * ybar(term.l, term.m, g.latDeg[iLat], g.lonDeg[iLon] + lonShiftDeg);
        return (1.0 + double(iR)) * v;
    });
}

grid::SphericalGrid poleGrid(size_t nLat, size_t nR, size_t nLon, double lon0Deg = 0)
{
    grid::SphericalGrid g = testing::centredGrid(nLat, nR, nLon);
    for (size_t i = 0; i < nLat; ++i)
        g.latDeg[i] = -90.0 + double(i) * 180.0 / double(nLat - 1);
    for (size_t i = 0; i < nLon; ++i)
        g.lonDeg[i] = lon0Deg + double(i) * 360.0 / double(nLon);
    return g;
}

TEST(SphericalHarmonics, QuadratureFromTheRows)
{
    EXPECT_EQ(quadratureOf(testing::centredGrid(36, 2, 72)), SphereQuadrature::Fejer1);
    EXPECT_EQ(quadratureOf(poleGrid(37, 2, 72)), SphereQuadrature::ClenshawCurtis);
    grid::SphericalGrid uneven = testing::centredGrid(36, 2, 72);
    uneven.latDeg[10] += 1.0;
    EXPECT_EQ(quadratureOf(uneven), SphereQuadrature::AreaWeights);
    EXPECT_EQ(maxDegree(testing::centredGrid(36, 2, 72)), 17);
    EXPECT_EQ(maxDegree(poleGrid(181, 2, 360)), 90);
}

// A field A Ȳ_lm has power A² at degree l and none elsewhere, on both exact quadratures and with any
// first longitude.
TEST(SphericalHarmonics, SingleHarmonicHasPowerOnlyAtItsDegree)
{
    for (const grid::SphericalGrid& g : {testing::centredGrid(36, 2, 72), poleGrid(37, 2, 72, 2.5)}) {
        for (const Term term : {Term{0, 0, 1.5}, Term{2, 0, 2.5}, Term{3, 1, -0.7}, Term{5, -3, 4.0}, Term{8, 8, 1.0}}) {
            const std::vector<float> v = harmonics(g, {term});
            const ShellSpectra s = shellSpectra(g, v.data(), 12, "field");
            ASSERT_EQ(s.lmax, 12);
            for (size_t iR = 0; iR < g.nR(); ++iR) {
                const double a2 = std::pow(term.amplitude * (1.0 + double(iR)), 2);
                for (int l = 0; l <= 12; ++l) {
                    if (l == term.l)
                        EXPECT_NEAR(s.at(iR, l), a2, 1e-6 * a2) << "l " << term.l << " m " << term.m << " quadrature "
                                                                 << quadratureName(s.quadrature);
                    else
                        EXPECT_LT(s.at(iR, l), 1e-10 * a2) << "degree " << l << " of Y_" << term.l << "^" << term.m;
                }
            }
        }
    }
}

// Rows of any other spacing: libsharp's general geometry with the dual cells' areas, approximate.
TEST(SphericalHarmonics, UnevenRowsUseAreaWeights)
{
    grid::SphericalGrid g = testing::centredGrid(60, 1, 72);
    for (size_t i = 0; i < g.nLat(); ++i)
        g.latDeg[i] = std::asin(-1.0 + (double(i) + 0.5) * 2.0 / double(g.nLat())) / kDeg;  // equal-area rows
    const std::vector<float> v = harmonics(g, {{3, 2, 2.0}});
    const ShellSpectra s = shellSpectra(g, v.data(), 10, "field");
    EXPECT_EQ(s.quadrature, SphereQuadrature::AreaWeights);
    EXPECT_NEAR(s.at(0, 3), 4.0, 0.02 * 4.0);
    for (const int l : {0, 1, 2, 4, 6, 8})
        EXPECT_LT(s.at(0, l), 0.01 * 4.0) << "degree " << l;
}

// The sum of the powers is the mean square over the sphere.
TEST(SphericalHarmonics, PowerSumsToTheMeanSquare)
{
    const grid::SphericalGrid g = testing::centredGrid(36, 1, 72);
    const std::vector<float> v = harmonics(g, {{0, 0, 1.0}, {2, 1, 0.5}, {4, -2, 0.25}});
    const ShellSpectra s = shellSpectra(g, v.data(), 17, "field");
    double sum = 0;
    for (int l = 0; l <= 17; ++l)
        sum += s.at(0, l);
    EXPECT_NEAR(sum, 1.0 + 0.25 + 0.0625, 1e-6);
}

// Filtering to L keeps the degrees up to L exactly and removes those above.
TEST(SphericalHarmonics, LowPassRemovesDegreesAboveL)
{
    const grid::SphericalGrid g = testing::centredGrid(36, 1, 72);
    const std::vector<float> v = harmonics(g, {{2, 0, 1.0}, {8, 3, 0.5}, {12, -5, 0.3}});
    const std::vector<float> low = harmonics(g, {{2, 0, 1.0}});
    const ShellTransform t(g, 5, "filter");
    std::vector<std::complex<double>> alm;
    t.analyse(v.data(), 0, alm);
    std::vector<double> shell;
    t.synthesiseShell(alm, shell);
    for (size_t i = 0; i < shell.size(); ++i)
        ASSERT_NEAR(shell[i], low[i], 1e-5) << "point " << i;
    // Correlated after the filter, the Y_2^0 part alone is left of each.
    const std::vector<float> other = harmonics(g, {{2, 0, -3.0}, {8, 3, 2.0}});
    const auto raw = correlateShells(g, v.data(), other.data(), {}, "test");
    const auto filtered = correlateShells(g, v.data(), other.data(), {5}, "test");
    EXPECT_GT(raw[0].correlation, -0.9);
    EXPECT_NEAR(filtered[0].correlation, -1.0, 1e-6);
    EXPECT_NEAR(filtered[0].rmsRatio, 1.0 / 3.0, 1e-4);
}

TEST(ShellCorrelation, SelfNegativeAndOrthogonalHarmonics)
{
    const grid::SphericalGrid g = testing::centredGrid(36, 3, 72);
    const std::vector<float> f = harmonics(g, {{2, 0, 1.0}, {3, 1, 0.5}, {6, -4, 0.2}});
    std::vector<float> neg(f), half(f);
    for (size_t i = 0; i < f.size(); ++i)
        neg[i] = -f[i], half[i] = 0.5f * f[i];
    const std::vector<float> y20 = harmonics(g, {{2, 0, 1.0}}), y31 = harmonics(g, {{3, 1, 1.0}});
    const auto self = correlateShells(g, f.data(), f.data(), {}, "test");
    const auto negative = correlateShells(g, f.data(), neg.data(), {}, "test");
    const auto ratio = correlateShells(g, f.data(), half.data(), {}, "test");
    const auto orthogonal = correlateShells(g, y20.data(), y31.data(), {}, "test");
    for (size_t iR = 0; iR < g.nR(); ++iR) {
        EXPECT_NEAR(self[iR].correlation, 1.0, 1e-9);
        EXPECT_NEAR(negative[iR].correlation, -1.0, 1e-9);
        EXPECT_NEAR(orthogonal[iR].correlation, 0.0, 1e-6);
        EXPECT_NEAR(ratio[iR].rmsRatio, 2.0, 1e-6);
        EXPECT_EQ(self[iR].points, g.nLat() * g.nLon());
        EXPECT_NEAR(self[iR].areaFraction, 1.0, 1e-12);
        EXPECT_NEAR(self[iR].depthKm, kSurfaceRadiusKm - g.rKm[iR], 1e-9);
        EXPECT_TRUE(self[iR].note.empty());
        // The RMS of A Ȳ_lm (mean 0) is A, to the dual cells' areas (a midpoint rule).
        EXPECT_NEAR(orthogonal[iR].rmsA, 1.0 + double(iR), 0.01 * (1.0 + double(iR)));
    }
}

// The field turned by 180° in longitude: the same spectrum; odd orders change sign.
TEST(ShellCorrelation, RotatedByHalfATurn)
{
    const grid::SphericalGrid g = testing::centredGrid(36, 2, 72);
    const std::vector<float> f = harmonics(g, {{2, 0, 1.0}, {3, 1, 0.5}, {5, 2, 0.7}, {7, -3, 0.2}});
    const std::vector<float> turned = harmonics(g, {{2, 0, 1.0}, {3, 1, 0.5}, {5, 2, 0.7}, {7, -3, 0.2}}, 180.0);
    const ShellSpectra a = shellSpectra(g, f.data(), 12, "f"), b = shellSpectra(g, turned.data(), 12, "turned");
    for (size_t i = 0; i < a.power.size(); ++i)
        EXPECT_NEAR(a.power[i], b.power[i], 1e-6 * (1.0 + a.power[i]));
    const std::vector<float> y31 = harmonics(g, {{3, 1, 1.0}}), y31turned = harmonics(g, {{3, 1, 1.0}}, 180.0);
    const std::vector<float> y52 = harmonics(g, {{5, 2, 1.0}}), y52turned = harmonics(g, {{5, 2, 1.0}}, 180.0);
    EXPECT_NEAR(correlateShells(g, y31.data(), y31turned.data(), {}, "t")[0].correlation, -1.0, 1e-9);
    EXPECT_NEAR(correlateShells(g, y52.data(), y52turned.data(), {}, "t")[0].correlation, 1.0, 1e-9);
}

TEST(ShellCorrelation, PerDegreeCorrelation)
{
    const grid::SphericalGrid g = testing::centredGrid(36, 2, 72);
    const std::vector<float> a = harmonics(g, {{2, 0, 1.0}, {3, 1, 2.0}, {4, 2, 1.0}, {4, -1, 1.0}});
    const std::vector<float> b = harmonics(g, {{2, 0, 3.0}, {3, 1, -1.0}, {4, 2, 1.0}, {4, 1, 1.0}, {6, 0, 1.0}});
    const DegreeCorrelation c = degreeCorrelationAt(g, a.data(), b.data(), 1, 8, "A", "B");
    EXPECT_NEAR(c.depthKm, kSurfaceRadiusKm - g.rKm[1], 1e-9);
    EXPECT_NEAR(c.correlation[2], 1.0, 1e-9);
    EXPECT_NEAR(c.correlation[3], -1.0, 1e-9);
    EXPECT_NEAR(c.correlation[4], 0.5, 1e-6);  // one of two equal orders shared
    EXPECT_NEAR(c.powerA[3], 16.0, 1e-5);      // (2 x 2)² on the second shell
    for (const int l : {0, 1, 5, 6, 7, 8})
        EXPECT_TRUE(std::isnan(c.correlation[size_t(l)])) << "degree " << l << ": A or B has no power there";
}

// Missing values: the correlation is over the points both have; the spectrum is refused naming the
// shell and the count. A regional grid: the same, the spectrum refused naming the region.
TEST(ShellCorrelation, MissingValuesAndRegionalGrids)
{
    grid::SphericalGrid g = testing::centredGrid(36, 2, 72);
    std::vector<float> f = harmonics(g, {{2, 0, 1.0}, {3, 1, 0.5}});
    std::vector<float> holes(f);
    size_t removed = 0;
    for (size_t iLat = 0; iLat < g.nLat(); ++iLat)
        for (size_t iLon = 0; iLon < 10; ++iLon, ++removed)
            holes[g.index(iLat, 1, iLon)] = NAN;
    const auto rows = correlateShells(g, f.data(), holes.data(), {}, "test");
    EXPECT_EQ(rows[0].points, g.nLat() * g.nLon());
    EXPECT_EQ(rows[1].points, g.nLat() * g.nLon() - removed);
    EXPECT_NEAR(rows[1].areaFraction, 1.0 - 10.0 / 72.0, 1e-9);
    EXPECT_NEAR(rows[1].correlation, 1.0, 1e-9);
    try {
        shellSpectra(g, holes.data(), 8, "holes");
        ADD_FAILURE() << "a spectrum of a field with missing values";
    } catch (const Error& e) {
        EXPECT_NE(std::string(e.what()).find(fmt::format("{} point(s) without data", removed)), std::string::npos) << e.what();
        EXPECT_NE(std::string(e.what()).find("a spectrum needs the whole sphere"), std::string::npos) << e.what();
    }
    // With --lmax the shell with holes is not filtered, and says why; the other is.
    const auto filtered = correlateShells(g, f.data(), holes.data(), {6}, "test");
    EXPECT_NEAR(filtered[0].correlation, 1.0, 1e-9);
    EXPECT_TRUE(std::isnan(filtered[1].correlation));
    EXPECT_NE(filtered[1].note.find("B has no data at"), std::string::npos) << filtered[1].note;

    grid::SphericalGrid regional = g;
    regional.dataLatDeg = std::array<double, 2>{-30.0, 30.0};
    std::vector<float> r(f);
    for (size_t iLat = 0; iLat < g.nLat(); ++iLat)
        if (!regional.latHoldsData(g.latDeg[iLat]))
            for (size_t iR = 0; iR < g.nR(); ++iR)
                for (size_t iLon = 0; iLon < g.nLon(); ++iLon)
                    r[g.index(iLat, iR, iLon)] = NAN;
    const auto region = correlateShells(regional, r.data(), r.data(), {}, "test");
    EXPECT_NEAR(region[0].correlation, 1.0, 1e-9);
    EXPECT_NEAR(region[0].areaFraction, 0.5, 0.02);  // sin 30° of the sphere, to the rows' dual cells
    EXPECT_LT(region[0].points, g.nLat() * g.nLon() / 2 + g.nLon());
    EXPECT_THROW(
        {
            try {
                shellSpectra(regional, r.data(), 8, "regional");
            } catch (const Error& e) {
                EXPECT_NE(std::string(e.what()).find("the grid is regional"), std::string::npos) << e.what();
                throw;
            }
        },
        Error);
    EXPECT_THROW(correlateShells(regional, r.data(), r.data(), {4}, "test"), Error);
}

TEST(ShellCorrelation, TooFewPointsAndConstantFieldsAreSaid)
{
    const grid::SphericalGrid g = testing::centredGrid(36, 1, 72);
    std::vector<float> f = harmonics(g, {{2, 0, 1.0}});
    std::vector<float> sparse(f.size(), NAN), constant(f.size(), 3.0f);
    sparse[0] = 1, sparse[5] = 2;
    const auto few = correlateShells(g, f.data(), sparse.data(), {}, "test");
    EXPECT_TRUE(std::isnan(few[0].correlation));
    EXPECT_EQ(few[0].points, 2u);
    EXPECT_NE(few[0].note.find("a correlation needs 3"), std::string::npos) << few[0].note;
    const auto flat = correlateShells(g, f.data(), constant.data(), {}, "test");
    EXPECT_TRUE(std::isnan(flat[0].correlation));
    EXPECT_TRUE(std::isnan(flat[0].rmsRatio));
    EXPECT_NE(flat[0].note.find("B is constant"), std::string::npos) << flat[0].note;
}

TEST(SphericalHarmonics, RefusesWhatItCannotTransform)
{
    grid::SphericalGrid g = testing::centredGrid(36, 1, 72);
    g.lonDeg[3] += 0.5;
    const std::vector<float> v(g.cellCount(), 1.0f);
    try {
        shellSpectra(g, v.data(), 8, "uneven");
        ADD_FAILURE() << "uneven longitudes accepted";
    } catch (const Error& e) {
        EXPECT_NE(std::string(e.what()).find("not evenly spaced"), std::string::npos) << e.what();
    }
    const grid::SphericalGrid even = testing::centredGrid(36, 1, 72);
    try {
        shellSpectra(even, v.data(), 18, "field");
        ADD_FAILURE() << "a degree beyond the grid's resolution accepted";
    } catch (const Error& e) {
        EXPECT_NE(std::string(e.what()).find("out of range 0..17"), std::string::npos) << e.what();
    }
    EXPECT_THROW(nearestShell(even, 3000.0), Error);
    EXPECT_EQ(nearestShell(testing::centredGrid(36, 3, 72), 0.0), 2u);
}

}  // namespace
}  // namespace raypc::analysis
