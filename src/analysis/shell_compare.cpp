// Two fields compared shell by shell (shell_compare.h).
#include "analysis/shell_compare.h"

#include "core/error.h"
#include "core/spherical.h"

#include <fmt/format.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <cmath>
#include <numbers>

namespace raypc::analysis {
namespace {

// A shell of `values` alone, (lat, lon) order, as doubles.
std::vector<double> shellOf(const grid::SphericalGrid& g, const float* values, size_t iR)
{
    std::vector<double> shell(g.nLat() * g.nLon());
    for (size_t iLat = 0; iLat < g.nLat(); ++iLat) {
        const float* row = values + g.index(iLat, iR, 0);
        std::copy(row, row + g.nLon(), shell.begin() + ptrdiff_t(iLat * g.nLon()));
    }
    return shell;
}

// The shell low-pass filtered to the transform's degree: analysed and synthesised again.
std::vector<double> filtered(const ShellTransform& t, const std::vector<double>& shell)
{
    std::vector<std::complex<double>> alm;
    t.analyseShell(shell, alm);
    std::vector<double> out;
    t.synthesiseShell(alm, out);
    return out;
}

std::string number(double v) { return std::isfinite(v) ? fmt::format("{:.9g}", v) : std::string(); }

// A CSV field: quoted when it holds a comma or a quote.
std::string field(const std::string& text)
{
    if (text.find_first_of(",\"\n") == std::string::npos)
        return text;
    std::string out = "\"";
    for (const char c : text)
        out += c == '"' ? std::string("\"\"") : std::string(1, c == '\n' ? ' ' : c);
    return out + "\"";
}

std::string unitsOf(const std::string& units) { return units.empty() ? std::string("1") : units; }

// Units that are one symbol go bare ("K^2"), others in parentheses ("(km/s)^2").
std::string bracketed(const std::string& units)
{
    return units.find_first_of("/ *^") == std::string::npos ? units : "(" + units + ")";
}
std::string squared(const std::string& units) { return units.empty() ? std::string("1") : bracketed(units) + "^2"; }
std::string ratioUnits(const std::string& a, const std::string& b)
{
    if (a == b)
        return "1";
    return bracketed(unitsOf(a)) + "/" + bracketed(unitsOf(b));
}

}  // namespace

std::vector<ShellCorrelation> correlateShells(const grid::SphericalGrid& g, const float* a, const float* b,
                                              const CorrelationOptions& options, const std::string& what)
{
    std::optional<ShellTransform> transform;
    if (options.lmax)
        transform.emplace(g, *options.lmax, what + " --lmax");
    const grid::SphericalGrid::VolumeFactors f = g.volumeFactors();
    const double sphere = 4.0 * std::numbers::pi;  // Σ lat factors (2) x Σ lon factors (2π) over the globe
    std::vector<ShellCorrelation> rows(g.nR());
    tbb::parallel_for(size_t(0), g.nR(), [&](size_t iR) {
        ShellCorrelation& row = rows[iR];
        row.radiusKm = g.rKm[iR];
        row.depthKm = kSurfaceRadiusKm - g.rKm[iR];
        std::vector<double> sa = shellOf(g, a, iR), sb = shellOf(g, b, iR);
        if (transform) {
            const size_t missingA = missingOnShell(g, a, iR), missingB = missingOnShell(g, b, iR);
            if (missingA || missingB) {
                row.note = fmt::format("not filtered: {} has no data at {} point(s) of the shell; the filter to degree {} "
                                       "needs the whole sphere",
                                       missingA ? "A" : "B", missingA ? missingA : missingB, *options.lmax);
                return;
            }
            sa = filtered(*transform, sa);
            sb = filtered(*transform, sb);
        }
        // Means over the points both fields have, then the sums of the deviations (two passes: no
        // cancellation of large means).
        double w = 0, ma = 0, mb = 0;
        size_t points = 0;
        for (size_t iLat = 0; iLat < g.nLat(); ++iLat)
            for (size_t iLon = 0; iLon < g.nLon(); ++iLon) {
                const size_t i = iLat * g.nLon() + iLon;
                const double wi = f.lat[iLat] * f.lon[iLon];
                if (!(wi > 0) || std::isnan(sa[i]) || std::isnan(sb[i]))
                    continue;
                w += wi, ma += wi * sa[i], mb += wi * sb[i];
                ++points;
            }
        row.points = points;
        row.areaFraction = w / sphere;
        if (points < kMinCorrelationPoints) {
            row.note = points == 0 ? std::string("no point where both fields have data")
                                   : fmt::format("{} point(s) where both fields have data; a correlation needs {}", points,
                                                 kMinCorrelationPoints);
            return;
        }
        ma /= w, mb /= w;
        double saa = 0, sbb = 0, sab = 0;
        for (size_t iLat = 0; iLat < g.nLat(); ++iLat)
            for (size_t iLon = 0; iLon < g.nLon(); ++iLon) {
                const size_t i = iLat * g.nLon() + iLon;
                const double wi = f.lat[iLat] * f.lon[iLon];
                if (!(wi > 0) || std::isnan(sa[i]) || std::isnan(sb[i]))
                    continue;
                const double da = sa[i] - ma, db = sb[i] - mb;
                saa += wi * da * da, sbb += wi * db * db, sab += wi * da * db;
            }
        row.rmsA = std::sqrt(saa / w);
        row.rmsB = std::sqrt(sbb / w);
        // A field constant on the shell (to rounding) has no lateral variation to correlate.
        const bool flatA = !(row.rmsA > 1e-12 * std::max(1.0, std::abs(ma)));
        const bool flatB = !(row.rmsB > 1e-12 * std::max(1.0, std::abs(mb)));
        if (!flatB)
            row.rmsRatio = row.rmsA / row.rmsB;
        if (flatA || flatB) {
            row.note = fmt::format("{} is constant on the shell: no correlation", flatA && flatB ? "each field" : flatA ? "A" : "B");
            return;
        }
        row.correlation = std::clamp(sab / std::sqrt(saa * sbb), -1.0, 1.0);
    });
    return rows;
}

ShellSpectra shellSpectra(const grid::SphericalGrid& g, const float* values, int lmax, const std::string& what)
{
    const ShellTransform t(g, lmax, what);
    for (size_t iR = g.nR(); iR-- > 0;)  // the shallowest first
        if (const size_t missing = missingOnShell(g, values, iR))
            fail("{}: {} point(s) without data (missing values) on the shell at depth {:.1f} km; a spectrum needs the whole "
                 "sphere",
                 what, missing, kSurfaceRadiusKm - g.rKm[iR]);
    ShellSpectra out;
    out.lmax = lmax;
    out.quadrature = t.quadrature();
    out.radiiKm = g.rKm;
    out.power.assign(g.nR() * size_t(lmax + 1), NAN);
    tbb::parallel_for(size_t(0), g.nR(), [&](size_t iR) {
        std::vector<std::complex<double>> alm;
        t.analyse(values, iR, alm);
        const std::vector<double> s = t.powerPerDegree(alm);
        std::copy(s.begin(), s.end(), out.power.begin() + ptrdiff_t(iR * size_t(lmax + 1)));
    });
    return out;
}

std::vector<double> shellSpectrumAt(const grid::SphericalGrid& g, const float* values, size_t iR, int lmax,
                                    const std::string& what)
{
    if (iR >= g.nR())
        fail("spectrum: shell {} out of range 0..{}", iR, g.nR() - 1);
    const ShellTransform t(g, lmax, what);
    if (const size_t missing = missingOnShell(g, values, iR))
        fail("{}: {} point(s) without data (missing values) on the shell at depth {:.1f} km; a spectrum needs the whole "
             "sphere",
             what, missing, kSurfaceRadiusKm - g.rKm[iR]);
    std::vector<std::complex<double>> alm;
    t.analyse(values, iR, alm);
    return t.powerPerDegree(alm);
}

int defaultSpectrumDegree(const grid::SphericalGrid& g)
{
    return std::max(0, std::min(maxDegree(g), 60));
}

DegreeCorrelation degreeCorrelationAt(const grid::SphericalGrid& g, const float* a, const float* b, size_t iR, int lmax,
                                      const std::string& whatA, const std::string& whatB)
{
    if (iR >= g.nR())
        fail("degree correlation: shell {} out of range 0..{}", iR, g.nR() - 1);
    const ShellTransform t(g, lmax, whatA);
    const double depth = kSurfaceRadiusKm - g.rKm[iR];
    for (const auto& [values, what] : {std::pair{a, &whatA}, std::pair{b, &whatB}})
        if (const size_t missing = missingOnShell(g, values, iR))
            fail("{}: {} point(s) without data (missing values) on the shell at depth {:.1f} km; a spectrum needs the whole "
                 "sphere",
                 *what, missing, depth);
    std::vector<std::complex<double>> almA, almB;
    t.analyse(a, iR, almA);
    t.analyse(b, iR, almB);
    DegreeCorrelation out;
    out.lmax = lmax;
    out.shell = iR;
    out.radiusKm = g.rKm[iR];
    out.depthKm = depth;
    out.powerA = t.powerPerDegree(almA);
    out.powerB = t.powerPerDegree(almB);
    out.correlation = degreeCorrelation(out.powerA, out.powerB, t.crossPowerPerDegree(almA, almB));
    return out;
}

size_t nearestShell(const grid::SphericalGrid& g, double depthKm)
{
    const double r = kSurfaceRadiusKm - depthKm;
    if (!(r >= g.rKm.front() - 1e-6 && r <= g.rKm.back() + 1e-6))
        fail("--depth: {} km is outside the grid's radii ({:.1f}..{:.1f} km deep)", depthKm, kSurfaceRadiusKm - g.rKm.back(),
             kSurfaceRadiusKm - g.rKm.front());
    size_t best = 0;
    for (size_t iR = 1; iR < g.nR(); ++iR)
        if (std::abs(g.rKm[iR] - r) < std::abs(g.rKm[best] - r))
            best = iR;
    return best;
}

std::string correlationCsv(const std::vector<ShellCorrelation>& rows, const std::string& titleA, const std::string& unitsA,
                           const std::string& titleB, const std::string& unitsB, const CorrelationOptions& options)
{
    std::string out = fmt::format("# A: {}\n# B: {}\n", titleA, titleB);
    out += options.lmax ? fmt::format("# both low-pass filtered to spherical-harmonic degree <= {}\n", *options.lmax)
                        : std::string("# unfiltered; over the points where both have data, area-weighted\n");
    out += fmt::format("# units: rms_a {}; rms_b {}; rms_ratio {}\n", unitsOf(unitsA), unitsOf(unitsB), ratioUnits(unitsA, unitsB));
    out += "depth_km,radius_km,correlation,rms_a,rms_b,rms_ratio,points,area_covered_percent,note\n";
    // Depth increasing downward, as mantle profiles are read.
    for (auto it = rows.rbegin(); it != rows.rend(); ++it)
        out += fmt::format("{},{},{},{},{},{},{},{},{}\n", number(it->depthKm), number(it->radiusKm), number(it->correlation),
                           number(it->rmsA), number(it->rmsB), number(it->rmsRatio), it->points,
                           number(100.0 * it->areaFraction), field(it->note));
    return out;
}

std::string spectrumCsv(const ShellSpectra& s, const std::string& title, const std::string& units)
{
    std::string out = fmt::format("# {}\n# power per degree S_l = sum over m of c_lm^2, 4pi-normalised real harmonics "
                                  "(sum over l = mean square over the sphere); quadrature: {}\n",
                                  title, quadratureName(s.quadrature));
    out += fmt::format("# units: power {}\ndepth_km,radius_km,degree,power\n", squared(units));
    for (size_t iR = s.radiiKm.size(); iR-- > 0;)
        for (int l = 0; l <= s.lmax; ++l)
            out += fmt::format("{},{},{},{}\n", number(kSurfaceRadiusKm - s.radiiKm[iR]), number(s.radiiKm[iR]), l,
                               number(s.at(iR, l)));
    return out;
}

std::string degreeCorrelationCsv(const DegreeCorrelation& c, const std::string& titleA, const std::string& unitsA,
                                 const std::string& titleB, const std::string& unitsB)
{
    std::string out = fmt::format("# A: {}\n# B: {}\n# shell at depth {:g} km; per-degree correlation r_l = sum_m c_lm d_lm / "
                                  "sqrt(S_l(A) S_l(B)), empty where either has no power\n",
                                  titleA, titleB, c.depthKm);
    out += fmt::format("# units: power_a {}; power_b {}\ndepth_km,radius_km,degree,power_a,power_b,correlation\n", squared(unitsA),
                       squared(unitsB));
    for (int l = 0; l <= c.lmax; ++l)
        out += fmt::format("{},{},{},{},{},{}\n", number(c.depthKm), number(c.radiusKm), l, number(c.powerA[size_t(l)]),
                           number(c.powerB[size_t(l)]), number(c.correlation[size_t(l)]));
    return out;
}

}  // namespace raypc::analysis
