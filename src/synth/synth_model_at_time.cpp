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
#include "synth/synth.h"

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
constexpr std::array<Layer, 2> kLayers = {{{660.0, 90.0, 0.85}, {1600.0, 130.0, 0.8}}};
constexpr int kNoLayer = -1;

double layerRadiusKm(int layer) { return kSurfaceRadiusKm - kLayers[layer].depthKm; }

// ---- the radial reference state ----

// Feature anomalies are tapered to zero over these distances from the surface and the CMB.
constexpr double kSurfaceTaperKm = 60.0, kCmbTaperKm = 40.0;

// The largest value of exp(-a / decayKm) * (1 - exp(-a / kCmbTaperKm)) over heights a above the
// CMB: the peak of a layer on the CMB (pile, pool) after the taper, at a = 40 ln((40 + L) / 40).
double cmbLayerPeak(double decayKm)
{
    const double q = kCmbTaperKm / (kCmbTaperKm + decayKm);
    return std::pow(q, kCmbTaperKm / decayKm) * (1.0 - q);
}

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
    double amplitudeK;      // excess temperature scale (conduit ~0.65-1x, head 1.2x)
    double headRadius0Km;   // radius of the head centre at t = 0
    int stallLayer;         // index into kLayers, or kNoLayer when it passes through
    double size;            // multiplies the lateral widths (0.8 ... 1.3)
};

// A slab hangs from a trench that is an arc of a small circle: the points at angular
// "latitude" beta0 about the pole `pole0` (beta0 != 0 curves the trench), from azimuth 0
// (direction `start0`) to `arcAngle`. With depth the sheet moves towards larger |beta| by
// dipSign * dipOffsetRad * (1 - exp(-depth / dipScaleKm)): shallow dip at the trench
// (atan(dipScale / (R * dipOffset))), steepening to near-vertical below a few hundred km.
struct Slab {
    Vec3d pole0, start0;
    double beta0, arcAngle;
    double dipSign, dipOffsetRad, dipScaleKm;
    double thicknessKm;     // Gaussian sigma of the sheet at the trench (thickens below 660)
    double speedMps;        // peak downwelling in the sheet
    double amplitudeK;      // (negative) temperature deficit
    double tipRadius0Km;    // radius of the slab tip at t = 0
    int stallLayer;
};

// One zonal spherical harmonic P_l(n . axis) (an exact degree-l harmonic about a random axis).
struct Harmonic {
    Vec3d axis0;
    int degree;
    double coeff;
};

struct Model {
    Vec3d rotationAxis;
    double rotationRadPerMyr;
    std::vector<Plume> plumes;
    std::vector<Slab> slabs;
    // Background: poloidal flow potential (its -lap_S also patterns the mid-mantle temperature),
    // toroidal flow stream function, top and bottom boundary-layer temperature patterns.
    std::vector<Harmonic> poloidal, toroidal, top, bottom;
    // Maxima over the sphere of |sum c l(l+1) P_l|, |toroidal velocity pattern|, |top|, |bottom|.
    double poloidalNorm = 1, toroidalNorm = 1, topNorm = 1, bottomNorm = 1;
};

// Lateral sizes (km, measured at the reference radius of each term).
constexpr double kPlumeFlowWidthKm = 480.0;   // angular width of the plume's flow potential
constexpr double kPlumeTailSigmaKm = 220.0;   // conduit, at kPlumeTailReferenceKm
constexpr double kPlumeTailReferenceKm = 4400.0;
constexpr double kPlumeHeadSigmaKm = 430.0;
constexpr double kPlumeHeadRadialSigmaKm = 220.0;
constexpr double kPlumeBaseSigmaKm = 700.0;   // the hot pile feeding a plume at the CMB
constexpr double kPancakeSigmaKm = 900.0;     // material spreading along a layer
constexpr double kPancakeRadialSigmaKm = 70.0;
constexpr double kPancakeOffsetKm = 70.0;     // below the layer for plumes, above for slabs
constexpr double kSlabFlowWidthKm = 300.0;
constexpr double kSlabPoolSigmaKm = 800.0;    // cold pool where a slab lies on the CMB
constexpr double kPlumePileDecayKm = 200.0;   // thickness scales of the pile and the pool
constexpr double kSlabPoolDecayKm = 160.0;
constexpr double kFlowReferenceRadiusKm = 5000.0;

// Background magnitudes.
constexpr double kBackgroundUpwellingCmPerYr = 0.7;   // peak |u_r| of the poloidal background
constexpr double kBackgroundToroidalCmPerYr = 0.8;    // peak toroidal speed at the surface
constexpr double kBackgroundMidK = 30.0;              // mid-mantle lateral variation
constexpr double kBackgroundTopK = 70.0;              // top boundary layer
constexpr double kBackgroundBottomK = 90.0;           // bottom boundary layer

