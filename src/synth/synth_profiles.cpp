// The synthetic mantle's radial profiles (synth_model.h): the reference temperature, the tapers at the
// isothermal boundaries, and the radial shapes of the features' and the background's flow with their
// notches at the layers.
#include "synth/synth_model.h"

#include <algorithm>
#include <cmath>

namespace raypc::synth::synth {
namespace {

// Notches of vertical flow at the layers a flow passes (not the one where it stalls).
double layerNotches(double rKm, int stallLayer)
{
    double shape = 1.0;
    for (int l = 0; l < static_cast<int>(kLayers.size()); ++l) {
        if (l == stallLayer)
            continue;
        const double t = (rKm - layerRadiusKm(l)) / kLayers[l].notchHalfWidthKm;
        shape *= 1.0 - kLayers[l].notchDepth * std::exp(-t * t);
    }
    return shape;
}

}  // namespace

double cmbLayerPeak(double decayKm)
{
    const double q = kCmbTaperKm / (kCmbTaperKm + decayKm);
    return std::pow(q, kCmbTaperKm / decayKm) * (1.0 - q);
}

double referenceTemperatureK(double rKm)
{
    const double depth = std::clamp(kSurfaceRadiusKm - rKm, 0.0, kMantleThicknessKm);
    const double adiabat = 1600.0 + 0.3 * depth;
    const double adiabatAtCmb = 1600.0 + 0.3 * kMantleThicknessKm;
    return adiabat - (1600.0 - 300.0) * std::erfc(depth / 120.0) +
           (4000.0 - adiabatAtCmb) * std::erfc((kMantleThicknessKm - depth) / 150.0);
}

double isothermalBoundaryTaper(double rKm)
{
    const double depthKm = kSurfaceRadiusKm - rKm;
    return (1.0 - std::exp(-std::max(0.0, depthKm) / kSurfaceTaperKm)) *
           (1.0 - std::exp(-std::max(0.0, rKm - kCoreRadiusKm) / kCmbTaperKm));
}

double pancakeStrength(double frontKm, double layerKm, double approachSign)
{
    const double ahead = approachSign * (layerKm - frontKm);  // > 0: not yet at the layer
    const double near = std::exp(-(ahead / 200.0) * (ahead / 200.0));
    return ahead >= 0.0 ? near : 0.5 + 0.5 * near;
}

double flowShape(double rKm, double frontKm, int stallLayer, double direction, bool released)
{
    constexpr double kAheadKm = 400.0;
    // sin(pi x) vanishes at both boundaries; it is not cut off outside them, so that f' (a
    // central difference) stays exact on the boundary rows themselves.
    const double x = (rKm - kCoreRadiusKm) / kMantleThicknessKm;
    double shape = std::sin(kPi * x) * layerNotches(rKm, stallLayer);
    if (stallLayer != kNoLayer && !released) {
        // The feature cannot cross this layer: its flow ends there, with a steep decline
        // just before it that turns vertical flow into lateral spreading.
        shape *= smootherstep(direction * (layerRadiusKm(stallLayer) - rKm) / 250.0);
    }
    const double beyond = direction * (rKm - frontKm);
    if (beyond > 0.0)
        shape *= std::exp(-(beyond / kAheadKm) * (beyond / kAheadKm));
    return shape;
}

double backgroundShape(double rKm)
{
    const double x = (rKm - kCoreRadiusKm) / kMantleThicknessKm;
    return std::sin(kPi * x) * layerNotches(rKm, kNoLayer);
}

double toroidalShape(double rKm)
{
    const double depth = kSurfaceRadiusKm - rKm;
    return (rKm / kSurfaceRadiusKm) * std::exp(-depth / 700.0);
}

}  // namespace raypc::synth::synth
