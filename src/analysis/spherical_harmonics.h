// Spherical-harmonic transforms of one shell of a field on the spherical grid (grid/grid.h), through
// libsharp (Debian's libsharp-dev; the transform is not written here): analysis into coefficients,
// synthesis back, the power per degree, the per-degree correlation of two fields and the low-pass
// filter to a degree L (docs/compare.md, "Spectra").
//
// Conventions. libsharp's coefficients a_lm (m >= 0, complex) are of the orthonormal complex harmonics
// (∫ |Y_lm|² dΩ = 1); a real field has a_l,-m = (-1)^m conj(a_lm). The power per degree is that of the
// 4π-normalised real harmonics (1/4π ∫ Ȳ_lm² dΩ = 1; f = Σ c_lm Ȳ_lm):
//     S_l = Σ_m c_lm² = (|a_l0|² + 2 Σ_{m>0} |a_lm|²) / 4π      (units: the field's squared),
// so that Σ_l S_l is the mean square of the field over the sphere, S_0 its mean squared, and a field
// A Ȳ_lm has S_l = A². The per-degree correlation (as in Becker & Boschi 2002) is
//     r_l = Σ_m c_lm d_lm / sqrt(Σ_m c_lm² Σ_m d_lm²).
//
// Grids. Longitudes must be evenly spaced over the whole circle (any first longitude); the rows'
// quadrature is chosen from their latitudes: cell centres of an equiangular grid (-90 + (i + ½) Δ) are
// Fejér's first rule, an equiangular grid with both pole rows (-90 + i Δ) Clenshaw–Curtis (both exact
// for band-limited fields, libsharp's own weights), any other spacing libsharp's general geometry
// with the rows' area weights (sin of the dual cell's edges, grid.volumeFactors: approximate). A
// regional grid, or longitudes that are uneven, are refused with the reason: the transform needs the
// whole sphere. The largest degree is min((nLat - 1) / 2, (nLon - 1) / 2), the sampling theorem's bound.
//
// Thread safety: a ShellTransform is immutable after construction; analyse and synthesise may run
// on several threads at once (each on one thread: libsharp's own OpenMP team is kept to one thread
// while they run, so that callers parallelise over shells with oneTBB).
#pragma once

#include "grid/grid.h"

#include <complex>
#include <cstddef>
#include <memory>
#include <span>
#include <string>
#include <vector>

namespace raypc::analysis {

enum class SphereQuadrature { Fejer1, ClenshawCurtis, AreaWeights };
// "Fejér's first rule", "Clenshaw–Curtis", "area weights": what docs and CSV headers say.
std::string quadratureName(SphereQuadrature quadrature);

// The quadrature a global grid's rows take (above).
SphereQuadrature quadratureOf(const grid::SphericalGrid& grid);

// Why the transform cannot be done on `grid` (regional; longitudes not evenly spaced over 360°; too
// few rows or columns), or empty when it can.
std::string transformRefusal(const grid::SphericalGrid& grid);

// The largest degree the grid resolves: min((nLat - 1) / 2, (nLon - 1) / 2).
int maxDegree(const grid::SphericalGrid& grid);

class ShellTransform {
public:
    // The transform of `grid`'s shells to degree `lmax` (0 <= lmax <= maxDegree). Throws raypc::Error
    // naming `what` and the reason when the grid is refused (transformRefusal) or lmax is out of range.
    ShellTransform(const grid::SphericalGrid& grid, int lmax, const std::string& what);
    ~ShellTransform();
    ShellTransform(const ShellTransform&) = delete;
    ShellTransform& operator=(const ShellTransform&) = delete;

    int lmax() const { return m_lmax; }
    SphereQuadrature quadrature() const { return m_quadrature; }
    const grid::SphericalGrid& grid() const { return m_grid; }
    // The number of coefficients (l, m), 0 <= m <= l <= lmax, and where (l, m) is among them.
    size_t coefficientCount() const { return size_t(m_lmax + 1) * size_t(m_lmax + 2) / 2; }
    size_t index(int l, int m) const { return size_t(m) * size_t(2 * m_lmax + 3 - m) / 2 + size_t(l - m); }

    // The coefficients of shell `iR` of `values` (the grid's canonical order, cellCount() of them) into
    // `alm` (resized to coefficientCount()). The shell must hold no missing value (checked by callers:
    // missingOnShell); a NaN makes every coefficient NaN.
    void analyse(const float* values, size_t iR, std::vector<std::complex<double>>& alm) const;
    // The same for one shell held alone, nLat * nLon values in (lat, lon) order.
    void analyseShell(std::span<const double> shell, std::vector<std::complex<double>>& alm) const;
    // The field of coefficients `alm` on one shell: nLat * nLon values in (lat, lon) order into `shell`.
    void synthesiseShell(const std::vector<std::complex<double>>& alm, std::vector<double>& shell) const;

    // S_l (above) for l = 0 .. lmax.
    std::vector<double> powerPerDegree(const std::vector<std::complex<double>>& alm) const;
    // Σ_m c_lm d_lm for l = 0 .. lmax (the cross power; the numerator of r_l).
    std::vector<double> crossPowerPerDegree(const std::vector<std::complex<double>>& a,
                                            const std::vector<std::complex<double>>& b) const;

private:
    grid::SphericalGrid m_grid;
    int m_lmax = 0;
    SphereQuadrature m_quadrature = SphereQuadrature::AreaWeights;
    struct Sharp;
    std::unique_ptr<Sharp> m_sharp;
};

// The number of missing values (NaN) of shell `iR` of `values` at points that hold data (a regional
// grid's padding does not count: the transform refuses the grid anyway).
size_t missingOnShell(const grid::SphericalGrid& grid, const float* values, size_t iR);

// r_l from the powers and the cross power of two fields: NaN where either field has no power at that
// degree (below 1e-12 of its largest degree's, the transform's rounding), so that no correlation is
// made of rounding noise.
std::vector<double> degreeCorrelation(std::span<const double> powerA, std::span<const double> powerB,
                                      std::span<const double> crossPower);

}  // namespace raypc::analysis
