// The synthetic snapshot (synth.h): the model at one time evaluated at every point of a grid —
// temperature, velocity, the material properties that follow from temperature — and the temperature
// anomaly against each shell's mean.
#include "synth/synth_columns.h"

#include "core/error.h"

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <array>
#include <cmath>

namespace raypc::synth {
namespace synth {
namespace {

// ---- derived material properties ----

// Lattice conductivity (W/m/K): rises with pressure (3.3 at the surface to ~8.5 at the CMB)
// and falls as T^-1/2 relative to the reference profile, as for mantle silicates.
float conductivity(double depthKm, double temperatureK, double referenceK)
{
    const double k0 = 3.3 + 5.2 * std::pow(depthKm / kMantleThicknessKm, 1.2);
    return static_cast<float>(k0 * std::sqrt(referenceK / temperatureK));
}

// Thermal expansivity (1/K): falls with pressure (3e-5 at the surface to ~1e-5 at the CMB).
// Its temperature sensitivity changes sign in the lower mantle (the spin crossover shifts to
// higher pressure in hot material), so a negative anomaly marks cold shallow and hot deep rock,
// as in the contest data.
float expansivity(double depthKm, double temperatureK, double referenceK)
{
    const double alpha0 = 1.0e-5 + 2.0e-5 * std::exp(-depthKm / 700.0);
    const double beta = 4e-4 * (1.0 - 2.0 * smootherstep((depthKm - 1500.0) / 800.0));
    return static_cast<float>(alpha0 * (1.0 + beta * (temperatureK - referenceK)));
}

// Density anomaly (kg/m^3) from the iron spin transition in ferropericlase: the low-spin
// fraction rises across ~1600 +- 400 km depth, and hotter rock transitions deeper. The
// anomaly is the low-spin excess relative to the reference profile at the same depth, so it
// lives in the mid mantle, positive in cold and negative in hot material.
float spinDensityAnomaly(double depthKm, double temperatureK, double referenceK)
{
    constexpr double kDensityJump = 60.0, kWidthKm = 180.0, kKmPerK = 0.45, kCentreKm = 1600.0;
    auto lowSpin = [&](double dT) { return 1.0 / (1.0 + std::exp(-(depthKm - kCentreKm - kKmPerK * dT) / kWidthKm)); };
    return static_cast<float>(kDensityJump * (lowSpin(temperatureK - referenceK) - lowSpin(0.0)));
}

// The contest's eight variables on `grid`, zero, with their names and units.
grid::Snapshot contestSnapshot(const grid::SphericalGrid& grid)
{
    grid::Snapshot snap;
    snap.grid = grid;
    const auto& names = grid::contestVariableNames();
    const std::array<const char*, 8> units = {"K", "m/s", "m/s", "m/s", "W/m/K", "1/K", "K", "kg/m^3"};
    snap.fields.resize(names.size());
    for (size_t v = 0; v < names.size(); ++v) {
        snap.fields[v].name = names[v];
        snap.fields[v].units = units[v];
        snap.fields[v].values.assign(grid.cellCount(), 0.0f);
    }
    return snap;
}

// Adds the active features' parts to a cell's temperature anomaly `dT` (K) and velocity (radial `ur`,
// horizontal `uh`; m/s) at radius index iR, invR = 1 / r.
void addFeatures(const ModelAtTime& model, const std::vector<ColumnTerms>& terms, const std::vector<int>& active,
                 size_t iR, double invR, double& dT, double& ur, Vec3d& uh)
{
    for (int f : active) {
        const FeatureAtTime& fa = model.features[f];
        const ColumnTerms& ct = terms[f];
        for (int k = 0; k < fa.termCount; ++k)
            dT += fa.termRadial[k][iR] * ct.angular[k];
        if (fa.isPlume) {
            ur -= fa.f[iR] * ct.lapG * invR * invR;
            uh = uh + (fa.fPrime[iR] * invR) * ct.gradG;
            continue;
        }
        // Slab: Q = f(r) g(xi) A(psi) with xi = beta - beta0 - shift(r).
        const double xi = ct.beta - fa.beta0 - fa.shift[iR];
        dT += fa.sheetK[iR] * ct.along * sheetProfile(fa, xi, iR);
        const double w2 = fa.flowWidthRad * fa.flowWidthRad;
        if (xi * xi > 2.0 * kNegligibleExponent * w2)
            continue;
        const double g = std::exp(-0.5 * xi * xi / w2);
        const double g1 = -xi / w2 * g, g2 = (xi * xi / w2 - 1.0) / w2 * g;
        const double lapG = ct.along * (g2 - ct.tanBeta * g1) + g * ct.alongD2 * ct.invCos2;
        const double fr = fa.f[iR], fp = fa.fPrime[iR], sp = fa.shiftPrime[iR];
        ur -= fr * lapG * invR * invR;
        // u_h = grad_S(dQ/dr) / r, dQ/dr = A (f' g - f s' g').
        uh = uh + (invR * ct.along * (fp * g1 - fr * sp * g2)) * ct.gradBeta +
             (invR * ct.alongD1 * (fp * g - fr * sp * g1)) * ct.gradPsi;
    }
}

// Temperature, velocity and the properties that follow from temperature at every point of `snap`'s
// grid (every field but the anomaly). Returns per (lat row, radius) the sums of the stored
// temperature weighted by the dual cells' areas (`latWeights`, `lonWeights`), for the shell means.
std::vector<double> evaluateFields(const ModelAtTime& model, const std::vector<double>& latWeights,
                                   const std::vector<double>& lonWeights, grid::Snapshot& snap)
{
    const grid::SphericalGrid& grid = snap.grid;
    const size_t nLat = grid.nLat(), nR = grid.nR(), nLon = grid.nLon();
    float* temperature = snap.fields[0].values.data();
    float* vx = snap.fields[1].values.data();
    float* vy = snap.fields[2].values.data();
    float* vz = snap.fields[3].values.data();
    float* conduct = snap.fields[4].values.data();
    float* expans = snap.fields[5].values.data();
    float* spin = snap.fields[7].values.data();

    std::vector<double> referenceK(nR), depthKm(nR), boundaryTaper(nR);
    for (size_t i = 0; i < nR; ++i) {
        referenceK[i] = referenceTemperatureK(grid.rKm[i]);
        depthKm[i] = kSurfaceRadiusKm - grid.rKm[i];
        boundaryTaper[i] = isothermalBoundaryTaper(grid.rKm[i]);
    }
    // Per (lat row, radius) weighted sums of temperature, for the shell means; summed in a
    // fixed order afterwards so the result does not depend on thread scheduling.
    std::vector<double> rowSums(nLat * nR, 0.0);
    forEachColumn(
        model, grid,
        [&](size_t iLat, size_t iLon, Vec3d n, const std::vector<ColumnTerms>& terms, const std::vector<int>& active) {
            // Rigid rotation omega x (r n): purely horizontal, in m/s per km of radius.
            const Vec3d spinPerKm = (model.rotationRadPerSecond * 1000.0) * cross(model.rotationAxis, n);
            const BackgroundColumn bg = backgroundColumn(model.model, model.harmonicAxes, n);
            for (size_t iR = 0; iR < nR; ++iR) {
                const double r = grid.rKm[iR];
                const double invR = r > 0.0 ? 1.0 / r : 0.0;
                // Background: long-wavelength temperature and the poloidal + toroidal flow.
                double dT = model.bgMidK[iR] * bg.upwelling + model.bgTopK[iR] * bg.top + model.bgBottomK[iR] * bg.bottom;
                double ur = model.bgF[iR] * bg.upwelling * invR * invR;
                Vec3d uh = r * spinPerKm + (model.bgFPrime[iR] * invR) * bg.gradB + model.bgToroidal[iR] * bg.toroidal;
                addFeatures(model, terms, active, iR, invR, dT, ur, uh);
                const double t = referenceK[iR] + dT * boundaryTaper[iR];
                const size_t idx = grid.index(iLat, iR, iLon);
                temperature[idx] = static_cast<float>(t);
                vx[idx] = static_cast<float>(ur * n.x + uh.x);
                vy[idx] = static_cast<float>(ur * n.y + uh.y);
                vz[idx] = static_cast<float>(ur * n.z + uh.z);
                conduct[idx] = conductivity(depthKm[iR], t, referenceK[iR]);
                expans[idx] = expansivity(depthKm[iR], t, referenceK[iR]);
                spin[idx] = spinDensityAnomaly(depthKm[iR], t, referenceK[iR]);
            }
        },
        [&](size_t iLat) {
            // Shell sums of the stored (float) temperature, so the anomaly is zero-mean on
            // exactly the values a reader sees.
            for (size_t iR = 0; iR < nR; ++iR) {
                double sum = 0.0;
                const float* row = temperature + grid.index(iLat, iR, 0);
                for (size_t iLon = 0; iLon < nLon; ++iLon)
                    sum += lonWeights[iLon] * row[iLon];
                rowSums[iLat * nR + iR] = latWeights[iLat] * sum;
            }
        });
    return rowSums;
}

// Temperature anomaly: temperature minus its area-weighted mean over each shell, from the row sums
// of evaluateFields.
void subtractShellMeans(const std::vector<double>& rowSums, const std::vector<double>& latWeights,
                        const std::vector<double>& lonWeights, grid::Snapshot& snap)
{
    const grid::SphericalGrid& grid = snap.grid;
    const size_t nLat = grid.nLat(), nR = grid.nR(), nLon = grid.nLon();
    const float* temperature = snap.fields[0].values.data();
    float* anomaly = snap.fields[6].values.data();
    double totalLonWeight = 0.0, totalLatWeight = 0.0;
    for (double w : lonWeights)
        totalLonWeight += w;
    for (double w : latWeights)
        totalLatWeight += w;
    std::vector<double> shellMean(nR, 0.0);
    for (size_t iR = 0; iR < nR; ++iR) {
        double sum = 0.0;
        for (size_t iLat = 0; iLat < nLat; ++iLat)
            sum += rowSums[iLat * nR + iR];
        shellMean[iR] = sum / (totalLatWeight * totalLonWeight);
    }
    tbb::parallel_for(tbb::blocked_range<size_t>(0, nLat), [&](const tbb::blocked_range<size_t>& rows) {
        for (size_t iLat = rows.begin(); iLat != rows.end(); ++iLat)
            for (size_t iR = 0; iR < nR; ++iR) {
                const size_t base = grid.index(iLat, iR, 0);
                for (size_t iLon = 0; iLon < nLon; ++iLon)
                    anomaly[base + iLon] = static_cast<float>(temperature[base + iLon] - shellMean[iR]);
            }
    });
}

}  // namespace
}  // namespace synth

grid::Snapshot synthesizeSnapshot(const SynthOptions& options, double timeMyr)
{
    return synthesizeSnapshot(options, timeMyr, syntheticGrid(options.nLat, options.nR, options.nLon));
}

grid::Snapshot synthesizeSnapshot(const SynthOptions& options, double timeMyr, const grid::SphericalGrid& grid)
{
    if (!std::isfinite(timeMyr))
        fail("synthetic snapshot: time {} Myr is not finite", timeMyr);
    const synth::ModelAtTime model = synth::modelAt(options, timeMyr, grid.rKm);
    grid::Snapshot snap = synth::contestSnapshot(grid);
    // Dual-cell area weights: lat rows by sin(upper edge) - sin(lower edge), lon columns by width.
    const std::vector<double> latWeights = grid.volumeFactors().lat;
    const std::vector<double> lonWeights = grid.lonWidthsDeg();
    const std::vector<double> rowSums = synth::evaluateFields(model, latWeights, lonWeights, snap);
    synth::subtractShellMeans(rowSums, latWeights, lonWeights, snap);
    return snap;
}

}  // namespace raypc::synth
