// Internal to raypc_synth: the model of synthetic mantle convection that the generator's files
// share (docs/synthetic-data.md for the model and its parameters).
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
//
// Where each part lives: the radial profiles in synth_profiles.cpp, the cast of features drawn from
// the seed in synth_model.cpp, the background's harmonic patterns in synth_background.cpp, the model
// at one time in synth_model_at_time.cpp; evaluating it on a grid's columns in synth_columns.h.
//
// Units: km (radii, depths), m/s (speeds), K, Myr; angles in radians unless a name says degrees;
// directions are unit vectors in the Cartesian frame of core/spherical.h. Plain functions of their
// arguments, safe to call from any thread.
#pragma once

#include "synth/synth.h"

#include "core/spherical.h"
#include "core/vec3.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <numbers>
#include <vector>

namespace raypc::synth::synth {

inline constexpr double kPi = std::numbers::pi;
inline constexpr double kMantleThicknessKm = kSurfaceRadiusKm - kCoreRadiusKm;

// Rodrigues rotation of `v` about the unit `axis` by `angle` radians.
inline Vec3d rotate(Vec3d v, Vec3d axis, double angle)
{
    const double c = std::cos(angle), s = std::sin(angle);
    return c * v + s * cross(axis, v) + (dot(axis, v) * (1.0 - c)) * axis;
}

// C2-continuous step from 0 (t <= 0) to 1 (t >= 1); f' must be smooth for the velocity.
// Inline: the material properties call it for every cell.
inline double smootherstep(double t)
{
    t = std::clamp(t, 0.0, 1.0);
    return t * t * t * (t * (6.0 * t - 15.0) + 10.0);
}

// ---- the layers where material stagnates ----

struct Layer {
    double depthKm;
    double notchHalfWidthKm;  // how thick the slow-down of vertical flow is
    double notchDepth;        // fraction of vertical speed lost at the layer when passing
};
// 660 km: the ringwoodite -> bridgmanite + ferropericlase transition (endothermic, resists flow).
// 1600 km: the iron spin transition in ferropericlase, which in the contest data also shows
// stagnation. Narrow notches with steep flanks give strong lateral flow around the layers.
inline constexpr std::array<Layer, 2> kLayers = {{{660.0, 90.0, 0.85}, {1600.0, 130.0, 0.8}}};
inline constexpr int kNoLayer = -1;

inline double layerRadiusKm(int layer) { return kSurfaceRadiusKm - kLayers[layer].depthKm; }

// ---- radial profiles (synth_profiles.cpp) ----

// Feature anomalies are tapered to zero over these distances from the surface and the CMB.
inline constexpr double kSurfaceTaperKm = 60.0, kCmbTaperKm = 40.0;

// The largest value of exp(-a / decayKm) * (1 - exp(-a / kCmbTaperKm)) over heights a above the
// CMB: the peak of a layer on the CMB (pile, pool) after the taper, at a = 40 ln((40 + L) / 40).
double cmbLayerPeak(double decayKm);

// Temperature at rest (K): 300 K surface, ~120 km top boundary layer into an adiabat of
// 0.3 K/km starting at 1600 K, and a ~150 km hot boundary layer up to 4000 K at the CMB.
double referenceTemperatureK(double rKm);

// Anomalies vanish at the isothermal surface and CMB: the factor (0 ... 1) they are multiplied by.
double isothermalBoundaryTaper(double rKm);

// Where the front of a feature (head, tip) is relative to a layer: 1 while it lingers near the
// layer, decaying to 0 far below / above it; after passing, half of the spread material remains.
double pancakeStrength(double frontKm, double layerKm, double approachSign);

// Radial profile (dimensionless, 0 at both boundaries) of a feature's flow. `front` is the head
// or tip radius; flow fades over `kAheadKm` (400 km) beyond it; `direction` is +1 for rising plumes.
// `released`: the feature is breaking through its stall layer (an avalanche, SynthOptions): its flow
// crosses the layer, without the notch the layers it passes get.
double flowShape(double rKm, double frontKm, int stallLayer, double direction, bool released = false);

// Radial profile of the background poloidal flow: sin(pi x) with notches at both layers.
double backgroundShape(double rKm);

// Radial profile of the background toroidal flow: plate-like, strongest at the surface.
double toroidalShape(double rKm);

// ---- the features and the background, drawn from the seed (synth_model.cpp) ----

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

// The cast of features. Their roles are fixed so every seed shows every phenomenon the contest
// tasks look for; the seed decides positions, orientations, sizes, strengths and starting depths.
Model buildModel(uint64_t seed);

// ---- the background's harmonic patterns (synth_background.cpp) ----

// Background patterns at the unit vector n for harmonics with the given (rotated) axes.
struct BackgroundColumn {
    double upwelling = 0;   // sum c l(l+1) P_l / poloidalNorm = -lap_S B / norm, in [-1, 1]
    Vec3d gradB{};          // grad_S B / poloidalNorm
    Vec3d toroidal{};       // n x grad_S C / toroidalNorm
    double top = 0, bottom = 0;
};
BackgroundColumn backgroundColumn(const Model& model, const std::vector<Vec3d>& axes, Vec3d n);

// The axes of every harmonic (poloidal, toroidal, top, bottom, in that order) turned by `turn`
// radians about the model's rotation axis.
std::vector<Vec3d> harmonicAxes(const Model& model, double turn);

// Background poloidal potential f_bg(r) (so that u_r = f_bg / r^2 * upwelling, in m/s).
double backgroundPotential(double rKm);

// Background radial velocity (m/s) at unit vector n (t = 0 frame) and radius r.
double backgroundRadialVelocity(const Model& model, const std::vector<Vec3d>& axes0, Vec3d n, double rKm);

// ---- the model at one time, ready to evaluate on a grid (synth_model_at_time.cpp) ----

// Terms of one feature: the flow potential's angular part and the temperature's angular
// factors, evaluated per column; the radial tables per radius.
inline constexpr int kMaxTerms = 5;

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

// A flow potential's radial tables at the radii `rKm`: f = potential(r), and f' by a central
// difference (h = 0.01 km; error ~1e-8 relative).
template <class Potential>
void potentialTables(const std::vector<double>& rKm, Potential potential, std::vector<double>& f,
                     std::vector<double>& fPrime)
{
    f.resize(rKm.size());
    fPrime.resize(rKm.size());
    for (size_t i = 0; i < rKm.size(); ++i) {
        const double r = rKm[i];
        constexpr double h = 0.01;
        f[i] = potential(r);
        fPrime[i] = (potential(r + h) - potential(r - h)) / (2.0 * h);
    }
}

// The background's radial tables of `m` (bgF ... bgBottomK) at the radii `rKm` (synth_background.cpp).
void backgroundTables(const std::vector<double>& rKm, ModelAtTime& m);

// Everything that depends on time but not on the grid, plus radial tables for `rKm`.
ModelAtTime modelAt(const SynthOptions& options, double timeMyr, const std::vector<double>& rKm);

}  // namespace raypc::synth::synth
