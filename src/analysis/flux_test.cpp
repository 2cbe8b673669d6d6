#include "analysis/flux.h"

#include "core/error.h"
#include "core/spherical.h"
#include "grid/test_util.h"

#include <gtest/gtest.h>

#include <cmath>
#include <numbers>

namespace raypc::analysis {
namespace {

std::shared_ptr<dataset::StepVolume> radialFlow(const grid::SphericalGrid& g, const std::function<double(size_t, size_t, size_t)>& vr)
{
    grid::Snapshot snap;
    snap.grid = g;
    snap.fields.push_back({"radial velocity", "cm/yr", testing::fillGrid(g, vr)});
    return dataset::StepVolume::fromSnapshot(snap);
}

TEST(ShellFlux, AUniformRadialFlowCarriesFourPiRSquaredU0)
{
    const grid::SphericalGrid g = testing::centredGrid(36, 21, 72);
    const double u0 = 0.7;  // cm/yr, upward everywhere
    const auto volume = radialFlow(g, [&](size_t, size_t, size_t) { return u0; });
    const std::vector<double> depths{660.0, 1600.0};
    const auto f = shellFluxes(*volume, 0, depths);
    ASSERT_EQ(f.size(), 2u);
    for (const ShellFlux& s : f) {
        const double r = kSurfaceRadiusKm - s.depthKm;
        EXPECT_DOUBLE_EQ(s.radiusKm, r);
        EXPECT_NEAR(s.areaKm2, 4 * std::numbers::pi * r * r, 1e-9 * s.areaKm2);
        EXPECT_NEAR(s.upKm3PerYr, 4 * std::numbers::pi * r * r * u0 * 1e-5, 1e-7 * s.upKm3PerYr);  // the field is float32
        EXPECT_EQ(s.downKm3PerYr, 0.0);
        EXPECT_EQ(s.selectedUpKm3PerYr, s.upKm3PerYr) << "no filters: the whole shell";
    }
}

// The mass flux ∫ ρ v_r dA: a uniform upward flow u0 through material of density ρ(r) = 3000 +
// (6371 - r) / 2 kg/m³ carries ρ(r_shell) 4πr² u0 upward (ρ linear in r: its interpolation is
// exact); the northern half (selected by lat) carries half; without a density variable, none.
TEST(ShellFlux, MassFluxIsDensityTimesVolumeFlux)
{
    const grid::SphericalGrid g = testing::centredGrid(36, 21, 72);
    const double u0 = 0.7;
    auto rhoAt = [](double rKm) { return 3000 + (kSurfaceRadiusKm - rKm) / 2; };
    grid::Snapshot snap;
    snap.grid = g;
    snap.fields.push_back({"radial velocity", "cm/yr", testing::fillGrid(g, [&](size_t, size_t, size_t) { return u0; })});
    snap.fields.push_back({"density", "kg/m^3", testing::fillGrid(g, [&](size_t, size_t iR, size_t) { return rhoAt(g.rKm[iR]); })});
    const auto volume = dataset::StepVolume::fromSnapshot(snap);
    const std::vector<double> depths{660.0, 1600.0};
    const auto flux = shellFluxes(*volume, 0, depths, {}, std::nullopt, size_t(1));
    for (const ShellFlux& f : flux) {
        const double expected = rhoAt(f.radiusKm) * 1e9 * 4 * std::numbers::pi * f.radiusKm * f.radiusKm * u0 * 1e-5;
        EXPECT_NEAR(f.massUpKgPerYr, expected, 1e-6 * expected) << f.depthKm << " km";  // about 9e17 kg/yr
        EXPECT_EQ(f.massDownKgPerYr, 0.0);
        EXPECT_EQ(f.selectedMassUpKgPerYr, f.massUpKgPerYr);
    }
    const std::vector<NamedRange> northRange{{"lat", 0, 90}};
    const auto half = shellFluxes(*volume, 0, depths, resolveRangeFilters(std::vector<std::string>{"radial velocity", "density"},
                                                                           northRange), std::nullopt, size_t(1));
    EXPECT_NEAR(half[0].selectedMassUpKgPerYr, 0.5 * flux[0].massUpKgPerYr, 1e-6 * flux[0].massUpKgPerYr);
    EXPECT_EQ(shellFluxes(*volume, 0, depths).at(0).massUpKgPerYr, 0.0) << "without a density, no mass flux";
    EXPECT_THROW(shellFluxes(*volume, 0, depths, {}, std::nullopt, size_t(2)), Error);
}

// Q = ρ c_p ∫ T′ v_r dA: a uniform upward flow u0 of material T′ = c warmer than its shell carries
// ρ c_p c u0 4πr² upward; with T′ = +c in the north and −c in the south the net is zero and the
// northern half (selected by lat) carries half the first.
TEST(ShellFlux, AdvectiveHeatFluxIsDensityHeatCapacityAnomalyAndVelocityOverTheShell)
{
    const grid::SphericalGrid g = testing::centredGrid(36, 21, 72);
    const double u0 = 0.7, c = 150;  // cm/yr, K
    grid::Snapshot snap;
    snap.grid = g;
    snap.fields.push_back({"radial velocity", "cm/yr", testing::fillGrid(g, [&](size_t, size_t, size_t) { return u0; })});
    snap.fields.push_back({"uniform anomaly", "K", testing::fillGrid(g, [&](size_t, size_t, size_t) { return c; })});
    snap.fields.push_back({"hemispheres", "K", testing::fillGrid(g, [&](size_t iLat, size_t, size_t) {
                               return g.latDeg[iLat] > 0 ? c : -c;
                           })});
    const auto volume = dataset::StepVolume::fromSnapshot(snap);
    const HeatFluxInputs heat{1, 3300, 1250};
    const std::vector<double> depths{660.0};
    const double r = kSurfaceRadiusKm - 660.0;
    const double metresPerSecond = u0 * 0.01 / (365.25 * 86400), areaM2 = 4 * std::numbers::pi * r * r * 1e6;
    const double expected = 3300 * 1250 * c * metresPerSecond * areaM2;  // about 3.3e13 W
    const ShellFlux uniform = shellFluxes(*volume, 0, depths, {}, heat).at(0);
    EXPECT_NEAR(uniform.heatW, expected, 1e-6 * expected);
    EXPECT_EQ(uniform.selectedHeatW, uniform.heatW);
    EXPECT_EQ(shellFluxes(*volume, 0, depths).at(0).heatW, 0.0) << "without HeatFluxInputs, no heat flux";
    const RangeFilter north{-1, grid::Coordinate::Lat, {{0.0f, 90.0f}}};
    const ShellFlux halves = shellFluxes(*volume, 0, depths, std::span(&north, 1), HeatFluxInputs{2, 3300, 1250}).at(0);
    EXPECT_NEAR(halves.heatW, 0.0, 1e-9 * expected);
    EXPECT_NEAR(halves.selectedHeatW, expected / 2, 1e-6 * expected);
    EXPECT_THROW(shellFluxes(*volume, 0, depths, {}, HeatFluxInputs{1, 0, 1250}), Error);
    EXPECT_THROW(shellFluxes(*volume, 0, depths, {}, HeatFluxInputs{1, 3300, -1}), Error);
    EXPECT_THROW(shellFluxes(*volume, 0, depths, {}, HeatFluxInputs{7, 3300, 1250}), Error);
}

TEST(ShellFlux, DownAndUpAreApartAndTheSelectionTakesItsColumns)
{
    const grid::SphericalGrid g = testing::centredGrid(36, 21, 72);
    // Rising in the north, sinking in the south, at 2 cm/yr; linear in radius, so the value at the
    // shell is the interpolation between the two grid radii around it.
    const auto volume = radialFlow(g, [&](size_t a, size_t r, size_t) { return (g.latDeg[a] > 0 ? 2.0 : -2.0) * g.rKm[r] / 6000.0; });
    const std::vector<double> depths{1000.0};
    const std::vector<RangeFilter> north{RangeFilter{-1, grid::Coordinate::Lat, {{0.0f, 90.0f}}}};
    const ShellFlux s = shellFluxes(*volume, 0, depths, north).front();
    const double r = kSurfaceRadiusKm - 1000.0;
    const double half = 2 * std::numbers::pi * r * r * 2.0 * r / 6000.0 * 1e-5;
    EXPECT_NEAR(s.upKm3PerYr, half, 1e-7 * half);
    EXPECT_NEAR(s.downKm3PerYr, -half, 1e-7 * half);
    EXPECT_NEAR(s.selectedUpKm3PerYr, half, 1e-7 * half);
    EXPECT_EQ(s.selectedDownKm3PerYr, 0.0);
    EXPECT_NEAR(s.selectedAreaKm2, 0.5 * s.areaKm2, 1e-9 * s.areaKm2);
}

TEST(ShellFlux, DepthsOutsideTheGridAreRefused)
{
    const grid::SphericalGrid g = testing::centredGrid(8, 5, 16);
    const auto volume = radialFlow(g, [](size_t, size_t, size_t) { return 1.0; });
    const std::vector<double> tooDeep{3000.0};
    EXPECT_THROW(shellFluxes(*volume, 0, tooDeep), Error);
    const std::vector<double> ok{660.0};
    EXPECT_THROW(shellFluxes(*volume, 1, ok), Error);
}

TEST(ShellFlux, AvalanchesStandOutOfTheSeries)
{
    const std::vector<double> down{-1.0, -1.2, -0.9, -6.0, -1.1, -1.0};
    EXPECT_EQ(avalancheSteps(down, 2.0), std::vector<size_t>{3});
    EXPECT_TRUE(avalancheSteps(std::vector<double>{-1.0, -1.0, -1.0}, 0.0).empty()) << "a constant series";
    EXPECT_TRUE(avalancheSteps(std::vector<double>{-5.0}, 1.0).empty());
}

}  // namespace
}  // namespace raypc::analysis