// Where the front of a feature (head, tip) is relative to a layer: 1 while it lingers near the
// layer, decaying to 0 far below / above it; after passing, half of the spread material remains.
double pancakeStrength(double frontKm, double layerKm, double approachSign)
{
    const double ahead = approachSign * (layerKm - frontKm);  // > 0: not yet at the layer
    const double near = std::exp(-(ahead / 200.0) * (ahead / 200.0));
    return ahead >= 0.0 ? near : 0.5 + 0.5 * near;
}

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

// Radial profile (dimensionless, 0 at both boundaries) of a feature's flow. `front` is the head
// or tip radius; flow fades over `kAheadKm` beyond it; `direction` is +1 for rising plumes.
// `released`: the feature is breaking through its stall layer (an avalanche, SynthOptions): its flow
// crosses the layer, without the notch the layers it passes get.
double flowShape(double rKm, double frontKm, int stallLayer, double direction, bool released = false)
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

// Radial profile of the background poloidal flow: sin(pi x) with notches at both layers.
double backgroundShape(double rKm)
{
    const double x = (rKm - kCoreRadiusKm) / kMantleThicknessKm;
    return std::sin(kPi * x) * layerNotches(rKm, kNoLayer);
}

// Radial profile of the background toroidal flow: plate-like, strongest at the surface.
double toroidalShape(double rKm)
{
    const double depth = kSurfaceRadiusKm - rKm;
    return (rKm / kSurfaceRadiusKm) * std::exp(-depth / 700.0);
}

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

// Background patterns at the unit vector n for harmonics with the given (rotated) axes.
struct BackgroundColumn {
    double upwelling = 0;   // sum c l(l+1) P_l / poloidalNorm = -lap_S B / norm, in [-1, 1]
    Vec3d gradB{};          // grad_S B / poloidalNorm
    Vec3d toroidal{};       // n x grad_S C / toroidalNorm
    double top = 0, bottom = 0;
};

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

// Background poloidal potential f_bg(r) (so that u_r = f_bg / r^2 * upwelling, in m/s).
double backgroundPotential(double rKm)
{
    const double v = kBackgroundUpwellingCmPerYr * 0.01 / (kSecondsPerMyr / 1e6);
    return v * rKm * rKm * backgroundShape(rKm);
}

// Background radial velocity (m/s) at unit vector n (t = 0 frame) and radius r.
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

// An avalanche (SynthOptions::avalancheMyr): the feature's flow crosses its stall layer, twice as
// fast, from avalancheMyr for avalancheDurationMyr.
constexpr double kAvalancheSpeedFactor = 2.0;
bool avalancheUnderWay(const SynthOptions& options, double timeMyr)
{
    return std::isfinite(options.avalancheMyr) && timeMyr >= options.avalancheMyr &&
           timeMyr < options.avalancheMyr + options.avalancheDurationMyr;
}

