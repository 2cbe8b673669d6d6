// Synthetic mantle convection (see docs/synthetic-data.md for the model and its parameters).
//
// The model is a handful of features (plumes rising from the core-mantle boundary, slabs sinking
// from the surface) on top of a radial temperature profile. Every feature contributes
//   - a velocity from a poloidal potential Q = f(r) G(n) (n the unit position vector):
//       u_r = -lap_S G * f / r^2,   u_h = grad_S G * f'(r) / r,
//     which is divergence-free for any f and G, since div u = (f' lap_S G - f' lap_S G) / r^2;
//   - a temperature anomaly that is a sum of separable terms R_k(r) * A_k(n).
// Separability is what makes the generator fast: angular factors are computed once per
// (lat, lon) column and radial factors once per radius, so a cell costs a few multiply-adds.
// Plume heads and slab tips move with the flow of their own feature (integrated in time), and
// the whole pattern turns with a slow rigid rotation that is also part of the velocity, so the
// series is consistent with its velocity field.
#include "data/synth.h"

#include "core/atomic_file.h"
#include "core/error.h"
#include "core/progress.h"
#include "core/spherical.h"
#include "core/strings.h"

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <array>
#include <charconv>
#include <cmath>
#include <random>

namespace raypc {
namespace {

constexpr double kPi = std::numbers::pi;
constexpr double kMantleThicknessKm = kSurfaceRadiusKm - kCoreRadiusKm;

// ---- small vector helpers (Cartesian, unit sphere or km) ----

Vec3d operator+(Vec3d a, Vec3d b) { return {a.x + b.x, a.y + b.y, a.z + b.z}; }
Vec3d operator-(Vec3d a, Vec3d b) { return {a.x - b.x, a.y - b.y, a.z - b.z}; }
Vec3d operator*(double s, Vec3d a) { return {s * a.x, s * a.y, s * a.z}; }
double dot(Vec3d a, Vec3d b) { return a.x * b.x + a.y * b.y + a.z * b.z; }
Vec3d cross(Vec3d a, Vec3d b) { return {a.y * b.z - a.z * b.y, a.z * b.x - a.x * b.z, a.x * b.y - a.y * b.x}; }
Vec3d normalized(Vec3d a) { return (1.0 / std::sqrt(dot(a, a))) * a; }

// Rodrigues rotation of `v` about the unit `axis` by `angle` radians.
Vec3d rotate(Vec3d v, Vec3d axis, double angle)
{
    const double c = std::cos(angle), s = std::sin(angle);
    return c * v + s * cross(axis, v) + (dot(axis, v) * (1.0 - c)) * axis;
}

// C2-continuous step from 0 (t <= 0) to 1 (t >= 1); f' must be smooth for the velocity.
double smootherstep(double t)
{
    t = std::clamp(t, 0.0, 1.0);
    return t * t * t * (t * (6.0 * t - 15.0) + 10.0);
}

// Deterministic across standard libraries: mt19937_64 is fully specified, while the
// std:: distributions are not, so uniform doubles are made from the raw bits.
class Rng {
public:
    explicit Rng(uint64_t seed) : m_engine(seed) {}
    double uniform() { return static_cast<double>(m_engine() >> 11) * 0x1.0p-53; }
    double uniform(double lo, double hi) { return lo + (hi - lo) * uniform(); }
    Vec3d onSphere()
    {
        const double z = uniform(-1.0, 1.0), phi = uniform(0.0, 2.0 * kPi);
        const double s = std::sqrt(std::max(0.0, 1.0 - z * z));
        return {s * std::cos(phi), s * std::sin(phi), z};
    }

private:
    std::mt19937_64 m_engine;
};

// ---- the layers where material stagnates ----

struct Layer {
    double depthKm;
    double notchHalfWidthKm;  // how thick the slow-down of vertical flow is
    double notchDepth;        // fraction of vertical speed lost at the layer when passing
};
// 660 km: the ringwoodite -> bridgmanite + ferropericlase transition (endothermic, resists flow).
// 1600 km: the iron spin transition in ferropericlase, which in the contest data also shows
// stagnation. Narrow notches with steep flanks give strong lateral flow around the layers.
constexpr std::array<Layer, 2> kLayers = {{{660.0, 70.0, 0.85}, {1600.0, 110.0, 0.8}}};
constexpr int kNoLayer = -1;

double layerRadiusKm(int layer) { return kSurfaceRadiusKm - kLayers[layer].depthKm; }

// ---- the radial reference state ----

// Temperature at rest (K): 300 K surface, ~120 km top boundary layer into an adiabat of
// 0.3 K/km starting at 1600 K, and a ~150 km hot boundary layer up to 4000 K at the CMB.
double referenceTemperatureK(double rKm)
{
    const double depth = std::clamp(kSurfaceRadiusKm - rKm, 0.0, kMantleThicknessKm);
    const double adiabat = 1600.0 + 0.3 * depth;
    const double adiabatAtCmb = 1600.0 + 0.3 * kMantleThicknessKm;
    return adiabat - (1600.0 - 300.0) * std::erfc(depth / 120.0) +
           (4000.0 - adiabatAtCmb) * std::erfc((kMantleThicknessKm - depth) / 150.0);
}

// ---- the features ----

struct Plume {
    Vec3d axis0;            // unit vector at t = 0
    double speedMps;        // peak upwelling on the axis
    double amplitudeK;      // tail excess temperature
    double headRadius0Km;   // radius of the head centre at t = 0
    int stallLayer;         // index into kLayers, or kNoLayer when it passes through
};

struct Slab {
    Vec3d start0, end0;     // ends of the trench-parallel great-circle arc at t = 0
    double speedMps;        // peak downwelling in the sheet
    double amplitudeK;      // (negative) temperature deficit
    double tipRadius0Km;    // radius of the slab tip at t = 0
    int stallLayer;
};

struct Model {
    Vec3d rotationAxis;
    double rotationRadPerMyr;
    std::vector<Plume> plumes;
    std::vector<Slab> slabs;
};

// Lateral sizes (km, measured at the reference radius of each term).
constexpr double kPlumeFlowWidthKm = 420.0;   // angular width of the plume's flow potential
constexpr double kPlumeTailSigmaKm = 180.0;
constexpr double kPlumeHeadSigmaKm = 380.0;
constexpr double kPlumeHeadRadialSigmaKm = 200.0;
constexpr double kPlumeBaseSigmaKm = 550.0;   // the hot pool feeding a plume at the CMB
constexpr double kPancakeSigmaKm = 950.0;     // material spreading along a layer
constexpr double kPancakeRadialSigmaKm = 60.0;
constexpr double kPancakeOffsetKm = 70.0;     // below the layer for plumes, above for slabs
constexpr double kSlabFlowWidthKm = 260.0;
constexpr double kSlabSigmaKm = 170.0;
constexpr double kFlowReferenceRadiusKm = 5000.0;

// Where the front of a feature (head, tip) is relative to a layer: 1 while it lingers near the
// layer, decaying to 0 far below / above it; after passing, half of the spread material remains.
double pancakeStrength(double frontKm, double layerKm, double approachSign)
{
    const double ahead = approachSign * (layerKm - frontKm);  // > 0: not yet at the layer
    const double near = std::exp(-(ahead / 200.0) * (ahead / 200.0));
    return ahead >= 0.0 ? near : 0.5 + 0.5 * near;
}

// Radial profile (dimensionless, 0 at both boundaries) of a feature's flow. `front` is the head
// or tip radius; flow fades over `kAheadKm` beyond it; `direction` is +1 for rising plumes.
double flowShape(double rKm, double frontKm, int stallLayer, double direction)
{
    constexpr double kAheadKm = 400.0;
    // sin(pi x) vanishes at both boundaries; it is not cut off outside them, so that f' (a
    // central difference) stays exact on the boundary rows themselves.
    const double x = (rKm - kCoreRadiusKm) / kMantleThicknessKm;
    double shape = std::sin(kPi * x);
    for (int l = 0; l < static_cast<int>(kLayers.size()); ++l) {
        const double rl = layerRadiusKm(l);
        if (l == stallLayer) {
            // The feature cannot cross this layer: its flow ends there, with a steep decline
            // just before it that turns vertical flow into lateral spreading.
            shape *= smootherstep(direction * (rl - rKm) / 250.0);
        } else {
            const double t = (rKm - rl) / kLayers[l].notchHalfWidthKm;
            shape *= 1.0 - kLayers[l].notchDepth * std::exp(-t * t);
        }
    }
    const double beyond = direction * (rKm - frontKm);
    if (beyond > 0.0)
        shape *= std::exp(-(beyond / kAheadKm) * (beyond / kAheadKm));
    return shape;
}

// Moves a head or tip with its own axis speed: dr/dt = direction * speed * shape(r).
// RK4 in steps of at most 0.05 Myr; the head sits at shape's "front" so the fade-out is 1.
double integrateFrontKm(double front0Km, double speedMps, int stallLayer, double direction, double timeMyr)
{
    const double kmPerMyr = speedMps * kSecondsPerMyr / 1000.0;
    auto rate = [&](double r) { return direction * kmPerMyr * flowShape(r, r, stallLayer, direction); };
    const int steps = std::max(1, static_cast<int>(std::ceil(std::abs(timeMyr) / 0.05)));
    const double h = timeMyr / steps;
    double r = front0Km;
    for (int i = 0; i < steps; ++i) {
        const double k1 = rate(r), k2 = rate(r + 0.5 * h * k1), k3 = rate(r + 0.5 * h * k2), k4 = rate(r + h * k3);
        r += h / 6.0 * (k1 + 2.0 * k2 + 2.0 * k3 + k4);
        r = std::clamp(r, kCoreRadiusKm + 20.0, kSurfaceRadiusKm - 20.0);
    }
    return r;
}

// Picks well-separated random unit vectors (rejection with a bounded number of tries, so any
// seed terminates; late picks may then be closer than `minAngle`).
Vec3d pickSeparated(Rng& rng, const std::vector<Vec3d>& taken, double minAngleRad)
{
    Vec3d best{};
    double bestAngle = -1.0;
    for (int attempt = 0; attempt < 200; ++attempt) {
        const Vec3d p = rng.onSphere();
        double nearest = kPi;
        for (const Vec3d& q : taken)
            nearest = std::min(nearest, std::acos(std::clamp(dot(p, q), -1.0, 1.0)));
        if (nearest > bestAngle) {
            best = p;
            bestAngle = nearest;
        }
        if (nearest >= minAngleRad)
            break;
    }
    return best;
}

// The cast of features. Their roles are fixed so every seed shows every phenomenon the contest
// tasks look for; the seed decides positions, orientations, strengths and starting depths.
Model buildModel(uint64_t seed)
{
    Rng rng(seed ^ 0x5eed5eed12345678ull);
    Model model;
    model.rotationAxis = rng.onSphere();
    // ~1 cm/yr at the surface: the whole pattern drifts by a couple of degrees over 24 Myr.
    const double surfaceSpeedMps = rng.uniform(0.8, 1.2) * 0.01 / (kSecondsPerMyr / 1e6);
    model.rotationRadPerMyr = surfaceSpeedMps * kSecondsPerMyr / (kSurfaceRadiusKm * 1000.0);

    std::vector<Vec3d> taken;
    const double cmPerYr = 0.01 / (kSecondsPerMyr / 1e6);  // in m/s
    struct PlumeRole {
        double headDepthKm;
        int stallLayer;
    };
    // Heads: one already in the upper mantle, one below 660 about to slow down, one below the
    // spin layer, two stalling (at 660 and at 1600 km), one young plume near the CMB.
    const std::array<PlumeRole, 6> plumeRoles = {
        {{450.0, kNoLayer}, {1000.0, kNoLayer}, {1850.0, kNoLayer}, {1780.0, 1}, {820.0, 0}, {2450.0, kNoLayer}}};
    for (const PlumeRole& role : plumeRoles) {
        Plume p;
        p.axis0 = pickSeparated(rng, taken, degToRad(40.0));
        taken.push_back(p.axis0);
        p.speedMps = rng.uniform(3.0, 4.5) * cmPerYr;
        p.amplitudeK = rng.uniform(250.0, 380.0);
        p.headRadius0Km = kSurfaceRadiusKm - role.headDepthKm + rng.uniform(-60.0, 60.0);
        p.stallLayer = role.stallLayer;
        model.plumes.push_back(p);
    }
    struct SlabRole {
        double tipDepthKm;
        int stallLayer;
    };
    // Tips: two lying on 660, one in the upper mantle heading for 660, one between the layers,
    // one crossing the spin layer, one deep in the lower mantle.
    const std::array<SlabRole, 5> slabRoles = {
        {{560.0, 0}, {420.0, 0}, {1150.0, kNoLayer}, {1500.0, kNoLayer}, {2150.0, kNoLayer}}};
    for (const SlabRole& role : slabRoles) {
        Slab s;
        const Vec3d mid = pickSeparated(rng, taken, degToRad(35.0));
        taken.push_back(mid);
        // A random direction tangent at `mid`, and an arc of 25-50 degrees along it.
        Vec3d tangent = cross(mid, rng.onSphere());
        tangent = normalized(tangent);
        const double halfArc = degToRad(rng.uniform(12.5, 25.0));
        s.start0 = std::cos(halfArc) * mid - std::sin(halfArc) * tangent;
        s.end0 = std::cos(halfArc) * mid + std::sin(halfArc) * tangent;
        s.speedMps = rng.uniform(3.5, 5.0) * cmPerYr;
        s.amplitudeK = -rng.uniform(320.0, 480.0);
        s.tipRadius0Km = kSurfaceRadiusKm - role.tipDepthKm + rng.uniform(-50.0, 50.0);
        s.stallLayer = role.stallLayer;
        model.slabs.push_back(s);
    }
    return model;
}

// ---- the model at one time, ready to evaluate on a grid ----

// Terms of one feature: the flow potential's angular part and the temperature's angular
// factors, evaluated per column; the radial tables per radius.
constexpr int kMaxTerms = 5;

struct FeatureAtTime {
    bool isPlume = true;
    // Plume: axis. Slab: arc start, in-plane unit vector towards the end, and the arc's normal.
    Vec3d axis{}, arcE1{}, arcE2{}, arcNormal{};
    double arcAngle = 0;
    double flowWidthRad = 0;  // angular width of G
    int termCount = 0;
    // Angular widths (radians) of the temperature terms.
    std::array<double, kMaxTerms> termWidthRad{};
    // Radial tables (per grid radius): flow potential f and f', temperature terms.
    std::vector<double> f, fPrime;
    std::array<std::vector<double>, kMaxTerms> termRadial;
    SynthFeature description;
};

struct ModelAtTime {
    Vec3d rotationAxis;
    double rotationRadPerSecond;
    std::vector<FeatureAtTime> features;
};

double angleBetween(Vec3d a, Vec3d b) { return std::atan2(std::sqrt(dot(cross(a, b), cross(a, b))), dot(a, b)); }

SynthFeature::Kind kindOf(bool isPlume) { return isPlume ? SynthFeature::Kind::Plume : SynthFeature::Kind::Slab; }

void describePoint(Vec3d p, double& latDeg, double& lonDeg)
{
    const SphericalPoint s = cartesianToSpherical(p);
    latDeg = s.latDeg;
    lonDeg = s.lonDeg;
}

// Everything that depends on time but not on the grid, plus radial tables for `rKm`.
ModelAtTime modelAt(const SynthOptions& options, double timeMyr, const std::vector<double>& rKm)
{
    const Model model = buildModel(options.seed);
    ModelAtTime m;
    m.rotationAxis = model.rotationAxis;
    m.rotationRadPerSecond = model.rotationRadPerMyr / kSecondsPerMyr;
    const double turn = model.rotationRadPerMyr * timeMyr;
    const size_t nR = rKm.size();

    for (const Plume& p : model.plumes) {
        FeatureAtTime fa;
        fa.isPlume = true;
        fa.axis = rotate(p.axis0, model.rotationAxis, turn);
        fa.flowWidthRad = kPlumeFlowWidthKm / kFlowReferenceRadiusKm;
        const double head = integrateFrontKm(p.headRadius0Km, p.speedMps, p.stallLayer, +1.0, timeMyr);
        // G = exp(-(1 - cos gamma) / s^2) has -lap_S G = 2 / s^2 on the axis; scaling f by
        // s^2 / 2 * r^2 makes the axis speed exactly speedMps * flowShape.
        const double s2 = fa.flowWidthRad * fa.flowWidthRad;
        auto potential = [&](double r) { return p.speedMps * 0.5 * s2 * r * r * flowShape(r, head, p.stallLayer, +1.0); };
        // Terms: tail (column up to the head), head, hot pool at the base, one pancake per layer.
        fa.termCount = 5;
        fa.termWidthRad = {kPlumeTailSigmaKm / kFlowReferenceRadiusKm, kPlumeHeadSigmaKm / head,
                           kPlumeBaseSigmaKm / kCoreRadiusKm, kPancakeSigmaKm / layerRadiusKm(0),
                           kPancakeSigmaKm / layerRadiusKm(1)};
        // A rising plume meets the spin layer (index 1) before 660 km (index 0); a plume
        // stalled at a layer spreads there and never reaches the layers above it.
        std::array<double, 2> pancake{};
        for (int l = 0; l < 2; ++l)
            pancake[l] = (p.stallLayer == kNoLayer || l >= p.stallLayer) ? pancakeStrength(head, layerRadiusKm(l), +1.0) : 0.0;
        fa.f.resize(nR);
        fa.fPrime.resize(nR);
        for (auto& t : fa.termRadial)
            t.assign(nR, 0.0);
        for (size_t i = 0; i < nR; ++i) {
            const double r = rKm[i];
            constexpr double h = 0.01;  // km; central difference, error ~1e-8 relative
            fa.f[i] = potential(r);
            fa.fPrime[i] = (potential(r + h) - potential(r - h)) / (2.0 * h);
            const double aboveCmb = r - kCoreRadiusKm;
            const double tail = 0.6 + 0.4 * std::exp(-aboveCmb / 300.0);
            fa.termRadial[0][i] = p.amplitudeK * tail * smootherstep((head - r) / 150.0);
            const double dh = (r - head) / kPlumeHeadRadialSigmaKm;
            fa.termRadial[1][i] = p.amplitudeK * 1.1 * std::exp(-0.5 * dh * dh);
            fa.termRadial[2][i] = p.amplitudeK * 0.6 * std::exp(-aboveCmb / 130.0);
            for (int l = 0; l < 2; ++l) {
                const double dl = (r - (layerRadiusKm(l) - kPancakeOffsetKm)) / kPancakeRadialSigmaKm;
                fa.termRadial[3 + l][i] = p.amplitudeK * 0.7 * pancake[l] * std::exp(-0.5 * dl * dl);
            }
        }
        SynthFeature& d = fa.description;
        d.kind = kindOf(true);
        describePoint(fa.axis, d.latDeg, d.lonDeg);
        d.frontRadiusKm = head;
        d.stallDepthKm = p.stallLayer == kNoLayer ? 0.0 : kLayers[p.stallLayer].depthKm;
        d.speedMps = p.speedMps;
        d.temperatureK = p.amplitudeK;
        m.features.push_back(std::move(fa));
    }

    for (const Slab& s : model.slabs) {
        FeatureAtTime fa;
        fa.isPlume = false;
        const Vec3d a = rotate(s.start0, model.rotationAxis, turn);
        const Vec3d b = rotate(s.end0, model.rotationAxis, turn);
        fa.arcNormal = normalized(cross(a, b));
        fa.arcE1 = a;
        fa.arcE2 = cross(fa.arcNormal, a);
        fa.arcAngle = angleBetween(a, b);
        fa.flowWidthRad = kSlabFlowWidthKm / kFlowReferenceRadiusKm;
        const double tip = integrateFrontKm(s.tipRadius0Km, s.speedMps, s.stallLayer, -1.0, timeMyr);
        // G = exp(-x^2 / (2 w^2)) across the sheet has -lap_S G ~ 1 / w^2 on the sheet; the
        // minus sign makes the flow go down where the slab is.
        const double w2 = fa.flowWidthRad * fa.flowWidthRad;
        auto potential = [&](double r) { return -s.speedMps * w2 * r * r * flowShape(r, tip, s.stallLayer, -1.0); };
        // Terms: the sheet down to the tip, then one pancake per layer (above it).
        fa.termCount = 3;
        fa.termWidthRad = {kSlabSigmaKm / kFlowReferenceRadiusKm, kPancakeSigmaKm / layerRadiusKm(0),
                           kPancakeSigmaKm / layerRadiusKm(1), 0.0, 0.0};
        // A sinking slab meets 660 km first; stalled there, it never reaches the spin layer.
        std::array<double, 2> pancake{};
        for (int l = 0; l < 2; ++l)
            pancake[l] = (s.stallLayer == kNoLayer || l <= s.stallLayer) ? pancakeStrength(tip, layerRadiusKm(l), -1.0) : 0.0;
        fa.f.resize(nR);
        fa.fPrime.resize(nR);
        for (auto& t : fa.termRadial)
            t.assign(nR, 0.0);
        for (size_t i = 0; i < nR; ++i) {
            const double r = rKm[i];
            constexpr double h = 0.01;
            fa.f[i] = potential(r);
            fa.fPrime[i] = (potential(r + h) - potential(r - h)) / (2.0 * h);
            // Coldest near the surface; warms (thermal assimilation) with depth below the trench.
            const double depth = kSurfaceRadiusKm - r;
            const double assimilation = 0.55 + 0.45 * std::exp(-depth / 900.0);
            fa.termRadial[0][i] = s.amplitudeK * assimilation * smootherstep((r - tip) / 120.0);
            for (int l = 0; l < 2; ++l) {
                const double dl = (r - (layerRadiusKm(l) + kPancakeOffsetKm)) / kPancakeRadialSigmaKm;
                fa.termRadial[1 + l][i] = s.amplitudeK * 0.6 * pancake[l] * std::exp(-0.5 * dl * dl);
            }
        }
        SynthFeature& d = fa.description;
        d.kind = kindOf(false);
        describePoint(normalized(a + b), d.latDeg, d.lonDeg);
        describePoint(a, d.startLatDeg, d.startLonDeg);
        describePoint(b, d.endLatDeg, d.endLonDeg);
        d.frontRadiusKm = tip;
        d.stallDepthKm = s.stallLayer == kNoLayer ? 0.0 : kLayers[s.stallLayer].depthKm;
        d.speedMps = s.speedMps;
        d.temperatureK = s.amplitudeK;
        m.features.push_back(std::move(fa));
    }
    return m;
}

// Angular part of the flow potential of a feature at the unit vector n.
double flowPotentialAngular(const FeatureAtTime& fa, Vec3d n)
{
    if (fa.isPlume) {
        const double w = fa.flowWidthRad;
        return std::exp(-(1.0 - dot(n, fa.axis)) / (w * w));
    }
    const double x = dot(n, fa.arcNormal);
    const double psi = std::atan2(dot(n, fa.arcE2), dot(n, fa.arcE1));
    const double taper = std::min(0.15, fa.arcAngle / 3.0);
    const double along = smootherstep(psi / taper) * smootherstep((fa.arcAngle - psi) / taper);
    const double w = fa.flowWidthRad;
    return std::exp(-0.5 * x * x / (w * w)) * along;
}

// Per-column values of one feature: G, its surface Laplacian and gradient, temperature factors.
struct ColumnTerms {
    double lapG = 0;
    Vec3d gradG{};
    std::array<double, kMaxTerms> angular{};
    bool active = false;
};

// Surface Laplacian and gradient of G on the unit sphere by geodesic central differences in an
// orthonormal tangent basis (e1, e2): at the origin of Riemann normal coordinates the
// Laplace-Beltrami operator is the flat Laplacian, so the 5-point stencil is second order.
void surfaceDerivatives(const FeatureAtTime& fa, Vec3d n, Vec3d e1, Vec3d e2, ColumnTerms& out)
{
    constexpr double h = 2e-4;  // radians (~1 km); features are >= 0.03 rad wide
    const double c = std::cos(h), s = std::sin(h);
    const double g0 = flowPotentialAngular(fa, n);
    const double g1p = flowPotentialAngular(fa, c * n + s * e1), g1m = flowPotentialAngular(fa, c * n - s * e1);
    const double g2p = flowPotentialAngular(fa, c * n + s * e2), g2m = flowPotentialAngular(fa, c * n - s * e2);
    out.lapG = (g1p + g1m + g2p + g2m - 4.0 * g0) / (h * h);
    out.gradG = ((g1p - g1m) / (2.0 * h)) * e1 + ((g2p - g2m) / (2.0 * h)) * e2;
}

void columnTerms(const FeatureAtTime& fa, Vec3d n, Vec3d e1, Vec3d e2, ColumnTerms& out)
{
    // Far from a feature every factor is below ~1e-13 of its peak; skipping it there is
    // invisible in float32 and makes the per-cell loop touch only nearby features.
    constexpr double kNegligibleExponent = 30.0;
    double widest = fa.flowWidthRad;
    for (int k = 0; k < fa.termCount; ++k)
        widest = std::max(widest, fa.termWidthRad[k]);
    if (fa.isPlume) {
        const double chord2 = 2.0 * (1.0 - dot(n, fa.axis));
        out.active = chord2 < 2.0 * kNegligibleExponent * widest * widest;
        if (!out.active)
            return;
        for (int k = 0; k < fa.termCount; ++k)
            out.angular[k] = std::exp(-0.5 * chord2 / (fa.termWidthRad[k] * fa.termWidthRad[k]));
    } else {
        const double x = dot(n, fa.arcNormal);
        const double psi = std::atan2(dot(n, fa.arcE2), dot(n, fa.arcE1));
        // Beyond the arc's ends by more than a few widths nothing remains either.
        const double margin = std::sqrt(2.0 * kNegligibleExponent) * widest;
        out.active = x * x < 2.0 * kNegligibleExponent * widest * widest && psi > -margin &&
                     psi < fa.arcAngle + margin;
        if (!out.active)
            return;
        // Temperature: the sheet tapers sharply at the arc's ends; the pancakes (spread
        // material) extend beyond the ends as well, with a Gaussian fall-off.
        const double taper = std::min(0.15, fa.arcAngle / 3.0);
        const double along = smootherstep(psi / taper) * smootherstep((fa.arcAngle - psi) / taper);
        const double outside = psi < 0.0 ? -psi : (psi > fa.arcAngle ? psi - fa.arcAngle : 0.0);
        out.angular[0] = std::exp(-0.5 * x * x / (fa.termWidthRad[0] * fa.termWidthRad[0])) * along;
        for (int k = 1; k < fa.termCount; ++k) {
            const double w2 = fa.termWidthRad[k] * fa.termWidthRad[k];
            out.angular[k] = std::exp(-0.5 * (x * x + outside * outside) / w2);
        }
    }
    surfaceDerivatives(fa, n, e1, e2, out);
}

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

// Area weights of lat rows: sin(upper edge) - sin(lower edge) of the row's dual cell, with the
// outer edges half a spacing out and clamped to the poles (as SphericalGrid::latEdgesDeg).
std::vector<double> latRowWeights(const std::vector<double>& latDeg)
{
    const size_t n = latDeg.size();
    std::vector<double> edges(n + 1);
    for (size_t i = 1; i < n; ++i)
        edges[i] = 0.5 * (latDeg[i - 1] + latDeg[i]);
    edges[0] = n > 1 ? latDeg[0] - 0.5 * (latDeg[1] - latDeg[0]) : -90.0;
    edges[n] = n > 1 ? latDeg[n - 1] + 0.5 * (latDeg[n - 1] - latDeg[n - 2]) : 90.0;
    std::vector<double> w(n);
    for (size_t i = 0; i < n; ++i)
        w[i] = std::sin(degToRad(std::clamp(edges[i + 1], -90.0, 90.0))) -
               std::sin(degToRad(std::clamp(edges[i], -90.0, 90.0)));
    return w;
}

// Lon weights: the width of each column's dual cell on the periodic circle.
std::vector<double> lonColumnWeights(const std::vector<double>& lonDeg)
{
    const size_t n = lonDeg.size();
    std::vector<double> w(n, 1.0);
    if (n < 2)
        return w;
    for (size_t i = 0; i < n; ++i) {
        const double prev = i == 0 ? lonDeg[n - 1] - 360.0 : lonDeg[i - 1];
        const double next = i + 1 == n ? lonDeg[0] + 360.0 : lonDeg[i + 1];
        w[i] = 0.5 * (next - prev);
    }
    return w;
}

}  // namespace

SphericalGrid syntheticGrid(int nLat, int nR, int nLon)
{
    if (nLat < 2 || nR < 2 || nLon < 3)
        fail("synthetic grid {}x{}x{}: expected at least 2 lat rows, 2 radii and 3 lon columns", nLat, nR, nLon);
    SphericalGrid grid;
    grid.latDeg.resize(nLat);
    grid.rKm.resize(nR);
    grid.lonDeg.resize(nLon);
    for (int i = 0; i < nLat; ++i)
        grid.latDeg[i] = -90.0 + (i + 0.5) * 180.0 / nLat;
    for (int i = 0; i < nR; ++i)
        grid.rKm[i] = i + 1 == nR ? kSurfaceRadiusKm : kCoreRadiusKm + i * kMantleThicknessKm / (nR - 1);
    for (int i = 0; i < nLon; ++i)
        grid.lonDeg[i] = i * 360.0 / nLon;
    return grid;
}

std::array<int, 3> parseSynthGridSize(const std::string& text, const std::string& option)
{
    const std::vector<std::string> parts = split(text, 'x');
    if (parts.size() != 3)
        fail("{} '{}': expected LATxRxLON, three sizes such as 64x81x128", option, text);
    std::array<int, 3> sizes{};
    for (size_t i = 0; i < 3; ++i) {
        const std::string& p = parts[i];
        const auto [end, ec] = std::from_chars(p.data(), p.data() + p.size(), sizes[i]);
        if (p.empty() || ec != std::errc() || end != p.data() + p.size())
            fail("{} '{}': '{}' is not a whole number; expected LATxRxLON such as 64x81x128", option, text, p);
    }
    if (sizes[0] < 2 || sizes[1] < 2 || sizes[2] < 3)
        fail("{} '{}': expected at least 2 lat rows, 2 radii and 3 lon columns", option, text);
    // Beyond this one variable no longer fits a 64-bit-offset file (4 GiB per variable).
    const double cells = static_cast<double>(sizes[0]) * sizes[1] * sizes[2];
    if (cells > 1.0e9)
        fail("{} '{}': {:.3g} cells, expected at most 1e9", option, text, cells);
    return sizes;
}

std::vector<SynthFeature> syntheticFeatures(const SynthOptions& options, double timeMyr)
{
    const ModelAtTime m = modelAt(options, timeMyr, {});
    std::vector<SynthFeature> out;
    for (const FeatureAtTime& fa : m.features)
        out.push_back(fa.description);
    return out;
}

std::array<double, 3> syntheticRotationRadPerSecond(const SynthOptions& options)
{
    const Model model = buildModel(options.seed);
    const double w = model.rotationRadPerMyr / kSecondsPerMyr;
    return {w * model.rotationAxis.x, w * model.rotationAxis.y, w * model.rotationAxis.z};
}

Snapshot synthesizeSnapshot(const SynthOptions& options, double timeMyr)
{
    return synthesizeSnapshot(options, timeMyr, syntheticGrid(options.nLat, options.nR, options.nLon));
}

Snapshot synthesizeSnapshot(const SynthOptions& options, double timeMyr, const SphericalGrid& grid)
{
    if (!std::isfinite(timeMyr))
        fail("synthetic snapshot: time {} Myr is not finite", timeMyr);
    const size_t nLat = grid.nLat(), nR = grid.nR(), nLon = grid.nLon();
    const ModelAtTime model = modelAt(options, timeMyr, grid.rKm);
    const size_t nFeatures = model.features.size();

    Snapshot snap;
    snap.grid = grid;
    const auto& names = contestVariableNames();
    const std::array<const char*, 8> units = {"K", "m/s", "m/s", "m/s", "W/m/K", "1/K", "K", "kg/m^3"};
    snap.fields.resize(names.size());
    for (size_t v = 0; v < names.size(); ++v) {
        snap.fields[v].name = names[v];
        snap.fields[v].units = units[v];
        snap.fields[v].values.assign(grid.cellCount(), 0.0f);
    }
    float* temperature = snap.fields[0].values.data();
    float* vx = snap.fields[1].values.data();
    float* vy = snap.fields[2].values.data();
    float* vz = snap.fields[3].values.data();
    float* conduct = snap.fields[4].values.data();
    float* expans = snap.fields[5].values.data();
    float* anomaly = snap.fields[6].values.data();
    float* spin = snap.fields[7].values.data();

    std::vector<double> referenceK(nR), depthKm(nR), boundaryTaper(nR);
    for (size_t i = 0; i < nR; ++i) {
        referenceK[i] = referenceTemperatureK(grid.rKm[i]);
        depthKm[i] = kSurfaceRadiusKm - grid.rKm[i];
        // Anomalies vanish at the isothermal surface and CMB.
        boundaryTaper[i] = (1.0 - std::exp(-std::max(0.0, depthKm[i]) / 60.0)) *
                           (1.0 - std::exp(-std::max(0.0, grid.rKm[i] - kCoreRadiusKm) / 40.0));
    }
    const std::vector<double> latWeights = latRowWeights(grid.latDeg);
    const std::vector<double> lonWeights = lonColumnWeights(grid.lonDeg);
    // Per (lat row, radius) weighted sums of temperature, for the shell means; summed in a
    // fixed order afterwards so the result does not depend on thread scheduling.
    std::vector<double> rowSums(nLat * nR, 0.0);

    tbb::parallel_for(tbb::blocked_range<size_t>(0, nLat), [&](const tbb::blocked_range<size_t>& rows) {
        std::vector<ColumnTerms> terms(nFeatures);
        std::vector<int> active;
        active.reserve(nFeatures);
        for (size_t iLat = rows.begin(); iLat != rows.end(); ++iLat) {
            const double lat = degToRad(grid.latDeg[iLat]);
            for (size_t iLon = 0; iLon < nLon; ++iLon) {
                const double lon = degToRad(grid.lonDeg[iLon]);
                const Vec3d n{std::cos(lat) * std::cos(lon), std::cos(lat) * std::sin(lon), std::sin(lat)};
                // East and north unit vectors: an orthonormal tangent basis even at the poles.
                const Vec3d east{-std::sin(lon), std::cos(lon), 0.0};
                const Vec3d north = cross(n, east);
                active.clear();
                for (size_t f = 0; f < nFeatures; ++f) {
                    columnTerms(model.features[f], n, east, north, terms[f]);
                    if (terms[f].active)
                        active.push_back(static_cast<int>(f));
                }
                // Rigid rotation omega x (r n): purely horizontal, in m/s per km of radius.
                const Vec3d spinPerKm = (model.rotationRadPerSecond * 1000.0) * cross(model.rotationAxis, n);
                for (size_t iR = 0; iR < nR; ++iR) {
                    const double r = grid.rKm[iR];
                    double dT = 0.0, ur = 0.0;
                    Vec3d uh = r * spinPerKm;
                    for (int f : active) {
                        const FeatureAtTime& fa = model.features[f];
                        const ColumnTerms& ct = terms[f];
                        for (int k = 0; k < fa.termCount; ++k)
                            dT += fa.termRadial[k][iR] * ct.angular[k];
                        if (r > 0.0) {
                            ur -= fa.f[iR] * ct.lapG / (r * r);
                            uh = uh + (fa.fPrime[iR] / r) * ct.gradG;
                        }
                    }
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
            }
            // Shell sums of the stored (float) temperature, so the anomaly is zero-mean on
            // exactly the values a reader sees.
            for (size_t iR = 0; iR < nR; ++iR) {
                double sum = 0.0;
                const float* row = temperature + grid.index(iLat, iR, 0);
                for (size_t iLon = 0; iLon < nLon; ++iLon)
                    sum += lonWeights[iLon] * row[iLon];
                rowSums[iLat * nR + iR] = latWeights[iLat] * sum;
            }
        }
    });

    // Temperature anomaly: temperature minus its area-weighted mean over each shell.
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
    return snap;
}

void writeSyntheticSeries(const std::filesystem::path& outDir, const SynthOptions& options)
{
    if (options.steps < 1)
        fail("synthetic series: {} steps, expected at least 1", options.steps);
    if (!(options.dtMyr > 0.0) || !std::isfinite(options.dtMyr))
        fail("synthetic series: time step {} Myr, expected a positive number", options.dtMyr);
    std::error_code ec;
    std::filesystem::create_directories(outDir, ec);
    if (ec)
        fail("{}: cannot create output directory: {}", outDir.string(), ec.message());
    Progress progress("synth", options.steps, "steps");
    for (int step = 0; step < options.steps; ++step) {
        const Snapshot snap = synthesizeSnapshot(options, step * options.dtMyr);
        writeContestFile(outDir / fmt::format("spherical{:03d}.nc", step + 1), snap, options.flavour);
        progress.advance();
    }
    progress.finish();
}

}  // namespace raypc
