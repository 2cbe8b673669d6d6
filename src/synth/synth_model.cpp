// The synthetic mantle's cast (synth_model.h): its plumes, slabs and background patterns, drawn from the
// seed. Every draw comes from one generator in a fixed order, so a seed always gives the same model.
#include "synth/synth_model.h"

#include <array>
#include <cmath>
#include <random>

namespace raypc::synth::synth {
namespace {

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

// One metre per second in cm/yr's terms: speeds are drawn in cm/yr.
constexpr double kCmPerYrInMps = 0.01 / (kSecondsPerMyr / 1e6);

// A feature's role: how deep its front starts and the layer where it stalls (kNoLayer: none).
struct Role {
    double frontDepthKm;
    int stallLayer;
};

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

// Plume heads: in the upper mantle (two, one spreading under the lithosphere), rising
// through the lower mantle (three), stalling below 1600 km (two) and below 660 km (two),
// and a young plume just above the CMB. Each keeps apart from the features in `taken`, and joins them.
std::vector<Plume> castPlumes(Rng& rng, std::vector<Vec3d>& taken)
{
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
    std::vector<Plume> plumes;
    for (const Role& role : plumeRoles) {
        Plume p;
        p.axis0 = pickSeparated(rng, taken, degToRad(32.0));
        taken.push_back(p.axis0);
        p.speedMps = rng.uniform(3.0, 4.5) * kCmPerYrInMps;
        p.amplitudeK = rng.uniform(250.0, 380.0);
        p.headRadius0Km = kSurfaceRadiusKm - role.frontDepthKm + rng.uniform(-60.0, 60.0);
        p.stallLayer = role.stallLayer;
        p.size = rng.uniform(0.9, 1.3);
        plumes.push_back(p);
    }
    return plumes;
}

// Slab tips: three lying on 660 and one heading for it, one between the layers, one
// crossing the spin layer, two stalling on it, one deep in the lower mantle and one on the CMB.
// Each keeps apart from the features in `taken`, and joins them.
std::vector<Slab> castSlabs(Rng& rng, std::vector<Vec3d>& taken)
{
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
    std::vector<Slab> slabs;
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
        s.speedMps = rng.uniform(3.5, 5.0) * kCmPerYrInMps;
        s.amplitudeK = -rng.uniform(320.0, 480.0);
        s.tipRadius0Km = kSurfaceRadiusKm - role.frontDepthKm + rng.uniform(-50.0, 50.0);
        s.stallLayer = role.stallLayer;
        slabs.push_back(s);
    }
    return slabs;
}

// Background: long-wavelength patterns (degrees 2-8), each divided by its largest value on the sphere.
void castBackground(Rng& rng, Model& model)
{
    addHarmonics(rng, model.poloidal, 2, 5, 2, 1.5);
    addHarmonics(rng, model.toroidal, 2, 4, 2, 1.0);
    addHarmonics(rng, model.top, 3, 8, 2, 0.7);
    addHarmonics(rng, model.bottom, 2, 4, 2, 0.8);
    const std::vector<Vec3d> axes = harmonicAxes(model, 0.0);
    Model unit = model;
    unit.poloidalNorm = unit.toroidalNorm = unit.topNorm = unit.bottomNorm = 1.0;
    model.poloidalNorm = maxOverSphere([&](Vec3d n) { return backgroundColumn(unit, axes, n).upwelling; });
    model.toroidalNorm = maxOverSphere([&](Vec3d n) {
        const Vec3d t = backgroundColumn(unit, axes, n).toroidal;
        return std::sqrt(dot(t, t));
    });
    model.topNorm = maxOverSphere([&](Vec3d n) { return backgroundColumn(unit, axes, n).top; });
    model.bottomNorm = maxOverSphere([&](Vec3d n) { return backgroundColumn(unit, axes, n).bottom; });
}

}  // namespace

Model buildModel(uint64_t seed)
{
    Rng rng(seed ^ 0x5eed5eed12345678ull);
    Model model;
    model.rotationAxis = rng.onSphere();
    // ~1 cm/yr at the surface: the whole pattern drifts by a couple of degrees over 24 Myr.
    const double surfaceSpeedMps = rng.uniform(0.8, 1.2) * 0.01 / (kSecondsPerMyr / 1e6);
    model.rotationRadPerMyr = surfaceSpeedMps * kSecondsPerMyr / (kSurfaceRadiusKm * 1000.0);

    // Each feature keeps apart from those drawn before it.
    std::vector<Vec3d> taken;
    model.plumes = castPlumes(rng, taken);
    model.slabs = castSlabs(rng, taken);
    castBackground(rng, model);
    return model;
}

}  // namespace raypc::synth::synth
