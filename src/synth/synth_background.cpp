// The synthetic mantle's background (synth_model.h): long-wavelength patterns of flow and temperature
// from a few zonal spherical harmonics, evaluated at a column, and their radial tables.
#include "synth/synth_model.h"

#include <cmath>

namespace raypc::synth::synth {
namespace {

// Background magnitudes.
constexpr double kBackgroundUpwellingCmPerYr = 0.7;   // peak |u_r| of the poloidal background
constexpr double kBackgroundToroidalCmPerYr = 0.8;    // peak toroidal speed at the surface
constexpr double kBackgroundMidK = 30.0;              // mid-mantle lateral variation
constexpr double kBackgroundTopK = 70.0;              // top boundary layer
constexpr double kBackgroundBottomK = 90.0;           // bottom boundary layer

// Legendre P_l(mu) and its derivative, by the three-term recurrences (no singularity at |mu| = 1).
void legendre(int l, double mu, double& p, double& dp)
{
    double p0 = 1.0, p1 = mu, d0 = 0.0, d1 = 1.0;
    if (l == 0) {
        p = 1.0;
        dp = 0.0;
        return;
    }
    for (int k = 2; k <= l; ++k) {
        const double p2 = ((2.0 * k - 1.0) * mu * p1 - (k - 1.0) * p0) / k;
        const double d2 = d0 + (2.0 * k - 1.0) * p1;
        p0 = p1;
        p1 = p2;
        d0 = d1;
        d1 = d2;
    }
    p = p1;
    dp = d1;
}

}  // namespace

BackgroundColumn backgroundColumn(const Model& model, const std::vector<Vec3d>& axes, Vec3d n)
{
    BackgroundColumn b;
    size_t a = 0;
    double p = 0, dp = 0;
    for (const Harmonic& h : model.poloidal) {
        const Vec3d ax = axes[a++];
        const double mu = dot(n, ax);
        legendre(h.degree, mu, p, dp);
        b.upwelling += h.coeff * h.degree * (h.degree + 1) * p;
        b.gradB = b.gradB + (h.coeff * dp) * (ax - mu * n);
    }
    for (const Harmonic& h : model.toroidal) {
        const Vec3d ax = axes[a++];
        legendre(h.degree, dot(n, ax), p, dp);
        b.toroidal = b.toroidal + (h.coeff * dp) * cross(n, ax);
    }
    for (const Harmonic& h : model.top) {
        legendre(h.degree, dot(n, axes[a++]), p, dp);
        b.top += h.coeff * p;
    }
    for (const Harmonic& h : model.bottom) {
        legendre(h.degree, dot(n, axes[a++]), p, dp);
        b.bottom += h.coeff * p;
    }
    b.upwelling /= model.poloidalNorm;
    b.gradB = (1.0 / model.poloidalNorm) * b.gradB;
    b.toroidal = (1.0 / model.toroidalNorm) * b.toroidal;
    b.top /= model.topNorm;
    b.bottom /= model.bottomNorm;
    return b;
}

std::vector<Vec3d> harmonicAxes(const Model& model, double turn)
{
    std::vector<Vec3d> axes;
    for (const auto* set : {&model.poloidal, &model.toroidal, &model.top, &model.bottom})
        for (const Harmonic& h : *set)
            axes.push_back(rotate(h.axis0, model.rotationAxis, turn));
    return axes;
}

double backgroundPotential(double rKm)
{
    const double v = kBackgroundUpwellingCmPerYr * 0.01 / (kSecondsPerMyr / 1e6);
    return v * rKm * rKm * backgroundShape(rKm);
}

double backgroundRadialVelocity(const Model& model, const std::vector<Vec3d>& axes0, Vec3d n, double rKm)
{
    double up = 0, p = 0, dp = 0;
    size_t a = 0;
    for (const Harmonic& h : model.poloidal) {
        legendre(h.degree, dot(n, axes0[a++]), p, dp);
        up += h.coeff * h.degree * (h.degree + 1) * p;
    }
    return backgroundPotential(rKm) / (rKm * rKm) * up / model.poloidalNorm;
}

void backgroundTables(const std::vector<double>& rKm, ModelAtTime& m)
{
    const size_t nR = rKm.size();
    potentialTables(rKm, backgroundPotential, m.bgF, m.bgFPrime);
    m.bgToroidal.resize(nR);
    m.bgMidK.resize(nR);
    m.bgTopK.resize(nR);
    m.bgBottomK.resize(nR);
    const double toroidalMps = kBackgroundToroidalCmPerYr * 0.01 / (kSecondsPerMyr / 1e6);
    for (size_t i = 0; i < nR; ++i) {
        const double r = rKm[i];
        m.bgToroidal[i] = toroidalMps * toroidalShape(r);
        const double depth = kSurfaceRadiusKm - r, above = r - kCoreRadiusKm;
        // The mid-mantle pattern follows the background upwelling (hot where it rises).
        m.bgMidK[i] = kBackgroundMidK * backgroundShape(r);
        m.bgTopK[i] = kBackgroundTopK * std::exp(-depth / 180.0);
        m.bgBottomK[i] = kBackgroundBottomK * std::exp(-above / 220.0);
    }
}

}  // namespace raypc::synth::synth
