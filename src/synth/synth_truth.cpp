// The generator's ground truth (synth.h): which feature and part of it the model put at each grid
// point, and the table of every step's features that `raypc synth --truth` writes.
#include "synth/synth_columns.h"

#include "core/error.h"

#include <fmt/format.h>

#include <array>
#include <cmath>

namespace raypc::synth {

const char* synthPartName(SynthPart part)
{
    switch (part) {
    case SynthPart::Background: return "background";
    case SynthPart::PlumeConduit: return "plume conduit";
    case SynthPart::PlumeHead: return "plume head";
    case SynthPart::PlumePile: return "plume pile";
    case SynthPart::PlumePancake660: return "plume pancake 660";
    case SynthPart::PlumePancake1600: return "plume pancake 1600";
    case SynthPart::SlabSheet: return "slab sheet";
    case SynthPart::SlabPancake660: return "slab pancake 660";
    case SynthPart::SlabPancake1600: return "slab pancake 1600";
    case SynthPart::SlabPool: return "slab pool";
    }
    return "?";
}

SynthTruth syntheticTruth(const SynthOptions& options, double timeMyr, const grid::SphericalGrid& grid)
{
    if (!std::isfinite(timeMyr))
        fail("synthetic truth: time {} Myr is not finite", timeMyr);
    const size_t nR = grid.nR();
    const synth::ModelAtTime model = synth::modelAt(options, timeMyr, grid.rKm);
    SynthTruth truth;
    truth.feature.assign(grid.cellCount(), -1);
    truth.part.assign(grid.cellCount(), SynthPart::Background);
    truth.envelope.assign(grid.cellCount(), 0.0f);
    std::vector<double> taper(nR);
    for (size_t i = 0; i < nR; ++i)
        taper[i] = synth::isothermalBoundaryTaper(grid.rKm[i]);

    // The same columns and radial tables synthesizeSnapshot sums, compared term by term.
    using synth::ColumnTerms, synth::FeatureAtTime;
    synth::forEachColumn(
        model, grid,
        [&](size_t iLat, size_t iLon, Vec3d, const std::vector<ColumnTerms>& terms, const std::vector<int>& active) {
            for (size_t iR = 0; iR < nR; ++iR) {
                double bestK = 0.0, bestEnvelope = 0.0;
                int bestFeature = -1;
                SynthPart bestPart = SynthPart::Background;
                // A part competes where its envelope reaches the extent; the largest anomaly wins.
                auto consider = [&](int f, SynthPart part, double anomalyK, double peakK) {
                    if (peakK == 0.0)
                        return;
                    const double envelope = anomalyK / peakK;
                    if (envelope >= kSynthExtent && std::abs(anomalyK) > bestK) {
                        bestK = std::abs(anomalyK);
                        bestEnvelope = envelope;
                        bestFeature = f;
                        bestPart = part;
                    }
                };
                for (int f : active) {
                    const FeatureAtTime& fa = model.features[f];
                    const ColumnTerms& ct = terms[f];
                    for (int k = 0; k < fa.termCount; ++k)
                        consider(f, fa.termPart[k], fa.termRadial[k][iR] * ct.angular[k] * taper[iR],
                                 fa.termPeakK[k][iR]);
                    if (!fa.isPlume) {
                        const double xi = ct.beta - fa.beta0 - fa.shift[iR];
                        consider(f, SynthPart::SlabSheet,
                                 fa.sheetK[iR] * ct.along * synth::sheetProfile(fa, xi, iR) * taper[iR], fa.sheetPeakK[iR]);
                    }
                }
                const size_t idx = grid.index(iLat, iR, iLon);
                truth.feature[idx] = static_cast<int16_t>(bestFeature);
                truth.part[idx] = bestPart;
                truth.envelope[idx] = static_cast<float>(bestEnvelope);
            }
        },
        [](size_t) {});
    return truth;
}

std::string syntheticTruthTable(const SynthOptions& options)
{
    if (options.steps < 1)
        fail("synthetic truth: {} steps, expected at least 1", options.steps);
    const grid::SphericalGrid grid = syntheticGrid(options.nLat, options.nR, options.nLon);
    const auto w = grid.volumeFactors();
    std::string csv = "step,time_myr,feature,kind,front_depth_km,stall_depth_km,front_at_stall,lat_deg,lon_deg,"
                      "core_volume_km3,pancake_660_core_km3,pancake_1600_core_km3,breaking_through\n";
    for (int step = 0; step < options.steps; ++step) {
        const double t = step * options.dtMyr;
        const std::vector<SynthFeature> features = syntheticFeatures(options, t);
        const SynthTruth truth = syntheticTruth(options, t, grid);
        std::vector<std::array<double, 3>> volumes(features.size(), {0, 0, 0});  // core, pancake 660, 1600
        for (size_t iLat = 0; iLat < grid.nLat(); ++iLat)
            for (size_t iR = 0; iR < grid.nR(); ++iR)
                for (size_t iLon = 0; iLon < grid.nLon(); ++iLon) {
                    const size_t i = grid.index(iLat, iR, iLon);
                    if (truth.feature[i] < 0 || !truth.inCore(i))
                        continue;
                    auto& v = volumes[size_t(truth.feature[i])];
                    const double dv = w.at(iLat, iR, iLon);
                    v[0] += dv;
                    const SynthPart part = truth.part[i];
                    if (part == SynthPart::PlumePancake660 || part == SynthPart::SlabPancake660)
                        v[1] += dv;
                    if (part == SynthPart::PlumePancake1600 || part == SynthPart::SlabPancake1600)
                        v[2] += dv;
                }
        for (size_t k = 0; k < features.size(); ++k) {
            const SynthFeature& f = features[k];
            const double front = kSurfaceRadiusKm - f.frontRadiusKm;
            const bool atStall = f.stallDepthKm > 0 && std::abs(front - f.stallDepthKm) <= 50.0;
            csv += fmt::format("{},{},{},{},{:.3f},{:g},{},{:.4f},{:.4f},{:.6e},{:.6e},{:.6e},{}\n", step, t, k,
                               f.kind == SynthFeature::Kind::Plume ? "plume" : "slab", front, f.stallDepthKm,
                               atStall ? 1 : 0, f.latDeg, f.lonDeg, volumes[k][0], volumes[k][1], volumes[k][2],
                               f.breakingThrough ? 1 : 0);
        }
    }
    return csv;
}

}  // namespace raypc::synth
