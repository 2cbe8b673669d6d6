// Volume flux across spherical shells (to find "avalanches"): how much material crosses a depth
// per unit time, downward and upward separately, over the whole shell and within a selection.
// docs/features.md gives the definitions.
//
// Thread safety: pure functions of their arguments.
#pragma once

#include "dataset/dataset.h"
#include "analysis/selection.h"

#include <optional>
#include <span>
#include <vector>

namespace raypc::analysis {

struct ShellFlux {
    double depthKm = 0, radiusKm = 0;
    // km³/yr: the integral of the radial velocity over the shell, its negative part (downward,
    // <= 0) and positive part (upward, >= 0); net = down + up.
    double downKm3PerYr = 0, upKm3PerYr = 0;
    // The same over the shell's points that lie in the selection (the whole shell without filters).
    double selectedDownKm3PerYr = 0, selectedUpKm3PerYr = 0;
    double areaKm2 = 0, selectedAreaKm2 = 0;  // of the shell, and of its selected part
    // With HeatFluxInputs: the net advective heat flux across the shell, W, positive upward,
    // Q = ∫ ρ c_p T′ v_r dA, over the shell and over its selected part.
    double heatW = 0, selectedHeatW = 0;
    // With a density variable (kg/m³): the mass flux, kg/yr, ∫ ρ v_r dA split as the volume flux is
    // (by the sign of v_r), over the shell and over its selected part; 0 without one.
    double massDownKgPerYr = 0, massUpKgPerYr = 0, selectedMassDownKgPerYr = 0, selectedMassUpKgPerYr = 0;
};

// The variable whose values are the density, kg/m³, for the mass flux: named "density" (as ASPECT
// writes it). The contest's files have none.
inline constexpr const char* kDensityVariable = "density";

// What the advective heat flux takes: the temperature anomaly T′ (a variable, K) and the density ρ
// (kg/m³) and heat capacity c_p (J/(kg·K)), constants (the contest's files carry neither).
struct HeatFluxInputs {
    size_t temperatureAnomaly = 0;
    double densityKgM3 = 3300;
    double heatCapacityJPerKgK = 1250;
};

// The flux across the shell at each depth (km below the surface, inside the grid's radii). At
// every (lat, lon) column of the grid the radial velocity (variable `radialVelocity`, cm/yr) is
// interpolated linearly in radius between the two grid radii around the shell — the ray caster's
// and the probe's rule along r — and weighted by the column's area on the shell, r² (sin φ+ −
// sin φ−) Δλ with the dual cells' edges (SphericalGrid::volumeFactors). A column is in the selection
// when the grid point nearer the shell is (selectedPoints). With `heat`, T′ is interpolated at the
// shell as v_r is and the heat flux summed alike; with `density` (a variable index, kg/m³), ρ is, and
// the mass flux summed alike. Throws raypc::Error for a depth outside the grid's radii, a variable
// index out of range, a density or heat capacity that is not positive, or bad filters.
std::vector<ShellFlux> shellFluxes(const dataset::StepVolume& volume, size_t radialVelocity, std::span<const double> depthsKm,
                                   std::span<const RangeFilter> filters = {},
                                   const std::optional<HeatFluxInputs>& heat = std::nullopt,
                                   std::optional<size_t> density = std::nullopt);

// Whether the shell at `depthKm` lies within the grid's radii; checkShellDepth throws raypc::Error
// naming them when it does not.
bool shellInsideGrid(const grid::SphericalGrid& grid, double depthKm);
void checkShellDepth(const grid::SphericalGrid& grid, double depthKm);

// The steps (indices into `downKm3PerYr`, one value per step) whose downward flux is stronger than
// the series' mean by more than k standard deviations: |down| > mean(|down|) + k σ(|down|) — an
// avalanche of material across the shell. Empty for fewer than two steps or a constant series.
std::vector<size_t> avalancheSteps(std::span<const double> downKm3PerYr, double k);
// avalancheSteps of each shell of a series of shellFluxes (bySteps[step][shell], every step with
// the same shells): per shell, the indices of its avalanche steps.
std::vector<std::vector<size_t>> avalancheStepsPerShell(std::span<const std::vector<ShellFlux>> bySteps, double k);

}  // namespace raypc::analysis