// Moves a head or tip: dr/dt = direction * speed * shape(r) + background u_r at the front's
// own position (`where(r)`, t = 0 frame, in which the features and background are at rest
// apart from the common rotation). `released(t)`: whether the feature breaks through its stall
// layer at time t (an avalanche). RK4 in steps of at most 0.05 Myr.
template <class Where, class Released>
double integrateFrontKm(const Model& model, const std::vector<Vec3d>& axes0, double front0Km, double speedMps,
                        int stallLayer, double direction, double timeMyr, Where where, Released released)
{
    const double kmPerMyrPerMps = kSecondsPerMyr / 1000.0;
    auto rate = [&](double r, double t) {
        const bool free = released(t);
        const double kmPerMyr = (free ? kAvalancheSpeedFactor : 1.0) * (speedMps * kSecondsPerMyr / 1000.0);
        return direction * kmPerMyr * flowShape(r, r, stallLayer, direction, free) +
               kmPerMyrPerMps * backgroundRadialVelocity(model, axes0, where(r), r);
    };
    const int steps = std::max(1, static_cast<int>(std::ceil(std::abs(timeMyr) / 0.05)));
    const double h = timeMyr / steps;
    double r = front0Km;
    for (int i = 0; i < steps; ++i) {
        const double t = i * h;
        const double k1 = rate(r, t), k2 = rate(r + 0.5 * h * k1, t + 0.5 * h), k3 = rate(r + 0.5 * h * k2, t + 0.5 * h),
                     k4 = rate(r + h * k3, t + h);
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
    for (int attempt = 0; attempt < 400; ++attempt) {
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

// Slab geometry: the sheet's angular latitude offset (radians, about the slab's pole) at depth.
double slabShift(const Slab& s, double rKm)
{
    const double depth = std::max(0.0, kSurfaceRadiusKm - rKm);
    return s.dipSign * s.dipOffsetRad * (1.0 - std::exp(-depth / s.dipScaleKm));
}
// d(shift)/dr (per km); the shift grows with depth, i.e. as r decreases.
double slabShiftPrime(const Slab& s, double rKm)
{
    const double depth = kSurfaceRadiusKm - rKm;
    if (depth < 0.0)
        return 0.0;
    return -s.dipSign * s.dipOffsetRad / s.dipScaleKm * std::exp(-depth / s.dipScaleKm);
}

// The point of a slab's sheet centre at radius r and trench azimuth psi (t = 0 frame unless
// pole/start are rotated).
Vec3d slabPoint(Vec3d pole, Vec3d start, double beta, double psi)
{
    const Vec3d e2 = cross(pole, start);
    return std::sin(beta) * pole + std::cos(beta) * (std::cos(psi) * start + std::sin(psi) * e2);
}

// Random harmonics of degrees [lo, hi], `perDegree` axes each, coefficient ~ degree^-slope.
void addHarmonics(Rng& rng, std::vector<Harmonic>& out, int lo, int hi, int perDegree, double slope)
{
    for (int l = lo; l <= hi; ++l)
        for (int k = 0; k < perDegree; ++k) {
            const double sign = rng.uniform() < 0.5 ? -1.0 : 1.0;
            out.push_back({rng.onSphere(), l, sign * rng.uniform(0.5, 1.0) * std::pow(static_cast<double>(l), -slope)});
        }
}

// Maximum over a fixed quasi-uniform point set (Fibonacci sphere) of |fn(n)|.
template <class Fn>
double maxOverSphere(Fn fn)
{
    constexpr int kPoints = 3000;
    double best = 1e-30;
    for (int i = 0; i < kPoints; ++i) {
        const double z = 1.0 - (2.0 * i + 1.0) / kPoints;
        const double phi = i * kPi * (3.0 - std::sqrt(5.0));
        const double s = std::sqrt(std::max(0.0, 1.0 - z * z));
        best = std::max(best, std::abs(fn(Vec3d{s * std::cos(phi), s * std::sin(phi), z})));
    }
    return best;
}

// The cast of features. Their roles are fixed so every seed shows every phenomenon the contest
// tasks look for; the seed decides positions, orientations, sizes, strengths and starting depths.
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
    struct Role {
        double frontDepthKm;
        int stallLayer;
    };
    // Plume heads: in the upper mantle (two, one spreading under the lithosphere), rising
    // through the lower mantle (three), stalling below 1600 km (two) and below 660 km (two),
    // and a young plume just above the CMB.
    const std::array<Role, 10> plumeRoles = {{{450.0, kNoLayer},
                                              {1000.0, kNoLayer},
                                              {1850.0, kNoLayer},
                                              {1780.0, 1},
                                              {820.0, 0},
                                              {2450.0, kNoLayer},
                                              {260.0, kNoLayer},
                                              {1300.0, kNoLayer},
                                              {2000.0, 1},
                                              {1050.0, 0}}};
    for (const Role& role : plumeRoles) {
        Plume p;
        p.axis0 = pickSeparated(rng, taken, degToRad(32.0));
        taken.push_back(p.axis0);
        p.speedMps = rng.uniform(3.0, 4.5) * cmPerYr;
        p.amplitudeK = rng.uniform(250.0, 380.0);
        p.headRadius0Km = kSurfaceRadiusKm - role.frontDepthKm + rng.uniform(-60.0, 60.0);
        p.stallLayer = role.stallLayer;
        p.size = rng.uniform(0.9, 1.3);
        model.plumes.push_back(p);
    }
    // Slab tips: three lying on 660 and one heading for it, one between the layers, one
    // crossing the spin layer, two stalling on it, one deep in the lower mantle and one on the CMB.
    const std::array<Role, 10> slabRoles = {{{560.0, 0},
                                             {420.0, 0},
                                             {1150.0, kNoLayer},
                                             {1500.0, kNoLayer},
                                             {2150.0, kNoLayer},
                                             {620.0, 0},
                                             {1380.0, 1},
                                             {1490.0, 1},
                                             {2700.0, kNoLayer},
                                             {300.0, kNoLayer}}};
    for (const Role& role : slabRoles) {
        Slab s;
        // The trench's midpoint, and a small circle through it: pole at angular distance
        // 90 - |beta0| from it; the arc extends half its length on both sides of the midpoint.
        const Vec3d mid = pickSeparated(rng, taken, degToRad(30.0));
        taken.push_back(mid);
        const Vec3d tangent = normalize(cross(mid, rng.onSphere()));
        const double beta0 = degToRad(rng.uniform(8.0, 40.0)) * (rng.uniform() < 0.5 ? -1.0 : 1.0);
        // Pole: rotate mid towards `tangent`'s normal by 90 - beta0 ... built so that
        // sin(beta0) = mid . pole.
        const Vec3d side = normalize(cross(tangent, mid));  // perpendicular to mid and tangent
        s.pole0 = std::sin(beta0) * mid + std::cos(beta0) * side;
        s.beta0 = beta0;
        const double lengthRad = degToRad(rng.uniform(25.0, 50.0));
        s.arcAngle = lengthRad / std::cos(beta0);
        // Start direction: the component of mid perpendicular to the pole, rotated back by half the arc.
        const Vec3d midFlat = normalize(mid - dot(mid, s.pole0) * s.pole0);
        s.start0 = rotate(midFlat, s.pole0, -0.5 * s.arcAngle);
        // Dip towards the concave side (the small circle's pole), like island arcs.
        s.dipSign = beta0 > 0 ? 1.0 : -1.0;
        s.dipScaleKm = rng.uniform(180.0, 320.0);
        const double dipAtTrench = degToRad(rng.uniform(25.0, 45.0));
        s.dipOffsetRad = s.dipScaleKm / std::tan(dipAtTrench) / kSurfaceRadiusKm;
        s.thicknessKm = rng.uniform(90.0, 130.0);
        s.speedMps = rng.uniform(3.5, 5.0) * cmPerYr;
        s.amplitudeK = -rng.uniform(320.0, 480.0);
        s.tipRadius0Km = kSurfaceRadiusKm - role.frontDepthKm + rng.uniform(-50.0, 50.0);
        s.stallLayer = role.stallLayer;
        model.slabs.push_back(s);
    }
    // Background: long-wavelength patterns (degrees 2-8).
    addHarmonics(rng, model.poloidal, 2, 5, 2, 1.5);
    addHarmonics(rng, model.toroidal, 2, 4, 2, 1.0);
    addHarmonics(rng, model.top, 3, 8, 2, 0.7);
    addHarmonics(rng, model.bottom, 2, 4, 2, 0.8);
    const std::vector<Vec3d> axes = harmonicAxes(model, 0.0);
    model.poloidalNorm = maxOverSphere([&](Vec3d n) {
        Model m = model;
        m.poloidalNorm = m.toroidalNorm = m.topNorm = m.bottomNorm = 1.0;
        return backgroundColumn(m, axes, n).upwelling;
    });
    Model unit = model;
    unit.poloidalNorm = unit.toroidalNorm = unit.topNorm = unit.bottomNorm = 1.0;
    model.toroidalNorm = maxOverSphere([&](Vec3d n) {
        const Vec3d t = backgroundColumn(unit, axes, n).toroidal;
        return std::sqrt(dot(t, t));
    });
    model.topNorm = maxOverSphere([&](Vec3d n) { return backgroundColumn(unit, axes, n).top; });
    model.bottomNorm = maxOverSphere([&](Vec3d n) { return backgroundColumn(unit, axes, n).bottom; });
    return model;
}

// ---- the model at one time, ready to evaluate on a grid ----

// Terms of one feature: the flow potential's angular part and the temperature's angular
// factors, evaluated per column; the radial tables per radius.
constexpr int kMaxTerms = 5;

struct FeatureAtTime {
    bool isPlume = true;
    // Plume: axis. Slab: the trench's small-circle pole, start direction, its normal partner.
    Vec3d axis{}, arcE1{}, arcE2{}, pole{};
    double beta0 = 0, arcAngle = 0;
    double flowWidthRad = 0;  // angular width of G
    int termCount = 0;
    // Angular widths (radians) of the separable temperature terms.
    std::array<double, kMaxTerms> termWidthRad{};
    // Radial tables (per grid radius): flow potential f and f', temperature terms.
    std::vector<double> f, fPrime;
    std::array<std::vector<double>, kMaxTerms> termRadial;
    // The ground truth (syntheticTruth): which part each term is, and per radius the anomaly it
    // would have at full development (termRadial without its radial shape and growth).
    std::array<SynthPart, kMaxTerms> termPart{};
    std::array<std::vector<double>, kMaxTerms> termPeakK;
    // Slabs: sheet shift and its r-derivative, sheet temperature and its angular width per radius;
    // the shifts at the centres of the separable terms (pancakes, pool); the sheet's anomaly at
    // full development (sheetK without the cut-off at the tip).
    std::vector<double> shift, shiftPrime, sheetK, sheetWidthRad, sheetPeakK;
    std::array<double, kMaxTerms> termShift{};
    double shiftLo = 0, shiftHi = 0, sheetWidthMax = 0;
    SynthFeature description;
};

struct ModelAtTime {
    Vec3d rotationAxis;
    double rotationRadPerSecond;
    Model model;
    std::vector<Vec3d> harmonicAxes;  // rotated to this time
    std::vector<FeatureAtTime> features;
    // Background radial tables: poloidal f, f', toroidal speed (m/s), temperature modes (K).
    std::vector<double> bgF, bgFPrime, bgToroidal, bgMidK, bgTopK, bgBottomK;
};

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
    m.model = model;
    m.rotationAxis = model.rotationAxis;
    m.rotationRadPerSecond = model.rotationRadPerMyr / kSecondsPerMyr;
    const double turn = model.rotationRadPerMyr * timeMyr;
    m.harmonicAxes = harmonicAxes(model, turn);
    const std::vector<Vec3d> axes0 = harmonicAxes(model, 0.0);
    const size_t nR = rKm.size();

    // Background radial tables.
    m.bgF.resize(nR);
    m.bgFPrime.resize(nR);
    m.bgToroidal.resize(nR);
    m.bgMidK.resize(nR);
    m.bgTopK.resize(nR);
    m.bgBottomK.resize(nR);
    const double toroidalMps = kBackgroundToroidalCmPerYr * 0.01 / (kSecondsPerMyr / 1e6);
    for (size_t i = 0; i < nR; ++i) {
        const double r = rKm[i];
        constexpr double h = 0.01;
        m.bgF[i] = backgroundPotential(r);
        m.bgFPrime[i] = (backgroundPotential(r + h) - backgroundPotential(r - h)) / (2.0 * h);
        m.bgToroidal[i] = toroidalMps * toroidalShape(r);
        const double depth = kSurfaceRadiusKm - r, above = r - kCoreRadiusKm;
        // The mid-mantle pattern follows the background upwelling (hot where it rises).
        m.bgMidK[i] = kBackgroundMidK * backgroundShape(r);
        m.bgTopK[i] = kBackgroundTopK * std::exp(-depth / 180.0);
        m.bgBottomK[i] = kBackgroundBottomK * std::exp(-above / 220.0);
    }

    for (const Plume& p : model.plumes) {
        FeatureAtTime fa;
        fa.isPlume = true;
        fa.axis = rotate(p.axis0, model.rotationAxis, turn);
        fa.flowWidthRad = p.size * kPlumeFlowWidthKm / kFlowReferenceRadiusKm;
        const double head = integrateFrontKm(model, axes0, p.headRadius0Km, p.speedMps, p.stallLayer, +1.0, timeMyr,
                                             [&](double) { return p.axis0; }, [](double) { return false; });
        // G = exp(-(1 - cos gamma) / s^2) has -lap_S G = 2 / s^2 on the axis; scaling f by
        // s^2 / 2 * r^2 makes the axis speed exactly speedMps * flowShape.
        const double s2 = fa.flowWidthRad * fa.flowWidthRad;
        auto potential = [&](double r) { return p.speedMps * 0.5 * s2 * r * r * flowShape(r, head, p.stallLayer, +1.0); };
        // Terms: conduit (up to the head), head, hot pile at the base, one pancake per layer.
        fa.termCount = 5;
        fa.termWidthRad = {p.size * kPlumeTailSigmaKm / kPlumeTailReferenceKm, p.size * kPlumeHeadSigmaKm / head,
                           p.size * kPlumeBaseSigmaKm / kCoreRadiusKm, kPancakeSigmaKm / layerRadiusKm(0),
                           kPancakeSigmaKm / layerRadiusKm(1)};
        // A rising plume meets the spin layer (index 1) before 660 km (index 0); a plume
        // stalled at a layer spreads there and never reaches the layers above it.
        std::array<double, 2> pancake{};
        for (int l = 0; l < 2; ++l)
            pancake[l] = (p.stallLayer == kNoLayer || l >= p.stallLayer) ? pancakeStrength(head, layerRadiusKm(l), +1.0) : 0.0;
        // A head near the surface flattens under the lithosphere.
        const double headRadialSigma = p.size * kPlumeHeadRadialSigmaKm * (1.0 - 0.5 * smootherstep((head - 5700.0) / 400.0));
        fa.f.resize(nR);
        fa.fPrime.resize(nR);
        for (auto& t : fa.termRadial)
            t.assign(nR, 0.0);
        fa.termPart = {SynthPart::PlumeConduit, SynthPart::PlumeHead, SynthPart::PlumePile, SynthPart::PlumePancake660,
                       SynthPart::PlumePancake1600};
        for (auto& t : fa.termPeakK)
            t.assign(nR, 0.0);
        for (size_t i = 0; i < nR; ++i) {
            const double r = rKm[i];
            constexpr double h = 0.01;  // km; central difference, error ~1e-8 relative
            fa.f[i] = potential(r);
            fa.fPrime[i] = (potential(r + h) - potential(r - h)) / (2.0 * h);
            const double aboveCmb = r - kCoreRadiusKm;
            const double tail = 0.65 + 0.35 * std::exp(-aboveCmb / 300.0);
            fa.termRadial[0][i] = p.amplitudeK * tail * smootherstep((head - r) / 150.0);
            const double dh = (r - head) / headRadialSigma;
            fa.termRadial[1][i] = p.amplitudeK * 1.2 * std::exp(-0.5 * dh * dh);
            fa.termRadial[2][i] = p.amplitudeK * 0.45 * std::exp(-aboveCmb / kPlumePileDecayKm);
            for (int l = 0; l < 2; ++l) {
                const double dl = (r - (layerRadiusKm(l) - kPancakeOffsetKm)) / kPancakeRadialSigmaKm;
                fa.termRadial[3 + l][i] = p.amplitudeK * 0.7 * pancake[l] * std::exp(-0.5 * dl * dl);
            }
            fa.termPeakK[0][i] = p.amplitudeK * tail;
            fa.termPeakK[1][i] = p.amplitudeK * 1.2;
            fa.termPeakK[2][i] = p.amplitudeK * 0.45 * cmbLayerPeak(kPlumePileDecayKm);
            fa.termPeakK[3][i] = fa.termPeakK[4][i] = p.amplitudeK * 0.7;
        }
        SynthFeature& d = fa.description;
        d.kind = kindOf(true);
        describePoint(fa.axis, d.latDeg, d.lonDeg);
        d.frontRadiusKm = head;
        d.stallDepthKm = p.stallLayer == kNoLayer ? 0.0 : kLayers[p.stallLayer].depthKm;
        d.speedMps = p.speedMps;
        d.temperatureK = p.amplitudeK;
        d.conduitSigmaKm = fa.termWidthRad[0] * kPlumeTailReferenceKm;
        m.features.push_back(std::move(fa));
    }

    const Slab* avalanching = nullptr;  // the first slab stalled at 660 km breaks through it (SynthOptions)
    if (std::isfinite(options.avalancheMyr))
        for (const Slab& s : model.slabs)
            if (s.stallLayer == 0) {
                avalanching = &s;
                break;
            }
    for (const Slab& s : model.slabs) {
        auto released = [&](double t) { return &s == avalanching && avalancheUnderWay(options, t); };
        const bool free = released(timeMyr);
        FeatureAtTime fa;
        fa.isPlume = false;
        fa.pole = rotate(s.pole0, model.rotationAxis, turn);
        fa.arcE1 = rotate(s.start0, model.rotationAxis, turn);
        fa.arcE2 = cross(fa.pole, fa.arcE1);
        fa.beta0 = s.beta0;
        fa.arcAngle = s.arcAngle;
        fa.flowWidthRad = kSlabFlowWidthKm / kFlowReferenceRadiusKm;
        const double midPsi = 0.5 * s.arcAngle;
        const double tip = integrateFrontKm(model, axes0, s.tipRadius0Km, s.speedMps, s.stallLayer, -1.0, timeMyr,
                                            [&](double r) { return slabPoint(s.pole0, s.start0, s.beta0 + slabShift(s, r), midPsi); },
                                            released);
        // On the sheet -lap_S G = A / w^2 (see columnTerms); the minus sign makes the flow go
        // down where the slab is.
        const double w2 = fa.flowWidthRad * fa.flowWidthRad;
        const double speed = (free ? kAvalancheSpeedFactor : 1.0) * s.speedMps;
        auto potential = [&](double r) { return -speed * w2 * r * r * flowShape(r, tip, s.stallLayer, -1.0, free); };
        // Separable terms: one pancake per layer (above it), a cold pool on the CMB.
        fa.termCount = 3;
        fa.termWidthRad = {kPancakeSigmaKm / layerRadiusKm(0), kPancakeSigmaKm / layerRadiusKm(1),
                           kSlabPoolSigmaKm / kCoreRadiusKm, 0.0, 0.0};
        fa.termShift = {slabShift(s, layerRadiusKm(0) + kPancakeOffsetKm), slabShift(s, layerRadiusKm(1) + kPancakeOffsetKm),
                        slabShift(s, kCoreRadiusKm), 0.0, 0.0};
        fa.shiftLo = std::min(0.0, s.dipSign * s.dipOffsetRad);
        fa.shiftHi = std::max(0.0, s.dipSign * s.dipOffsetRad);
        // A sinking slab meets 660 km first; stalled there, it never reaches the spin layer.
        std::array<double, 2> pancake{};
        for (int l = 0; l < 2; ++l)
            pancake[l] = (s.stallLayer == kNoLayer || l <= s.stallLayer) ? pancakeStrength(tip, layerRadiusKm(l), -1.0) : 0.0;
        const double pool = smootherstep((kCoreRadiusKm + 700.0 - tip) / 550.0);
        fa.f.resize(nR);
        fa.fPrime.resize(nR);
        fa.shift.resize(nR);
        fa.shiftPrime.resize(nR);
        fa.sheetK.resize(nR);
        fa.sheetWidthRad.resize(nR);
        fa.sheetPeakK.resize(nR);
        for (auto& t : fa.termRadial)
            t.assign(nR, 0.0);
        fa.termPart = {SynthPart::SlabPancake660, SynthPart::SlabPancake1600, SynthPart::SlabPool};
        for (auto& t : fa.termPeakK)
            t.assign(nR, 0.0);
        for (size_t i = 0; i < nR; ++i) {
            const double r = rKm[i];
            constexpr double h = 0.01;
            fa.f[i] = potential(r);
            fa.fPrime[i] = (potential(r + h) - potential(r - h)) / (2.0 * h);
            fa.shift[i] = slabShift(s, r);
            fa.shiftPrime[i] = slabShiftPrime(s, r);
            // Coldest near the surface; warms (thermal assimilation) with depth below the trench,
            // and thickens (buckling, slower sinking) below 660 km.
            const double depth = kSurfaceRadiusKm - r;
            const double assimilation = 0.55 + 0.45 * std::exp(-depth / 900.0);
            fa.sheetK[i] = s.amplitudeK * assimilation * smootherstep((r - tip) / 120.0);
            fa.sheetPeakK[i] = s.amplitudeK * assimilation;
            fa.sheetWidthRad[i] = s.thicknessKm * (1.0 + 0.9 * smootherstep((depth - 500.0) / 500.0)) / std::max(r, 1.0);
            fa.sheetWidthMax = std::max(fa.sheetWidthMax, fa.sheetWidthRad[i]);
            for (int l = 0; l < 2; ++l) {
                const double dl = (r - (layerRadiusKm(l) + kPancakeOffsetKm)) / kPancakeRadialSigmaKm;
                fa.termRadial[l][i] = s.amplitudeK * 0.6 * pancake[l] * std::exp(-0.5 * dl * dl);
            }
            fa.termRadial[2][i] = s.amplitudeK * 0.55 * pool * std::exp(-(r - kCoreRadiusKm) / kSlabPoolDecayKm);
            fa.termPeakK[0][i] = fa.termPeakK[1][i] = s.amplitudeK * 0.6;
            fa.termPeakK[2][i] = s.amplitudeK * 0.55 * cmbLayerPeak(kSlabPoolDecayKm);
        }
        SynthFeature& d = fa.description;
        d.kind = kindOf(false);
        describePoint(slabPoint(fa.pole, fa.arcE1, s.beta0, midPsi), d.latDeg, d.lonDeg);
        describePoint(slabPoint(fa.pole, fa.arcE1, s.beta0, 0.0), d.startLatDeg, d.startLonDeg);
        describePoint(slabPoint(fa.pole, fa.arcE1, s.beta0, s.arcAngle), d.endLatDeg, d.endLonDeg);
        d.frontRadiusKm = tip;
        d.stallDepthKm = s.stallLayer == kNoLayer ? 0.0 : kLayers[s.stallLayer].depthKm;
        d.breakingThrough = free;
        d.speedMps = speed;
        d.temperatureK = s.amplitudeK;
        d.dipAtTrenchDeg = radToDeg(std::atan(s.dipScaleKm / (kSurfaceRadiusKm * s.dipOffsetRad)));
        m.features.push_back(std::move(fa));
    }
    return m;
}

// Per-column values of one feature.
struct ColumnTerms {
    // Plumes: G's surface Laplacian and gradient.
    double lapG = 0;
    Vec3d gradG{};
    // Slabs: angular latitude about the pole and its gradient, the trench taper A(psi) and its
    // psi-derivatives times grad psi, 1 / cos^2(beta), tan(beta).
    double beta = 0, along = 0, alongD1 = 0, alongD2 = 0, invCos2 = 0, tanBeta = 0;
    Vec3d gradBeta{}, gradPsi{};
    std::array<double, kMaxTerms> angular{};
    bool active = false;
};

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

// Far from a feature every factor is below ~1e-13 of its peak; skipping it there is invisible
// in float32 and makes the per-cell loop touch only nearby features.
constexpr double kNegligibleExponent = 30.0;

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

// The slab sheet's profile across its (dipping) centre at radius index iR: a Gaussian of the
// angular offset `xi` from the centre, 0 where it is negligible.
double sheetProfile(const FeatureAtTime& fa, double xi, size_t iR)
{
    const double wt = fa.sheetWidthRad[iR];
    return xi * xi < 2.0 * kNegligibleExponent * wt * wt ? std::exp(-0.5 * xi * xi / (wt * wt)) : 0.0;
}

// Anomalies vanish at the isothermal surface and CMB: the factor (0 ... 1) they are multiplied by.
double isothermalBoundaryTaper(double rKm)
{
    const double depthKm = kSurfaceRadiusKm - rKm;
    return (1.0 - std::exp(-std::max(0.0, depthKm) / kSurfaceTaperKm)) *
           (1.0 - std::exp(-std::max(0.0, rKm - kCoreRadiusKm) / kCmbTaperKm));
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

// The features at the grid column (latDeg, lonDeg): every feature's terms there (columnTerms, with
// east and north as an orthonormal tangent basis even at the poles) and in `active` the features
// present. Returns the column's outward unit vector.
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

std::array<double, 2> syntheticFeatureCentreDeg(const SynthOptions& options, double timeMyr, size_t index, double rKm)
{
    const Model model = buildModel(options.seed);
    const double turn = model.rotationRadPerMyr * timeMyr;
    Vec3d p{};
    if (index < model.plumes.size()) {
        p = rotate(model.plumes[index].axis0, model.rotationAxis, turn);
    } else {
        if (index >= model.plumes.size() + model.slabs.size())
            fail("synthetic feature {} does not exist", index);
        const Slab& s = model.slabs[index - model.plumes.size()];
        p = rotate(slabPoint(s.pole0, s.start0, s.beta0 + slabShift(s, rKm), 0.5 * s.arcAngle), model.rotationAxis, turn);
    }
    std::array<double, 2> out{};
    describePoint(p, out[0], out[1]);
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
        boundaryTaper[i] = isothermalBoundaryTaper(grid.rKm[i]);
    }
    // Dual-cell area weights: lat rows by sin(upper edge) - sin(lower edge), lon columns by width.
    const std::vector<double> latWeights = grid.volumeFactors().lat;
    const std::vector<double> lonWeights = grid.lonWidthsDeg();
    // Per (lat row, radius) weighted sums of temperature, for the shell means; summed in a
    // fixed order afterwards so the result does not depend on thread scheduling.
    std::vector<double> rowSums(nLat * nR, 0.0);

    tbb::parallel_for(tbb::blocked_range<size_t>(0, nLat), [&](const tbb::blocked_range<size_t>& rows) {
        std::vector<ColumnTerms> terms(nFeatures);
        std::vector<int> active;
        active.reserve(nFeatures);
        for (size_t iLat = rows.begin(); iLat != rows.end(); ++iLat) {
            for (size_t iLon = 0; iLon < nLon; ++iLon) {
                const Vec3d n = featuresOfColumn(model, grid.latDeg[iLat], grid.lonDeg[iLon], terms, active);
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

SynthTruth syntheticTruth(const SynthOptions& options, double timeMyr, const SphericalGrid& grid)
{
    if (!std::isfinite(timeMyr))
        fail("synthetic truth: time {} Myr is not finite", timeMyr);
    const size_t nLat = grid.nLat(), nR = grid.nR(), nLon = grid.nLon();
    const ModelAtTime model = modelAt(options, timeMyr, grid.rKm);
    const size_t nFeatures = model.features.size();
    SynthTruth truth;
    truth.feature.assign(grid.cellCount(), -1);
    truth.part.assign(grid.cellCount(), SynthPart::Background);
    truth.envelope.assign(grid.cellCount(), 0.0f);
    std::vector<double> taper(nR);
    for (size_t i = 0; i < nR; ++i)
        taper[i] = isothermalBoundaryTaper(grid.rKm[i]);

    // The same columns and radial tables synthesizeSnapshot sums, compared term by term.
    tbb::parallel_for(tbb::blocked_range<size_t>(0, nLat), [&](const tbb::blocked_range<size_t>& rows) {
        std::vector<ColumnTerms> terms(nFeatures);
        std::vector<int> active;
        active.reserve(nFeatures);
        for (size_t iLat = rows.begin(); iLat != rows.end(); ++iLat) {
            for (size_t iLon = 0; iLon < nLon; ++iLon) {
                featuresOfColumn(model, grid.latDeg[iLat], grid.lonDeg[iLon], terms, active);
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
                            consider(f, SynthPart::SlabSheet, fa.sheetK[iR] * ct.along * sheetProfile(fa, xi, iR) * taper[iR],
                                     fa.sheetPeakK[iR]);
                        }
                    }
                    const size_t idx = grid.index(iLat, iR, iLon);
                    truth.feature[idx] = static_cast<int16_t>(bestFeature);
                    truth.part[idx] = bestPart;
                    truth.envelope[idx] = static_cast<float>(bestEnvelope);
                }
            }
        }
    });
    return truth;
}

std::string syntheticTruthTable(const SynthOptions& options)
{
    if (options.steps < 1)
        fail("synthetic truth: {} steps, expected at least 1", options.steps);
    const SphericalGrid grid = syntheticGrid(options.nLat, options.nR, options.nLon);
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
