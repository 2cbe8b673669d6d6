// The synthetic mantle at one time (synth_model.h): the pattern turned by the slow rotation, every
// plume's head and slab's tip moved with its own flow since t = 0, an avalanche under way, and the
// radial tables the grid's radii need; and the public views of it (synth.h): the features, where
// they are centred, the rotation.
#include "synth/synth_model.h"

#include "core/error.h"

#include <algorithm>
#include <array>
#include <cmath>

namespace raypc::synth {
namespace synth {
namespace {

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

void describePoint(Vec3d p, double& latDeg, double& lonDeg)
{
    const SphericalPoint s = cartesianToSpherical(p);
    latDeg = s.latDeg;
    lonDeg = s.lonDeg;
}

// What every feature's state at one time is computed from.
struct TimeContext {
    const Model& model;
    const std::vector<Vec3d>& axes0;  // the harmonics' axes at t = 0, the frame the fronts move in
    double timeMyr;
    double turn;                      // radians the pattern has turned since t = 0
    const std::vector<double>& rKm;   // the radii of the radial tables
};

// The radial tables of a feature's separable terms and their peaks, zero until filled.
void clearTermTables(FeatureAtTime& fa, size_t nR)
{
    for (auto& t : fa.termRadial)
        t.assign(nR, 0.0);
    for (auto& t : fa.termPeakK)
        t.assign(nR, 0.0);
}

// A plume's separable temperature terms with its head at `head` km: conduit (up to the head), head,
// hot pile at the base, one pancake per layer; their angular widths, parts and radial tables.
void plumeTerms(const Plume& p, double head, const std::vector<double>& rKm, FeatureAtTime& fa)
{
    const size_t nR = rKm.size();
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
    clearTermTables(fa, nR);
    fa.termPart = {SynthPart::PlumeConduit, SynthPart::PlumeHead, SynthPart::PlumePile, SynthPart::PlumePancake660,
                   SynthPart::PlumePancake1600};
    for (size_t i = 0; i < nR; ++i) {
        const double r = rKm[i];
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
}

void describePlume(const Plume& p, double head, FeatureAtTime& fa)
{
    SynthFeature& d = fa.description;
    d.kind = SynthFeature::Kind::Plume;
    describePoint(fa.axis, d.latDeg, d.lonDeg);
    d.frontRadiusKm = head;
    d.stallDepthKm = p.stallLayer == kNoLayer ? 0.0 : kLayers[p.stallLayer].depthKm;
    d.speedMps = p.speedMps;
    d.temperatureK = p.amplitudeK;
    d.conduitSigmaKm = fa.termWidthRad[0] * kPlumeTailReferenceKm;
}

// A plume at the context's time: its axis turned with the pattern, its head risen with its own flow.
FeatureAtTime plumeAt(const TimeContext& at, const Plume& p)
{
    FeatureAtTime fa;
    fa.isPlume = true;
    fa.axis = rotate(p.axis0, at.model.rotationAxis, at.turn);
    fa.flowWidthRad = p.size * kPlumeFlowWidthKm / kFlowReferenceRadiusKm;
    const double head =
        integrateFrontKm(at.model, at.axes0, p.headRadius0Km, p.speedMps, p.stallLayer, +1.0, at.timeMyr,
                         [&](double) { return p.axis0; }, [](double) { return false; });
    // G = exp(-(1 - cos gamma) / s^2) has -lap_S G = 2 / s^2 on the axis; scaling f by
    // s^2 / 2 * r^2 makes the axis speed exactly speedMps * flowShape.
    const double s2 = fa.flowWidthRad * fa.flowWidthRad;
    potentialTables(
        at.rKm, [&](double r) { return p.speedMps * 0.5 * s2 * r * r * flowShape(r, head, p.stallLayer, +1.0); }, fa.f,
        fa.fPrime);
    plumeTerms(p, head, at.rKm, fa);
    describePlume(p, head, fa);
    return fa;
}

// The slab that breaks through 660 km in an avalanche (SynthOptions): the first one stalled there;
// none without an avalanche.
const Slab* avalanchingSlab(const SynthOptions& options, const Model& model)
{
    if (std::isfinite(options.avalancheMyr))
        for (const Slab& s : model.slabs)
            if (s.stallLayer == 0)
                return &s;
    return nullptr;
}

// A slab's separable temperature terms with its tip at `tip` km: one pancake per layer (above it), a
// cold pool on the CMB; their angular widths, shifts, parts and radial tables.
void slabTerms(const Slab& s, double tip, const std::vector<double>& rKm, FeatureAtTime& fa)
{
    const size_t nR = rKm.size();
    fa.termCount = 3;
    fa.termWidthRad = {kPancakeSigmaKm / layerRadiusKm(0), kPancakeSigmaKm / layerRadiusKm(1),
                       kSlabPoolSigmaKm / kCoreRadiusKm, 0.0, 0.0};
    fa.termShift = {slabShift(s, layerRadiusKm(0) + kPancakeOffsetKm), slabShift(s, layerRadiusKm(1) + kPancakeOffsetKm),
                    slabShift(s, kCoreRadiusKm), 0.0, 0.0};
    // A sinking slab meets 660 km first; stalled there, it never reaches the spin layer.
    std::array<double, 2> pancake{};
    for (int l = 0; l < 2; ++l)
        pancake[l] = (s.stallLayer == kNoLayer || l <= s.stallLayer) ? pancakeStrength(tip, layerRadiusKm(l), -1.0) : 0.0;
    const double pool = smootherstep((kCoreRadiusKm + 700.0 - tip) / 550.0);
    clearTermTables(fa, nR);
    fa.termPart = {SynthPart::SlabPancake660, SynthPart::SlabPancake1600, SynthPart::SlabPool};
    for (size_t i = 0; i < nR; ++i) {
        const double r = rKm[i];
        for (int l = 0; l < 2; ++l) {
            const double dl = (r - (layerRadiusKm(l) + kPancakeOffsetKm)) / kPancakeRadialSigmaKm;
            fa.termRadial[l][i] = s.amplitudeK * 0.6 * pancake[l] * std::exp(-0.5 * dl * dl);
        }
        fa.termRadial[2][i] = s.amplitudeK * 0.55 * pool * std::exp(-(r - kCoreRadiusKm) / kSlabPoolDecayKm);
        fa.termPeakK[0][i] = fa.termPeakK[1][i] = s.amplitudeK * 0.6;
        fa.termPeakK[2][i] = s.amplitudeK * 0.55 * cmbLayerPeak(kSlabPoolDecayKm);
    }
}

// A slab's dipping sheet with its tip at `tip` km: per radius its shift and the shift's
// r-derivative, its temperature, its peak and its angular width; the range of its shifts.
void slabSheet(const Slab& s, double tip, const std::vector<double>& rKm, FeatureAtTime& fa)
{
    const size_t nR = rKm.size();
    fa.shiftLo = std::min(0.0, s.dipSign * s.dipOffsetRad);
    fa.shiftHi = std::max(0.0, s.dipSign * s.dipOffsetRad);
    fa.shift.resize(nR);
    fa.shiftPrime.resize(nR);
    fa.sheetK.resize(nR);
    fa.sheetWidthRad.resize(nR);
    fa.sheetPeakK.resize(nR);
    for (size_t i = 0; i < nR; ++i) {
        const double r = rKm[i];
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
    }
}

void describeSlab(const Slab& s, double tip, bool free, double speed, FeatureAtTime& fa)
{
    const double midPsi = 0.5 * s.arcAngle;
    SynthFeature& d = fa.description;
    d.kind = SynthFeature::Kind::Slab;
    describePoint(slabPoint(fa.pole, fa.arcE1, s.beta0, midPsi), d.latDeg, d.lonDeg);
    describePoint(slabPoint(fa.pole, fa.arcE1, s.beta0, 0.0), d.startLatDeg, d.startLonDeg);
    describePoint(slabPoint(fa.pole, fa.arcE1, s.beta0, s.arcAngle), d.endLatDeg, d.endLonDeg);
    d.frontRadiusKm = tip;
    d.stallDepthKm = s.stallLayer == kNoLayer ? 0.0 : kLayers[s.stallLayer].depthKm;
    d.breakingThrough = free;
    d.speedMps = speed;
    d.temperatureK = s.amplitudeK;
    d.dipAtTrenchDeg = radToDeg(std::atan(s.dipScaleKm / (kSurfaceRadiusKm * s.dipOffsetRad)));
}

// A slab at the context's time: its trench turned with the pattern, its tip sunk with its own flow,
// faster and through 660 km while `avalanching` and its avalanche is under way.
FeatureAtTime slabAt(const TimeContext& at, const SynthOptions& options, const Slab& s, bool avalanching)
{
    auto released = [&](double t) { return avalanching && avalancheUnderWay(options, t); };
    const bool free = released(at.timeMyr);
    FeatureAtTime fa;
    fa.isPlume = false;
    fa.pole = rotate(s.pole0, at.model.rotationAxis, at.turn);
    fa.arcE1 = rotate(s.start0, at.model.rotationAxis, at.turn);
    fa.arcE2 = cross(fa.pole, fa.arcE1);
    fa.beta0 = s.beta0;
    fa.arcAngle = s.arcAngle;
    fa.flowWidthRad = kSlabFlowWidthKm / kFlowReferenceRadiusKm;
    const double midPsi = 0.5 * s.arcAngle;
    const double tip = integrateFrontKm(at.model, at.axes0, s.tipRadius0Km, s.speedMps, s.stallLayer, -1.0, at.timeMyr,
                                        [&](double r) { return slabPoint(s.pole0, s.start0, s.beta0 + slabShift(s, r), midPsi); },
                                        released);
    // On the sheet -lap_S G = A / w^2 (see columnTerms); the minus sign makes the flow go
    // down where the slab is.
    const double w2 = fa.flowWidthRad * fa.flowWidthRad;
    const double speed = (free ? kAvalancheSpeedFactor : 1.0) * s.speedMps;
    potentialTables(
        at.rKm, [&](double r) { return -speed * w2 * r * r * flowShape(r, tip, s.stallLayer, -1.0, free); }, fa.f,
        fa.fPrime);
    slabTerms(s, tip, at.rKm, fa);
    slabSheet(s, tip, at.rKm, fa);
    describeSlab(s, tip, free, speed, fa);
    return fa;
}

}  // namespace

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
    backgroundTables(rKm, m);
    const TimeContext at{model, axes0, timeMyr, turn, rKm};
    for (const Plume& p : model.plumes)
        m.features.push_back(plumeAt(at, p));
    const Slab* avalanching = avalanchingSlab(options, model);
    for (const Slab& s : model.slabs)
        m.features.push_back(slabAt(at, options, s, &s == avalanching));
    return m;
}

}  // namespace synth

std::vector<SynthFeature> syntheticFeatures(const SynthOptions& options, double timeMyr)
{
    const synth::ModelAtTime m = synth::modelAt(options, timeMyr, {});
    std::vector<SynthFeature> out;
    for (const synth::FeatureAtTime& fa : m.features)
        out.push_back(fa.description);
    return out;
}

std::array<double, 2> syntheticFeatureCentreDeg(const SynthOptions& options, double timeMyr, size_t index, double rKm)
{
    const synth::Model model = synth::buildModel(options.seed);
    const double turn = model.rotationRadPerMyr * timeMyr;
    Vec3d p{};
    if (index < model.plumes.size()) {
        p = synth::rotate(model.plumes[index].axis0, model.rotationAxis, turn);
    } else {
        if (index >= model.plumes.size() + model.slabs.size())
            fail("synthetic feature {} does not exist", index);
        const synth::Slab& s = model.slabs[index - model.plumes.size()];
        p = synth::rotate(synth::slabPoint(s.pole0, s.start0, s.beta0 + synth::slabShift(s, rKm), 0.5 * s.arcAngle),
                          model.rotationAxis, turn);
    }
    std::array<double, 2> out{};
    synth::describePoint(p, out[0], out[1]);
    return out;
}

std::array<double, 3> syntheticRotationRadPerSecond(const SynthOptions& options)
{
    const synth::Model model = synth::buildModel(options.seed);
    const double w = model.rotationRadPerMyr / kSecondsPerMyr;
    return {w * model.rotationAxis.x, w * model.rotationAxis.y, w * model.rotationAxis.z};
}

}  // namespace raypc::synth
