// Two fields compared shell by shell on one spherical grid (docs/compare.md, "Correlation" and
// "Spectra"): per radius, the area-weighted Pearson correlation, the RMS of each and their ratio
// (optionally after a low-pass filter to degree L), the spherical-harmonic power per degree of a field
// per radius, and the per-degree correlation of two fields on one shell. The second field is on the
// first one's grid already (grid/regrid.h puts it there).
//
// Units: km (radius, depth), the fields' own units (RMS), their squares (power). Area weights are the
// dual cells' (grid.volumeFactors: lat factor x lon factor; 0 outside a regional grid's data). Never an
// invented value: a shell where the measure cannot be made is NaN with a note saying why.
//
// Thread safety: plain functions; they use every core over the shells (oneTBB).
#pragma once

#include "analysis/spherical_harmonics.h"
#include "grid/grid.h"

#include <optional>
#include <string>
#include <vector>

namespace raypc::analysis {

// Fewer points than this on a shell where both fields have data: no correlation (NaN).
inline constexpr size_t kMinCorrelationPoints = 3;

struct ShellCorrelation {
    double radiusKm = 0, depthKm = 0;
    // r = Σ w (a - ā)(b - b̄) / sqrt(Σ w (a - ā)² Σ w (b - b̄)²), ā, b̄ the area-weighted means over the
    // points where both have data; the RMS of each about that mean (the RMS of its lateral variation:
    // of an anomaly field, its RMS), and rmsA / rmsB. NaN where `note` says why.
    double correlation = NAN, rmsA = NAN, rmsB = NAN, rmsRatio = NAN;
    size_t points = 0;          // grid points where both fields have data (and area)
    double areaFraction = 0;    // their area over the whole sphere's, 0..1
    std::string note;           // why a value is missing; empty when all are given
};

struct CorrelationOptions {
    // Both fields low-pass filtered to degrees <= lmax first (spherical_harmonics.h); a shell where
    // either has missing values is then not correlated (the filter needs the whole sphere).
    std::optional<int> lmax;
};

// One row per radius of `grid` (ascending). `a`, `b`: values in the grid's canonical order, NaN where
// there are no data. Throws raypc::Error when lmax is given and the grid is refused by the transform
// (regional, uneven longitudes) or lmax is out of range, naming `what` and the reason.
std::vector<ShellCorrelation> correlateShells(const grid::SphericalGrid& grid, const float* a, const float* b,
                                              const CorrelationOptions& options, const std::string& what);

// The power per degree S_l (spherical_harmonics.h) of a field on every shell.
struct ShellSpectra {
    int lmax = 0;
    SphereQuadrature quadrature = SphereQuadrature::AreaWeights;
    std::vector<double> radiiKm;  // the grid's, ascending
    std::vector<double> power;    // radii x (lmax + 1), radius-major: power[iR * (lmax + 1) + l]
    double at(size_t iR, int l) const { return power[iR * size_t(lmax + 1) + size_t(l)]; }
};
// Throws raypc::Error naming `what` when the grid is refused (transformRefusal) or lmax is out of
// range, and naming the shallowest shell (its depth) and the count when a shell has missing values.
ShellSpectra shellSpectra(const grid::SphericalGrid& grid, const float* values, int lmax, const std::string& what);

// The power per degree of a field on shell `iR` alone (what the UI plots for the shown depth). Throws as
// shellSpectra does.
std::vector<double> shellSpectrumAt(const grid::SphericalGrid& grid, const float* values, size_t iR, int lmax,
                                    const std::string& what);

// The degree a spectrum goes to when none is given: the grid's largest (maxDegree), at most 60.
int defaultSpectrumDegree(const grid::SphericalGrid& grid);

// The per-degree powers of two fields on shell `iR` and their correlation r_l (NaN where either has no
// power at that degree). Throws as shellSpectra does, for either field.
struct DegreeCorrelation {
    int lmax = 0;
    size_t shell = 0;
    double radiusKm = 0, depthKm = 0;
    std::vector<double> powerA, powerB, correlation;  // per degree 0..lmax
};
DegreeCorrelation degreeCorrelationAt(const grid::SphericalGrid& grid, const float* a, const float* b, size_t iR, int lmax,
                                      const std::string& whatA, const std::string& whatB);

// The shell of `grid` nearest depth `depthKm`; throws raypc::Error (analysis/flux.h's message) when
// the depth lies outside the grid's radii.
size_t nearestShell(const grid::SphericalGrid& grid, double depthKm);

// The CSV tables of `raypc correlate` and `raypc spectrum`, units in the header. `titleA`, `titleB`:
// what was compared ("run1.raypc: temperature anomaly [K], step 3"), written in comment lines (#).
std::string correlationCsv(const std::vector<ShellCorrelation>& rows, const std::string& titleA, const std::string& unitsA,
                           const std::string& titleB, const std::string& unitsB, const CorrelationOptions& options);
std::string spectrumCsv(const ShellSpectra& spectra, const std::string& title, const std::string& units);
std::string degreeCorrelationCsv(const DegreeCorrelation& c, const std::string& titleA, const std::string& unitsA,
                                 const std::string& titleB, const std::string& unitsB);

}  // namespace raypc::analysis
