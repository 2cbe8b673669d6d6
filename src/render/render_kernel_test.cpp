// The samplers: SIMD equals scalar on random inputs; analytic values at grid points, across the lon
// seam and at the poles; the angle approximation.
#include "grid/sampler.h"
#include "render/render_kernel.h"
#include "render/test_volumes.h"
#include "render/volume_renderer.h"

#include <gtest/gtest.h>

#include <cmath>
#include <functional>
#include <random>

namespace raypc::render {
namespace {

using testing::makeGrid;
using testing::makeVolume;

Vec3 toXyz(double latDeg, double lonDeg, double rKm)
{
    const double a = latDeg * M_PI / 180, o = lonDeg * M_PI / 180;
    return {float(rKm * std::cos(a) * std::cos(o)), float(rKm * std::cos(a) * std::sin(o)), float(rKm * std::sin(a))};
}

struct Sampler {
    std::shared_ptr<dataset::StepVolume> volume;
    VolumeRenderer renderer;
    explicit Sampler(std::shared_ptr<dataset::StepVolume> v) : volume(v), renderer(v)
    {
        RenderParams p;
        p.shading.enabled = true;  // binds the gradient (nativeGradient)
        renderer.setParams(p);
    }
    const kernel::KernelParams& k() const { return renderer.kernelParams(); }
    float scalar(Vec3 p) const
    {
        float out;
        kernel::sampleBatchScalar(k(), k().color, &p.x, &p.y, &p.z, 1, &out);
        return out;
    }
};

TEST(FastAtan2, WithinTenMicroradians)
{
    std::mt19937 rng(3);
    std::uniform_real_distribution<float> u(-1, 1);
    for (int i = 0; i < 100000; ++i) {
        const float y = u(rng), x = u(rng);
        EXPECT_NEAR(kernel::fastAtan2(y, x), std::atan2(y, x), 1e-5) << y << "," << x;
    }
}

void expectSimdEqualsScalar(const Sampler& s)
{
    std::mt19937 rng(7);
    std::uniform_real_distribution<float> u(-6371, 6371);
    std::vector<float> x, y, z;
    while (x.size() < 20000) {
        const Vec3 p{u(rng), u(rng), u(rng)};
        const float r = length(p);
        if (r < 3485 || r > 6371)
            continue;
        x.push_back(p.x);
        y.push_back(p.y);
        z.push_back(p.z);
    }
    // Include the seam, the poles and the shell boundaries explicitly.
    for (const Vec3 p : {toXyz(0, 0, 5000), toXyz(10, 359.999, 4000), toXyz(90, 0, 6371), toXyz(-90, 0, 3485),
                         toXyz(89.9, 123, 5000), toXyz(-89.7, 300, 6000)}) {
        x.push_back(p.x);
        y.push_back(p.y);
        z.push_back(p.z);
    }
    const int n = int(x.size());
    std::vector<float> a(n), b(n);
    kernel::sampleBatchScalar(s.k(), s.k().color, x.data(), y.data(), z.data(), n, a.data());
    kernel::sampleBatchSimd(s.k(), s.k().color, x.data(), y.data(), z.data(), n, b.data());
    for (int i = 0; i < n; ++i)
        ASSERT_NEAR(a[i], b[i], 1e-4f * (1 + std::abs(a[i]))) << "point " << i;
}

TEST(Sampler, SimdEqualsScalarOnRandomPointsUniformGrid)
{
    expectSimdEqualsScalar(Sampler(makeVolume(makeGrid(30, 21, 60), {{"f", testing::plumeField}})));
}

TEST(Sampler, SimdEqualsScalarOnRandomPointsNonUniformGrid)
{
    expectSimdEqualsScalar(Sampler(makeVolume(makeGrid(30, 21, 60, 0.5), {{"f", testing::plumeField}})));
}

TEST(Sampler, ReproducesGridValuesAndLinearFieldsOnNonUniformGrids)
{
    // f = lat + 0.01 r is linear in the coordinates; trilinear-in-index interpolation reproduces it
    // exactly at grid points and within the table resolution between them along one axis.
    const grid::SphericalGrid g = makeGrid(24, 17, 48, 0.5);
    const Sampler s(makeVolume(g, {{"f", [](double lat, double r, double) { return float(lat + 0.01 * r); }}}));
    for (size_t a = 0; a < g.nLat(); a += 5)
        for (size_t r = 0; r < g.nR(); r += 4)
            EXPECT_NEAR(s.scalar(toXyz(g.latDeg[a], g.lonDeg[a], g.rKm[r])), g.latDeg[a] + 0.01 * g.rKm[r], 5e-3);  // ~1e-3 cells (angle approximation + table)
    // Between radii at a grid lat: linear in r between neighbours.
    const double rMid = 0.5 * (g.rKm[3] + g.rKm[4]);
    EXPECT_NEAR(s.scalar(toXyz(g.latDeg[7], 0, rMid)), g.latDeg[7] + 0.01 * rMid, 2e-3);
}

TEST(Sampler, ContinuousAcrossTheLonSeam)
{
    const grid::SphericalGrid g = makeGrid(20, 9, 36);  // 10° lon spacing, last column at 350°
    const Sampler s(makeVolume(g, {{"f", [](double, double, double lon) { return float(std::cos(lon * M_PI / 180)); }}}));
    // Between 350° and 360° the value interpolates column 35 (cos 350°) and column 0 (cos 0°).
    const float at355 = s.scalar(toXyz(g.latDeg[10], 355, 5000));
    EXPECT_NEAR(at355, 0.5 * (std::cos(350 * M_PI / 180) + 1.0), 1e-4);
    EXPECT_NEAR(s.scalar(toXyz(g.latDeg[10], 359.9999, 5000)), s.scalar(toXyz(g.latDeg[10], 0.0001, 5000)), 1e-4);
}

TEST(Sampler, PolesGiveOneValueForAllLongitudesAndBlendContinuously)
{
    const grid::SphericalGrid g = makeGrid(18, 9, 36);  // outermost rows at ±85°
    const Sampler s(makeVolume(g, {{"f", [](double lat, double r, double lon) {
                                        return float(std::sin(lon * M_PI / 180) + lat / 90 + r / 1000);
                                    }}}));
    for (double r : {3600.0, 5000.0, 6300.0}) {
        const float north = s.scalar(toXyz(90, 0, r));
        for (double lon : {10.0, 100.0, 200.0, 290.0})
            EXPECT_NEAR(s.scalar(toXyz(90, lon, r)), north, 1e-4);
        // Ring mean of sin(lon) is 0: the pole value is 85/90 + r/1000 (linear in r between grid radii).
        EXPECT_NEAR(north, 85.0 / 90 + r / 1000, 2e-3);
        EXPECT_NEAR(s.scalar(toXyz(-90, 0, r)), -85.0 / 90 + r / 1000, 2e-3);
        // Continuity at the outermost row: just beyond it the value is (nearly) the row's value.
        EXPECT_NEAR(s.scalar(toXyz(85.001, 90, r)), s.scalar(toXyz(84.999, 90, r)), 2e-3);
        // Half way to the pole: half way between the row value and the ring mean.
        const float row = s.scalar(toXyz(85, 90, r));
        EXPECT_NEAR(s.scalar(toXyz(87.5, 90, r)), 0.5 * (row + north), 2e-3);
    }
}

// The selection's floor (KernelParams::selectionSigmaPerKm) in the extinction both kernels give: a
// selected sample at a value the table makes transparent gets the floor, an opaque one keeps the
// table's larger extinction, an unselected one stays 0; SIMD equals scalar.
TEST(Kernel, SelectionFloorIsTheSameInBothKernelsAndLeavesUnselectedSamplesAlone)
{
    auto volume = makeVolume(makeGrid(30, 21, 60), {{"f", testing::plumeField}});
    VolumeRenderer renderer(volume);
    RenderParams p;
    p.transfer.range = {-0.8f, 1.0f};
    p.transfer.opacity = {{0, 0.9f}, {0.35f, 0}, {0.65f, 0}, {1, 0.9f}};
    p.brushes = {{-1, grid::Coordinate::Lon, {{0, 180}}}};  // the eastern half selected
    p.selectionMinOpacity = 0.2f;
    renderer.setParams(p);
    const kernel::KernelParams& k = renderer.kernelParams();
    const float floor = float(-std::log1p(-0.2) / p.transfer.opacityUnitKm);
    EXPECT_NEAR(k.selectionSigmaPerKm, floor, 1e-9f);
    std::mt19937 rng(5);
    std::uniform_real_distribution<double> lat(-89, 89), lon(0.5, 359.5), r(3500, 6360);
    std::vector<float> x, y, z;
    for (int i = 0; i < 4000; ++i) {
        const double o = lon(rng);
        if (std::abs(o - 180) < 0.01)  // the brush's edge, within the kernel's angle approximation
            continue;
        const Vec3 q = toXyz(lat(rng), o, r(rng));
        x.push_back(q.x), y.push_back(q.y), z.push_back(q.z);
    }
    const int n = int(x.size());
    std::vector<float> scalar(n), simd(n), value(n);
    kernel::extinctionBatchScalar(k, x.data(), y.data(), z.data(), n, scalar.data());
    kernel::extinctionBatchSimd(k, x.data(), y.data(), z.data(), n, simd.data());
    kernel::sampleBatchScalar(k, k.color, x.data(), y.data(), z.data(), n, value.data());
    int floored = 0, unselected = 0, opaque = 0;
    for (int i = 0; i < n; ++i) {
        ASSERT_NEAR(scalar[i], simd[i], 1e-6f * (1 + scalar[i])) << "point " << i;
        const float table = k.table.sigmaPerKm[k.table.indexOf(value[i])];
        if (std::atan2(y[i], x[i]) < 0) {  // western half: not selected
            ASSERT_EQ(scalar[i], 0.0f) << "point " << i;
            ++unselected;
        } else if (table < floor) {
            ASSERT_NEAR(scalar[i], floor, 1e-9f) << "point " << i;
            floored += table == 0.0f;
        } else {
            ASSERT_EQ(scalar[i], table) << "point " << i;
            ++opaque;
        }
    }
    EXPECT_GT(floored, 200);  // selected samples at values of opacity 0, made visible
    EXPECT_GT(unselected, 1000);
    EXPECT_GT(opaque, 10);
}

// The closed-form sample count along a ray: increasing, inverted by tAt, continuous at the crossover,
// and about stepFactor cells per sample — dr on a radial ray, h dθ at a tangential closest approach.
// Shading's gradient on the native grid (nativeGradient) points along the analytic gradient of
// linear Cartesian fields and of r, on uniform and non-uniform grids, across the lon seam and up to
// the outermost lat rows; a field constant in lon gives no east component even at the seam.
void expectGradientDirection(const grid::SphericalGrid& g, std::function<float(Vec3)> field, Vec3 expected,
                             bool radial, double maxDeg)
{
    const Sampler s(makeVolume(g, {{"f", [&](double lat, double r, double lon) { return field(toXyz(lat, lon, r)); }}}));
    std::mt19937 rng(11);
    std::uniform_real_distribution<double> lat(g.latDeg.front(), g.latDeg.back()), lon(0, 360), r(3600, 6250);
    std::vector<Vec3> points;
    for (int i = 0; i < 2000; ++i)
        points.push_back(toXyz(lat(rng), lon(rng), r(rng)));
    for (double seamLon : {359.95, 0.0, 0.05, 359.5, 0.5})
        points.push_back(toXyz(20, seamLon, 5000));
    double worst = 0;
    for (const Vec3 p : points) {
        const kernel::Located L = kernel::locate(s.k(), p.x, p.y, p.z);
        const Vec3 gr = kernel::nativeGradient(s.k(), L, p);
        const Vec3 want = radial ? normalize(p) : expected;
        const double c = std::clamp(double(dot(normalize(gr), want)), -1.0, 1.0);
        worst = std::max(worst, std::acos(c) * 180 / M_PI);
    }
    EXPECT_LT(worst, maxDeg);
}

TEST(NativeGradient, PointsAlongTheAnalyticGradient)
{
    for (const double stretch : {0.0, 0.5}) {
        SCOPED_TRACE(stretch);
        const grid::SphericalGrid g = makeGrid(60, 41, 120, stretch);
        expectGradientDirection(g, [](Vec3 p) { return p.z; }, {0, 0, 1}, false, 6);
        expectGradientDirection(g, [](Vec3 p) { return p.x; }, {1, 0, 0}, false, 6);
        expectGradientDirection(g, [](Vec3 p) { return -2 * p.y; }, {0, -1, 0}, false, 6);
        expectGradientDirection(g, [](Vec3 p) { return length(p); }, {}, true, 0.5);
    }
}

TEST(NativeGradient, MatchesTheFiniteDifferenceOfTheSampledField)
{
    // Magnitude, not just direction: d/dz of f = 3 z is 3 per km (within the interpolation error).
    const grid::SphericalGrid g = makeGrid(90, 61, 180);
    const Sampler s(makeVolume(g, {{"f", [](double lat, double r, double lon) { return 3 * toXyz(lat, lon, r).z; }}}));
    for (const Vec3 p : {toXyz(30, 10, 5000), toXyz(-45, 200, 4000), toXyz(5, 359.9, 6000)}) {
        const Vec3 gr = kernel::nativeGradient(s.k(), kernel::locate(s.k(), p.x, p.y, p.z), p);
        EXPECT_NEAR(gr.z, 3.0, 0.15) << p.x << "," << p.y << "," << p.z;
        EXPECT_NEAR(gr.x, 0.0, 0.15);
        EXPECT_NEAR(gr.y, 0.0, 0.15);
    }
}

TEST(RaySampling, SamplesAreAboutStepFactorCellsApartAndTheMapInverts)
{
    kernel::KernelParams k;
    k.stepFactor = 0.5f;
    k.drKm = 14.4f;
    k.dAngleRad = float(M_PI / 180.0);
    std::mt19937 rng(3);
    std::normal_distribution<float> nd;
    for (int ray = 0; ray < 200; ++ray) {
        const Vec3 o = normalize(Vec3{nd(rng), nd(rng), nd(rng)}) * 19000.0f;
        const Vec3 target = normalize(Vec3{nd(rng), nd(rng), nd(rng)}) * (6371.0f * float(ray % 10) / 9.0f);
        const Vec3 d = normalize(target - o);
        const kernel::RaySampling rs = kernel::raySampling(k, o, d);
        float previous = -INFINITY;
        for (float t = 10000.0f; t < 30000.0f; t += 3.7f) {
            const float u = rs.samplesAt(t);
            ASSERT_GE(u, previous) << "ray " << ray << " t " << t;
            previous = u;
            ASSERT_NEAR(rs.tAt(u), t, 2e-2f) << "ray " << ray << " t " << t;
            // The spacing where the ray is at radius r in the shell, against the cell it crosses.
            const Vec3 p = o + d * t;
            const float r = length(p);
            if (r < 3485.0f || r > 6371.0f)
                continue;
            const float spacing = 1.0f / (rs.samplesAt(t + 0.5f) - rs.samplesAt(t - 0.5f));
            const float cosA = std::abs(dot(p, d)) / r, sinA = std::sqrt(std::max(0.0f, 1.0f - cosA * cosA));
            const float cellAlongRay = 1.0f / std::max(cosA / k.drKm, sinA / (r * k.dAngleRad));
            ASSERT_GT(spacing, 0.9f * cellAlongRay * k.stepFactor) << "ray " << ray << " t " << t;
            ASSERT_LT(spacing, 1.01f * cellAlongRay * k.stepFactor) << "ray " << ray << " t " << t;
        }
    }
    // A ray through the centre steps dr; one grazing the surface steps h dθ at its closest approach.
    const kernel::RaySampling radial = kernel::raySampling(k, {0, 0, 19000}, {0, 0, -1});
    EXPECT_NEAR(radial.tAt(1) - radial.tAt(0), k.stepFactor * k.drKm, 1e-3);
    const kernel::RaySampling grazing = kernel::raySampling(k, {-19000, 6000, 0}, {1, 0, 0});
    EXPECT_NEAR(grazing.tAt(1) - grazing.tAt(0), k.stepFactor * 6000.0f * k.dAngleRad, 1e-2);
}

// The kernels and GridSampler (probe, pathlines) follow the same sampling rules, including the pole
// caps' ring mean (weighted by lon width) and the lon seam, on a grid whose lon axis is not uniform.
TEST(Sampler, KernelsEqualGridSamplerOnRandomPointsWithNonUniformLonCapsAndSeam)
{
    grid::SphericalGrid g = makeGrid(20, 13, 40, 0.4);
    g.lonDeg.clear();
    for (int i = 0; i < 40; ++i) {  // columns bunched towards 90° and sparse towards 270°
        const double u = i / 40.0;
        g.lonDeg.push_back(2.0 + 360.0 * (u + 0.35 * std::sin(2 * M_PI * u) / (2 * M_PI)));
    }
    // A field whose ring mean depends on how the columns are weighted.
    const Sampler s(makeVolume(g, {{"f", [](double lat, double r, double lon) {
                                        return float(std::cos(lon * M_PI / 180) * (1 + lat / 90) + 0.0005 * r);
                                    }}}));
    const grid::GridSampler reference(g);
    const float* values = s.volume->values(0);

    std::mt19937 rng(11);
    std::uniform_real_distribution<double> u(0, 1);
    std::vector<float> x, y, z;
    std::vector<double> expected;
    const double capLat = g.latDeg.back(), firstLon = g.lonDeg.front(), lastLon = g.lonDeg.back();
    int inCaps = 0, inSeam = 0;
    while (x.size() < 6000) {
        const int kind = int(x.size() % 3);  // anywhere, in a pole cap, in the seam gap
        const double r = 3485.0 + (6371.0 - 3485.0) * u(rng);
        double lat = -90 + 180 * u(rng), lon = 360 * u(rng);
        if (kind == 1)
            lat = (u(rng) < 0.5 ? -1 : 1) * (capLat + (90 - capLat) * u(rng) * 0.999);
        if (kind == 2)
            lon = std::fmod(lastLon + (firstLon + 360 - lastLon) * u(rng), 360.0);
        const auto at = reference.locate(lat, lon, r);
        ASSERT_TRUE(at) << lat << " " << lon << " " << r;
        inCaps += at->poleWeight > 0;
        inSeam += at->lon0 == g.nLon() - 1 && at->lon1 == 0;
        const Vec3 p = toXyz(lat, lon, r);
        x.push_back(p.x), y.push_back(p.y), z.push_back(p.z);
        expected.push_back(reference.sample(values, *at));
    }
    EXPECT_GT(inCaps, 1500);
    EXPECT_GT(inSeam, 1500);
    std::vector<float> scalar(x.size()), simd(x.size());
    kernel::sampleBatchScalar(s.k(), s.k().color, x.data(), y.data(), z.data(), int(x.size()), scalar.data());
    kernel::sampleBatchSimd(s.k(), s.k().color, x.data(), y.data(), z.data(), int(x.size()), simd.data());
    double worst = 0;
    for (size_t i = 0; i < x.size(); ++i) {
        worst = std::max({worst, std::abs(scalar[i] - expected[i]), std::abs(simd[i] - expected[i])});
        const auto sp = cartesianToSpherical({x[i], y[i], z[i]});
        ASSERT_NEAR(scalar[i], expected[i], 2e-3) << "point " << i << " lat " << sp.latDeg << " lon " << sp.lonDeg << " r " << sp.rKm;
        ASSERT_NEAR(simd[i], expected[i], 2e-3) << "point " << i;
    }
    RecordProperty("worstDifference", std::to_string(worst));
}

}  // namespace
}  // namespace raypc::render
