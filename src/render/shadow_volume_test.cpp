// Volumetric occlusion against analytic truth: the light's visibility behind a slab of known
// optical depth, none with empty space towards the light, the core's shadow, the ambient
// visibility inside a slab, the extinction the kernels see (SIMD against scalar), and the renderer
// with shadows (SIMD against scalar, darker behind the slab than without it).
#include "render/shadow_volume.h"

#include "render/pathline_scene.h"
#include "render/test_pathlines.h"
#include "render/test_volumes.h"
#include "render/volume_renderer.h"

#include <gtest/gtest.h>

#include <cmath>
#include <numbers>
#include <random>
#include <string>

namespace raypc::render {
namespace {

using testing::makeGrid;
using testing::makeVolume;

Vec3 unit(Vec3 v) { return normalize(v); }

// A field whose value is the distance along `l` (a unit vector): a slab of it is a plane slab
// perpendicular to l.
std::shared_ptr<dataset::StepVolume> planeVolume(Vec3 l)
{
    return makeVolume(makeGrid(90, 48, 180), {{"s", [l](double latDeg, double rKm, double lonDeg) {
                                                   const double lat = latDeg * M_PI / 180, lon = lonDeg * M_PI / 180;
                                                   return float(rKm * (std::cos(lat) * std::cos(lon) * l.x +
                                                                       std::cos(lat) * std::sin(lon) * l.y +
                                                                       std::sin(lat) * l.z));
                                               }}});
}

constexpr float kSlabLoKm = 3700, kSlabHiKm = 4300;  // the slab: s in [3700, 4300] km, 600 km thick
constexpr double kSlabOpticalDepth = 1.0;

// Opacity per 100 km that gives the slab an optical depth of 1 (or a transparent volume).
RenderParams slabParams(bool slab)
{
    RenderParams p;
    p.width = p.height = 32;
    p.camera.distanceKm = 19000;
    p.core.visible = false;
    p.transfer.range = {3000, 5000};
    const float a = slab ? float(1 - std::exp(-kSlabOpticalDepth / 6.0)) : 0.0f;
    p.transfer.opacity = {{0, 0}, {0.349f, 0}, {0.35f, a}, {0.65f, a}, {0.651f, 0}, {1, 0}};
    p.transfer.opacityUnitKm = 100;
    return p;
}

// A renderer of `volume` (by default the plane field along l) with `p`, and its kernels' parameters
// with the light along l. The parameters point into the renderer, so the two are kept together.
struct LitRenderer {
    LitRenderer(Vec3 l, const RenderParams& p, std::shared_ptr<dataset::StepVolume> volume = nullptr)
        : renderer(volume ? std::move(volume) : planeVolume(l))
    {
        renderer.setParams(p);
        k = renderer.kernelParams();
        k.lightDir = l;
    }
    VolumeRenderer renderer;
    kernel::KernelParams k;
};

kernel::Occlusion lookup(const ShadowVolume& shadows, kernel::KernelParams k, Vec3 p)
{
    shadows.bind(k);
    return kernel::occlusionAt(k, p);
}

class LightDirections : public ::testing::TestWithParam<Vec3> {};

TEST_P(LightDirections, SlabTowardsTheLightTransmitsItsOpticalDepth)
{
    const Vec3 l = unit(GetParam());
    const auto volume = planeVolume(l);
    // u: a unit vector perpendicular to l; points at 3000 u lie off the core's shadow and the rays
    // from them towards the light stay in the shell through the whole slab.
    const Vec3 u = unit(std::abs(l.z) < 0.9f ? cross(l, Vec3{0, 0, 1}) : cross(l, Vec3{1, 0, 0}));
    const Vec3 behind = l * 3000.0f + u * 3000.0f;  // s = 3000: the slab lies towards the light
    const Vec3 front = l * 4900.0f + u * 3000.0f;   // s = 4900: beyond the slab, empty towards the light
    for (bool slab : {true, false}) {
        const LitRenderer lit(l, slabParams(slab), volume);
        const kernel::KernelParams& k = lit.k;
        ShadowVolume shadows;
        shadows.update(k, 1.0f, nullptr);
        const kernel::Occlusion b = lookup(shadows, k, behind), f = lookup(shadows, k, front);
        if (slab) {
            // Optical depth within 10 %: each slab face is found to within a quarter cell (the
            // extinction's sub-samples are half a cell apart), 25 km of 600 per face.
            EXPECT_NEAR(-std::log(b.light), kSlabOpticalDepth, 0.1 * kSlabOpticalDepth) << "light visibility " << b.light;
            RecordProperty("opticalDepth", std::to_string(-std::log(b.light)));
        } else {
            EXPECT_EQ(b.light, 1.0f);  // the same region with the slab removed
            EXPECT_EQ(b.ambient, 1.0f);
        }
        EXPECT_EQ(f.light, 1.0f) << "empty space towards the light, slab " << slab;
    }
}

INSTANTIATE_TEST_SUITE_P(Shadows, LightDirections,
                         ::testing::Values(Vec3{1, 0, 0}, Vec3{0, 0, -1}, Vec3{0.6f, -0.5f, 0.62f}, Vec3{-0.3f, 0.8f, 0.4f}));

TEST(Shadows, StrengthScalesTheOcclusion)
{
    const Vec3 l{1, 0, 0};
    const LitRenderer lit(l, slabParams(true));
    const kernel::KernelParams& k = lit.k;
    ShadowVolume full, half;
    full.update(k, 1.0f, nullptr);
    half.update(k, 0.5f, nullptr);
    const Vec3 p{3000, 0, 3000};
    const float vFull = lookup(full, k, p).light, vHalf = lookup(half, k, p).light;
    EXPECT_NEAR(vHalf, 1.0f - 0.5f * (1.0f - vFull), 1e-5f);
}

TEST(Shadows, InsideASlabTheAmbientVisibilityIsTheMeanOverTheAxes)
{
    // At the middle of a slab perpendicular to x, 300 km from its faces: along +-x the ambient rays
    // (kAmbientReachKm = 400 km) leave it after 300 km, along +-y and +-z they stay in it.
    const Vec3 l{1, 0, 0};
    const LitRenderer lit(l, slabParams(true));
    const kernel::KernelParams& k = lit.k;
    ShadowVolume shadows;
    shadows.update(k, 1.0f, nullptr);
    const double sigma = kSlabOpticalDepth / 600.0;
    const double expected = (2 * std::exp(-sigma * 300) + 4 * std::exp(-sigma * kAmbientReachKm)) / 6;
    const float got = lookup(shadows, k, Vec3{4000, 0, 2500}).ambient;
    RecordProperty("ambient", std::to_string(got) + " expected " + std::to_string(expected));
    EXPECT_NEAR(got, expected, 0.03) << "ambient visibility";
    EXPECT_LT(got, 0.7f);
    EXPECT_EQ(lookup(shadows, k, Vec3{5400, 0, 2500}).ambient, 1.0f);  // 1100 km from the slab
}

TEST(Shadows, TheDrawnCoreCastsAShadowAndDoesNotShadeItsLitSide)
{
    const Vec3 l = unit(Vec3{0.3f, 0.5f, 0.8f});
    RenderParams p = slabParams(false);
    p.core.visible = true;
    const LitRenderer lit(l, p);
    kernel::KernelParams k = lit.k;
    ASSERT_TRUE(k.drawCore);
    ShadowVolume shadows;
    shadows.update(k, 1.0f, nullptr);
    const Vec3 u = unit(cross(l, Vec3{1, 0, 0}));
    EXPECT_LT(lookup(shadows, k, l * -5000.0f).light, 0.01f);                 // behind the core
    EXPECT_LT(lookup(shadows, k, l * -4500.0f + u * 2000.0f).light, 0.01f);  // inside its shadow's cylinder
    EXPECT_EQ(lookup(shadows, k, l * 5000.0f).light, 1.0f);                  // in front of it
    EXPECT_EQ(lookup(shadows, k, l * 3485.0f).light, 1.0f);                  // its lit pole
    EXPECT_EQ(lookup(shadows, k, l * -4000.0f + u * 5000.0f).light, 1.0f);  // beside its shadow
    // Hidden, it casts none.
    k.drawCore = false;
    ShadowVolume none;
    none.update(k, 1.0f, nullptr);
    EXPECT_EQ(lookup(none, k, l * -5000.0f).light, 1.0f);
}

TEST(Shadows, ExtinctionSimdEqualsScalar)
{
    auto volume = makeVolume(makeGrid(30, 17, 60, 0.3), {{"p", testing::plumeField}});
    VolumeRenderer renderer(volume);
    RenderParams p;
    p.transfer.range = {-1, 1};
    p.transfer.opacity = {{0, 0.6f}, {0.4f, 0}, {0.6f, 0}, {1, 0.6f}};
    p.brushes = {{0, std::nullopt, {{-0.9f, 0.8f}}}};
    renderer.setParams(p);
    const kernel::KernelParams& k = renderer.kernelParams();
    std::mt19937 rng(7);
    std::uniform_real_distribution<float> coord(-6500, 6500);
    const int n = 4001;
    std::vector<float> x(n), y(n), z(n), scalar(n), simd(n);
    for (int i = 0; i < n; ++i) {
        x[size_t(i)] = coord(rng);
        y[size_t(i)] = coord(rng);
        z[size_t(i)] = coord(rng);
    }
    kernel::extinctionBatchScalar(k, x.data(), y.data(), z.data(), n, scalar.data());
    kernel::extinctionBatchSimd(k, x.data(), y.data(), z.data(), n, simd.data());
    int nonzero = 0;
    for (int i = 0; i < n; ++i) {
        EXPECT_NEAR(simd[size_t(i)], scalar[size_t(i)], 1e-6f) << i;
        const float r = std::sqrt(x[size_t(i)] * x[size_t(i)] + y[size_t(i)] * y[size_t(i)] + z[size_t(i)] * z[size_t(i)]);
        if (r > 6371.5f || r < 3484.5f) {
            EXPECT_EQ(scalar[size_t(i)], 0.0f) << "outside the shell";
        }
        nonzero += scalar[size_t(i)] > 0.0f;
    }
    EXPECT_GT(nonzero, n / 100);  // the comparison is not vacuous
}

std::vector<float> renderImage(VolumeRenderer& r, const RenderParams& p, int passes = 2)
{
    r.setParams(p);
    FrameBuffer f(p.width, p.height);
    for (int i = 0; i < passes; ++i)
        r.renderPass(f);
    return f.averagedRgba();
}

TEST(Shadows, RendererSimdEqualsScalarAndShadowsDarken)
{
    auto volume = makeVolume(makeGrid(30, 17, 60, 0.3), {{"p", testing::plumeField}});
    VolumeRenderer renderer(volume);
    RenderParams p;
    p.width = p.height = 40;
    p.camera.distanceKm = 19000;
    p.transfer.range = {-1, 1};
    p.transfer.opacity = {{0, 0.6f}, {0.4f, 0}, {0.6f, 0}, {1, 0.6f}};
    p.shading.enabled = true;
    p.shading.shadows = true;
    p.shading.shadowStrength = 1.0f;
    const auto simd = renderImage(renderer, p);
    p.kernel = KernelKind::Scalar;
    const auto scalar = renderImage(renderer, p);
    double maxDiff = 0, sumShadowed = 0, sumLit = 0;
    for (size_t i = 0; i < simd.size(); ++i)
        maxDiff = std::max(maxDiff, double(std::abs(simd[i] - scalar[i])));
    EXPECT_LT(maxDiff, 2e-3);
    p.kernel = KernelKind::Simd;
    p.shading.shadows = false;
    const auto lit = renderImage(renderer, p);
    for (size_t i = 0; i < simd.size(); i += 4) {
        sumShadowed += simd[i] + simd[i + 1] + simd[i + 2];
        sumLit += lit[i] + lit[i + 1] + lit[i + 2];
        // Occlusion only takes light away; alpha is unchanged.
        EXPECT_LE(simd[i] + simd[i + 1] + simd[i + 2], lit[i] + lit[i + 1] + lit[i + 2] + 1e-4f) << i / 4;
        EXPECT_NEAR(simd[i + 3], lit[i + 3], 1e-5f);
    }
    EXPECT_LT(sumShadowed, 0.97 * sumLit);
}

// A straight tube along z through (x, y, 0), from z = -1500 to 1500 km, drawn.
std::shared_ptr<PathlineScene> straightTube(double xKm, double yKm, float radiusKm)
{
    testing::TestLine line;
    for (int i = 0; i <= 30; ++i) {
        line.pointsKm.push_back({xKm, yKm, -1500.0 + 100.0 * i});
        line.timesMyr.push_back(double(i));
    }
    auto scene = std::make_shared<PathlineScene>(std::vector<analysis::PathlineSet>{testing::makePathlineSet(0, 0, 1, {line})},
                                                 radiusKm);
    scene->setVisibility({1});
    PathlineStyle style = scene->style();
    style.ambientOcclusion = false;
    scene->setStyle(style);
    return scene;
}

TEST(Shadows, TubesShadowTheVolume)
{
    // A transparent volume, the light along +x, a 50 km tube at x = 4500: behind it (towards -x)
    // the light's visibility drops by about its splatted optical depth, pi r / cell (<= 1.6 here),
    // in front of it nothing changes.
    const Vec3 l{1, 0, 0};
    const LitRenderer lit(l, slabParams(false));
    const kernel::KernelParams& k = lit.k;
    const auto tube = straightTube(4500, 0, 50);
    ShadowVolume withTube, without;
    withTube.update(k, 1.0f, tube.get());
    without.update(k, 1.0f, nullptr);
    const Vec3 behind{3000, 0, 0}, front{5200, 0, 0};
    EXPECT_EQ(lookup(without, k, behind).light, 1.0f);
    const float v = lookup(withTube, k, behind).light;
    EXPECT_LT(v, 0.75f);
    EXPECT_GT(v, std::exp(-std::numbers::pi_v<float> * 50.0f / withTube.cellKm()) - 0.02f);
    EXPECT_EQ(lookup(withTube, k, front).light, 1.0f);
    EXPECT_LT(lookup(withTube, k, Vec3{4400, 0, 0}).ambient, 1.0f);  // beside the tube
    // Hiding the line removes its shadow (the mask is part of what update() watches).
    tube->setVisibility({0});
    withTube.update(k, 1.0f, tube.get());
    EXPECT_EQ(lookup(withTube, k, behind).light, 1.0f);
}

TEST(Shadows, TheVolumeShadowsTubes)
{
    // The camera on +x looks at a tube at (4000, 2000); the light comes from the camera's right,
    // +y. A slab of optical depth 1 across y in [3700, 4300] lies between the tube and the light
    // (within the shell all along the tube) but not between the tube and the camera. Lit by the diffuse term alone, the tube's pixels
    // are dimmed by the slab's transmittance, exp(-1) (optical depth within 10 %, as above);
    // without the slab they are as bright as without shadows.
    const Vec3 l{0, 1, 0};
    auto volume = planeVolume(l);
    const auto tube = straightTube(4000, 2000, 150);  // wider than a pixel (165 km at the tube)
    auto render = [&](bool slab, bool shadows) {
        VolumeRenderer r(volume);
        RenderParams p = slabParams(slab);
        p.width = p.height = 64;
        p.camera.azimuthDeg = 0;
        p.camera.elevationDeg = 0;
        p.camera.distanceKm = 19000;
        p.camera.fovYDeg = 40;
        p.shading.lightFromCamera = {1, 0, 0};
        p.shading.ambient = 0;
        p.shading.diffuse = 1;
        p.shading.shadows = shadows;
        p.shading.shadowStrength = 1.0f;
        r.setParams(p);
        EXPECT_NEAR(dot(r.kernelParams().lightDir, l), 1.0f, 1e-4f) << "the light is not along +y";
        r.setPathlines(tube);
        FrameBuffer f(p.width, p.height);
        r.renderPass(f);
        return f.averagedRgba();
    };
    const auto plain = render(false, false), open = render(false, true), shadowed = render(true, true);
    double sumPlain = 0, sumOpen = 0, sumShadowed = 0;
    int tubePixels = 0;
    for (size_t i = 0; i < plain.size(); i += 4) {
        if (plain[i + 3] < 0.999f)
            continue;  // not the tube (the volume alone is transparent)
        ++tubePixels;
        for (size_t c = 0; c < 3; ++c) {
            sumPlain += plain[i + c];
            sumOpen += open[i + c];
            sumShadowed += shadowed[i + c];
        }
    }
    ASSERT_GT(tubePixels, 10);
    ASSERT_GT(sumPlain, 0.0);
    EXPECT_NEAR(sumOpen / sumPlain, 1.0, 1e-5);
    const double ratio = sumShadowed / sumPlain;
    RecordProperty("opticalDepth", std::to_string(-std::log(ratio)));
    EXPECT_GT(ratio, std::exp(-1.1 * kSlabOpticalDepth));
    EXPECT_LT(ratio, std::exp(-0.9 * kSlabOpticalDepth));
}

TEST(Shadows, BadStrengthIsRefused)
{
    VolumeRenderer renderer(planeVolume(Vec3{1, 0, 0}));
    RenderParams p = slabParams(true);
    p.shading.shadowStrength = 1.5f;
    try {
        renderer.setParams(p);
        ADD_FAILURE() << "strength 1.5 accepted";
    } catch (const std::exception& e) {
        EXPECT_NE(std::string(e.what()).find("shadow strength"), std::string::npos) << e.what();
    }
}

}  // namespace
}  // namespace raypc::render
