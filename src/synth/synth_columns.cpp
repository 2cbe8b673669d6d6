// Each feature of the synthetic mantle at one grid column (synth_columns.h): a plume's flow pattern
// and its surface derivatives, a slab's angular coordinates about its trench and the trench's taper,
// and the angular factors of the separable temperature terms.
#include "synth/synth_columns.h"

#include <algorithm>
#include <cmath>

namespace raypc::synth::synth {
namespace {

// Angular part of a plume's flow potential at the unit vector n.
double plumeFlowAngular(const FeatureAtTime& fa, Vec3d n)
{
    const double w = fa.flowWidthRad;
    return std::exp(-(1.0 - dot(n, fa.axis)) / (w * w));
}

// Surface Laplacian and gradient of a plume's G on the unit sphere by geodesic central
// differences in an orthonormal tangent basis (e1, e2): at the origin of Riemann normal
// coordinates the Laplace-Beltrami operator is the flat Laplacian, so the stencil is second order.
void surfaceDerivatives(const FeatureAtTime& fa, Vec3d n, Vec3d e1, Vec3d e2, ColumnTerms& out)
{
    constexpr double h = 2e-4;  // radians (~1 km); features are >= 0.03 rad wide
    const double c = std::cos(h), s = std::sin(h);
    const double g0 = plumeFlowAngular(fa, n);
    const double g1p = plumeFlowAngular(fa, c * n + s * e1), g1m = plumeFlowAngular(fa, c * n - s * e1);
    const double g2p = plumeFlowAngular(fa, c * n + s * e2), g2m = plumeFlowAngular(fa, c * n - s * e2);
    out.lapG = (g1p + g1m + g2p + g2m - 4.0 * g0) / (h * h);
    out.gradG = ((g1p - g1m) / (2.0 * h)) * e1 + ((g2p - g2m) / (2.0 * h)) * e2;
}

// One feature's terms at the column's unit vector n, with (e1, e2) an orthonormal tangent basis
// there; out.active is false where the feature is negligible, and nothing else is set then.
void columnTerms(const FeatureAtTime& fa, Vec3d n, Vec3d e1, Vec3d e2, ColumnTerms& out)
{
    double widest = std::max(fa.flowWidthRad, fa.sheetWidthMax);
    for (int k = 0; k < fa.termCount; ++k)
        widest = std::max(widest, fa.termWidthRad[k]);
    if (fa.isPlume) {
        const double chord2 = 2.0 * (1.0 - dot(n, fa.axis));
        out.active = chord2 < 2.0 * kNegligibleExponent * widest * widest;
        if (!out.active)
            return;
        for (int k = 0; k < fa.termCount; ++k)
            out.angular[k] = std::exp(-0.5 * chord2 / (fa.termWidthRad[k] * fa.termWidthRad[k]));
        surfaceDerivatives(fa, n, e1, e2, out);
        return;
    }
    // Slab: beta = asin(n . pole) (|grad beta| = 1, lap beta = -tan beta), psi = azimuth about
    // the pole from arcE1 (|grad psi| = 1 / cos beta, lap psi = 0, grad beta . grad psi = 0).
    const double x = std::clamp(dot(n, fa.pole), -1.0, 1.0);
    const double cos2 = 1.0 - x * x;
    const double beta = std::asin(x);
    const double margin = std::sqrt(2.0 * kNegligibleExponent) * widest;
    const double rel = beta - fa.beta0;
    out.active = cos2 > 1e-6 && rel > fa.shiftLo - margin && rel < fa.shiftHi + margin;
    if (!out.active)
        return;
    const double psi = std::atan2(dot(n, fa.arcE2), dot(n, fa.arcE1));
    const double cosBeta = std::sqrt(cos2);
    // Beyond the arc's ends by more than a few widths nothing remains either.
    const double psiMargin = margin / cosBeta;
    out.active = psi > -psiMargin && psi < fa.arcAngle + psiMargin;
    if (!out.active)
        return;
    out.beta = beta;
    out.invCos2 = 1.0 / cos2;
    out.tanBeta = x / cosBeta;
    out.gradBeta = (1.0 / cosBeta) * (fa.pole - x * n);
    out.gradPsi = (1.0 / cos2) * cross(fa.pole, n);
    // The trench taper A(psi) = S(psi / tau) S((Psi - psi) / tau) and its derivatives.
    const double tau = std::min(0.15, fa.arcAngle / 3.0);
    auto S = [](double t, double& d1, double& d2) {
        if (t <= 0.0) {
            d1 = d2 = 0.0;
            return 0.0;
        }
        if (t >= 1.0) {
            d1 = d2 = 0.0;
            return 1.0;
        }
        d1 = 30.0 * t * t * (1.0 - t) * (1.0 - t);
        d2 = 60.0 * t * (1.0 - t) * (1.0 - 2.0 * t);
        return t * t * t * (t * (6.0 * t - 15.0) + 10.0);
    };
    double a1 = 0, a2 = 0, b1 = 0, b2 = 0;
    const double a = S(psi / tau, a1, a2), b = S((fa.arcAngle - psi) / tau, b1, b2);
    out.along = a * b;
    out.alongD1 = (a1 * b - a * b1) / tau;
    out.alongD2 = (a2 * b - 2.0 * a1 * b1 + a * b2) / (tau * tau);
    // Separable terms (pancakes, pool) extend beyond the arc's ends with a Gaussian fall-off.
    const double outside = (psi < 0.0 ? -psi : (psi > fa.arcAngle ? psi - fa.arcAngle : 0.0)) * cosBeta;
    for (int k = 0; k < fa.termCount; ++k) {
        const double xi = rel - fa.termShift[k];
        const double w2 = fa.termWidthRad[k] * fa.termWidthRad[k];
        out.angular[k] = std::exp(-0.5 * (xi * xi + outside * outside) / w2);
    }
}

}  // namespace

Vec3d featuresOfColumn(const ModelAtTime& model, double latDeg, double lonDeg, std::vector<ColumnTerms>& terms,
                       std::vector<int>& active)
{
    const double lat = degToRad(latDeg), lon = degToRad(lonDeg);
    const Vec3d n{std::cos(lat) * std::cos(lon), std::cos(lat) * std::sin(lon), std::sin(lat)};
    const Vec3d east{-std::sin(lon), std::cos(lon), 0.0};
    const Vec3d north = cross(n, east);
    active.clear();
    for (size_t f = 0; f < model.features.size(); ++f) {
        columnTerms(model.features[f], n, east, north, terms[f]);
        if (terms[f].active)
            active.push_back(static_cast<int>(f));
    }
    return n;
}

}  // namespace raypc::synth::synth
