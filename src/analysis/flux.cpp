#include "analysis/flux.h"

#include "core/error.h"
#include "core/spherical.h"

#include <algorithm>
#include <cmath>
#include <optional>

namespace raypc::analysis {

bool shellInsideGrid(const grid::SphericalGrid& g, double depthKm)
{
    const double r = kSurfaceRadiusKm - depthKm;
    return r >= g.rKm.front() && r <= g.rKm.back();
}

void checkShellDepth(const grid::SphericalGrid& g, double depthKm)
{
    if (!shellInsideGrid(g, depthKm))
        fail("flux: depth {} km is outside the grid's radii ({:.1f}..{:.1f} km deep)", depthKm,
             kSurfaceRadiusKm - g.rKm.back(), kSurfaceRadiusKm - g.rKm.front());
}

std::vector<ShellFlux> shellFluxes(const dataset::StepVolume& volume, size_t radialVelocity, std::span<const double> depthsKm,
                                   std::span<const RangeFilter> filters, const std::optional<HeatFluxInputs>& heat,
                                   std::optional<size_t> density)
{
    for (const size_t variable :
         {radialVelocity, heat ? heat->temperatureAnomaly : radialVelocity, density.value_or(radialVelocity)})
        if (variable >= volume.variableCount())
            fail("flux: variable index {} out of range 0..{}", variable, volume.variableCount() - 1);
    if (heat && !(heat->densityKgM3 > 0 && std::isfinite(heat->densityKgM3)))
        fail("flux: density {} kg/m³ is not positive", heat->densityKgM3);
    if (heat && !(heat->heatCapacityJPerKgK > 0 && std::isfinite(heat->heatCapacityJPerKgK)))
        fail("flux: heat capacity {} J/(kg K) is not positive", heat->heatCapacityJPerKgK);
    const grid::SphericalGrid& g = volume.grid();
    // The radii around a shell at `depth` and the weight of the upper one.
    struct Shell {
        size_t lower, upper, nearer;
        double t;
    };
    const auto shellAt = [&](double depth) {
        const double r = kSurfaceRadiusKm - depth;
        const size_t upper = std::min(size_t(std::lower_bound(g.rKm.begin(), g.rKm.end(), r) - g.rKm.begin()), g.nR() - 1);
        const size_t lower = upper > 0 ? upper - 1 : 0;
        const double t = upper == lower ? 1.0 : (r - g.rKm[lower]) / (g.rKm[upper] - g.rKm[lower]);
        return Shell{lower, upper, t >= 0.5 ? upper : lower, t};
    };
    // The selection on the radii the shells take it from alone.
    std::vector<uint8_t> radii(g.nR(), 0);
    for (const double depth : depthsKm)
        radii[shellAt(depth).nearer] = 1;
    const HugePageVector<uint8_t> selected =
        filters.empty() ? HugePageVector<uint8_t>(g.cellCount(), 1) : selectedPoints(volume, filters, radii);
    // Read on the shells alone (two radii each): a variable not decoded yet is not decoded whole.
    using Values = dataset::StepVolume::PointValues;
    const Values v = volume.pointValues(radialVelocity);
    const Values anomaly = heat ? volume.pointValues(heat->temperatureAnomaly) : Values{};  // read only with heat
    const Values rho = density ? volume.pointValues(*density) : Values{};                  // only with density
    const auto at = [&](const Values& values, size_t iLat, size_t iR, size_t iLon) {
        return values.at(g.index(iLat, iR, iLon), iLat, iR, iLon);
    };
    constexpr double kM3PerKm3 = 1e9;
    const auto w = g.volumeFactors();
    constexpr double kKmPerCm = 1e-5;
    // ρ c_p × (cm/yr → m/s) × (km² → m²): W per (K · cm/yr · km²).
    constexpr double kSecondsPerYear = 365.25 * 86400;
    const double heatFactor = heat ? heat->densityKgM3 * heat->heatCapacityJPerKgK * (0.01 / kSecondsPerYear) * 1e6 : 0;
    std::vector<ShellFlux> out;
    for (const double depth : depthsKm) {
        checkShellDepth(g, depth);
        const double r = kSurfaceRadiusKm - depth;
        const auto [lower, upper, nearer, t] = shellAt(depth);
        ShellFlux f;
        f.depthKm = depth;
        f.radiusKm = r;
        for (size_t iLat = 0; iLat < g.nLat(); ++iLat)
            for (size_t iLon = 0; iLon < g.nLon(); ++iLon) {
                const double area = r * r * w.lat[iLat] * w.lon[iLon];
                const double vr = (1.0 - t) * at(v, iLat, lower, iLon) + t * at(v, iLat, upper, iLon);
                const double flux = vr * kKmPerCm * area;
                double heatW = 0;
                if (heat)
                    heatW = heatFactor * area * vr *
                            ((1.0 - t) * at(anomaly, iLat, lower, iLon) + t * at(anomaly, iLat, upper, iLon));
                const double mass =
                    density ? kM3PerKm3 * flux * ((1.0 - t) * at(rho, iLat, lower, iLon) + t * at(rho, iLat, upper, iLon))
                        : 0.0;
                f.areaKm2 += area;
                (flux < 0 ? f.downKm3PerYr : f.upKm3PerYr) += flux;
                (flux < 0 ? f.massDownKgPerYr : f.massUpKgPerYr) += mass;
                f.heatW += heatW;
                if (selected[g.index(iLat, nearer, iLon)]) {
                    f.selectedAreaKm2 += area;
                    (flux < 0 ? f.selectedDownKm3PerYr : f.selectedUpKm3PerYr) += flux;
                    (flux < 0 ? f.selectedMassDownKgPerYr : f.selectedMassUpKgPerYr) += mass;
                    f.selectedHeatW += heatW;
                }
            }
        out.push_back(f);
    }
    return out;
}

std::vector<size_t> avalancheSteps(std::span<const double> downKm3PerYr, double k)
{
    const size_t n = downKm3PerYr.size();
    if (n < 2)
        return {};
    double mean = 0;
    for (const double d : downKm3PerYr)
        mean += std::abs(d);
    mean /= double(n);
    double var = 0;
    for (const double d : downKm3PerYr)
        var += (std::abs(d) - mean) * (std::abs(d) - mean);
    const double sigma = std::sqrt(var / double(n));
    std::vector<size_t> steps;
    if (sigma <= 0)
        return steps;
    for (size_t i = 0; i < n; ++i)
        if (std::abs(downKm3PerYr[i]) > mean + k * sigma)
            steps.push_back(i);
    return steps;
}

std::vector<std::vector<size_t>> avalancheStepsPerShell(std::span<const std::vector<ShellFlux>> bySteps, double k)
{
    const size_t shells = bySteps.empty() ? 0 : bySteps.front().size();
    std::vector<std::vector<size_t>> out(shells);
    for (size_t d = 0; d < shells; ++d) {
        std::vector<double> down;
        for (const auto& fluxes : bySteps)
            down.push_back(fluxes.at(d).downKm3PerYr);
        out[d] = avalancheSteps(down, k);
    }
    return out;
}

}  // namespace raypc::analysis
