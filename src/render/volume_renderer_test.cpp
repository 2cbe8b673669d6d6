// The renderer against analytic truth: transmittance and depth of a constant medium, opacity
// correction, SIMD vs scalar images, skipping on vs off, brushing, cancellation, level choice.
#include "render/volume_renderer.h"

#include "core/error.h"
#include "render/test_volumes.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>

namespace raypc::render {
namespace {

using testing::makeGrid;
using testing::makeVolume;

RenderParams smallParams(int size = 48)
{
    RenderParams p;
    p.width = p.height = size;
    p.camera.distanceKm = 19000;
    p.camera.fovYDeg = 42;
    return p;
}

std::vector<float> render(VolumeRenderer& r, const RenderParams& p, int passes, PassStats* last = nullptr)
{
    r.setParams(p);
    FrameBuffer f(p.width, p.height);
    for (int i = 0; i < passes; ++i) {
        const PassStats s = r.renderPass(f);
        if (last)
            *last = s;
    }
    return f.averagedRgba();
}

double maxAbsDiff(const std::vector<float>& a, const std::vector<float>& b)
{
    double m = 0;
    for (size_t i = 0; i < a.size(); ++i)
        m = std::max(m, double(std::abs(a[i] - b[i])));
    return m;
}

double meanAbsDiff(const std::vector<float>& a, const std::vector<float>& b)
{
    double s = 0;
    for (size_t i = 0; i < a.size(); ++i)
        s += std::abs(a[i] - b[i]);
    return s / double(a.size());
}

TEST(Renderer, ConstantMediumGivesAnalyticTransmittanceAndDepth)
{
    auto volume = makeVolume(makeGrid(18, 9, 36), {{"c", [](double, double, double) { return 1.0f; }}});
    VolumeRenderer renderer(volume);
    RenderParams p = smallParams(40);
    p.core.visible = false;
    p.transfer.range = {0, 2};
    p.transfer.opacity = {{0, 0.02f}, {1, 0.02f}};
    p.transfer.opacityUnitKm = 100;
    p.depthOpacity = 0.5f;
    p.stepFactor = 0.1f;  // steps of at most 0.1 x 10° x 6371 km = 111 km: the depth is exact to a step
    renderer.setParams(p);
    FrameBuffer frame(p.width, p.height);
    renderer.renderPass(frame);
    const auto rgba = frame.averagedRgba();
    const auto depth = frame.averagedDepthKm();
    const double sigma = -std::log(1 - 0.02) / 100;
    const CameraFrame cam(p.camera, p.width, p.height);
    int hits = 0, withDepth = 0;
    for (int y = 0; y < p.height; ++y) {
        for (int x = 0; x < p.width; ++x) {
            const Vec3 d = cam.direction(x + 0.5f, y + 0.5f);
            const ShellSegments s = intersectShell(cam.eye, d, 3485, 6371, true);
            double chord = 0, crossing = INFINITY;
            for (int i = 0; i < s.count; ++i) {
                const double need = std::log(2.0) / sigma - chord;  // optical depth ln 2 -> opacity 0.5
                if (!std::isfinite(crossing) && need <= s.t1[i] - s.t0[i])
                    crossing = s.t0[i] + need;
                chord += s.t1[i] - s.t0[i];
            }
            const size_t i = size_t(y) * p.width + x;
            EXPECT_NEAR(rgba[4 * i + 3], 1 - std::exp(-sigma * chord), 1e-3) << x << "," << y;
            hits += chord > 0;
            if (std::isfinite(crossing)) {
                ++withDepth;
                EXPECT_NEAR(depth[i], crossing, 112.0) << x << "," << y;
            } else {
                EXPECT_TRUE(std::isinf(depth[i])) << x << "," << y;
            }
        }
    }
    EXPECT_GT(hits, 400);
    EXPECT_GT(withDepth, 50);
}

TEST(Renderer, OpacityCorrectionMakesTheStepLengthInvisible)
{
    auto volume = makeVolume(makeGrid(36, 21, 72), {{"f", testing::plumeField}});
    VolumeRenderer renderer(volume);
    RenderParams p = smallParams();
    p.transfer.range = {-0.8f, 1.0f};
    p.transfer.opacity = {{0, 0.1f}, {0.5f, 0.0f}, {1, 0.6f}};
    p.stepFactor = 0.25f;
    const auto fine = render(renderer, p, 8);
    p.stepFactor = 1.0f;
    const auto coarse = render(renderer, p, 8);
    EXPECT_LT(meanAbsDiff(fine, coarse), 0.01);
    // Without correction (same alpha per sample) the quadrupled sample count would differ a lot;
    // make sure the scene is not trivially transparent.
    double alpha = 0;
    for (size_t i = 3; i < fine.size(); i += 4)
        alpha += fine[i];
    EXPECT_GT(alpha / (fine.size() / 4), 0.2);
}

TEST(Renderer, SimdImageEqualsScalarImage)
{
    auto volume = makeVolume(makeGrid(36, 21, 72, 0.4), {{"f", testing::plumeField},
                                                         {"g", [](double lat, double r, double) { return float(lat + r / 100); }}});
    VolumeRenderer renderer(volume);
    RenderParams p = smallParams();
    p.transfer.range = {-0.8f, 1.0f};
    p.transfer.colorMap = ColorMapId::CoolToWarm;
    p.transfer.opacity = {{0, 0.3f}, {0.4f, 0.0f}, {1, 0.8f}};
    p.brushes = {{1, std::nullopt, {{-60, 80}}}, {-1, grid::Coordinate::Lon, {{20, 300}}}};
    p.shading.enabled = true;
    p.core.variable = 1;
    p.core.range = {0, 40};
    const auto simd = render(renderer, p, 2);
    p.kernel = KernelKind::Scalar;
    const auto scalar = render(renderer, p, 2);
    EXPECT_LT(maxAbsDiff(simd, scalar), 0.02);
    EXPECT_LT(meanAbsDiff(simd, scalar), 2e-4);
}

TEST(Renderer, SkippingNeverChangesTheImage)
{
    auto volume = makeVolume(makeGrid(36, 33, 72), {{"f", testing::plumeField},
                                                    {"g", [](double, double r, double lon) { return float(r + lon); }}});
    VolumeRenderer renderer(volume);
    uint64_t jumped = 0;
    for (int variant = 0; variant < 8; ++variant) {
        RenderParams p = smallParams();
        p.transfer.range = {-0.8f, 1.0f};
        p.transfer.opacity = {{0, 0}, {0.6f, 0}, {0.7f, 0.5f}, {1, 0.9f}};  // transparent below 0.28
        if (variant >= 1 && variant <= 2)
            p.brushes.push_back({1, std::nullopt, {{4000, 6000}}});
        if (variant == 2)
            p.brushes.push_back({-1, grid::Coordinate::Z, {{-3000, 5000}}});
        // Large empty regions, so that interval skipping jumps over many chunks: a thin outer
        // shell; the polar regions next to the caps (caps are always sampled); a lon wedge
        // across the seam seen edge-on and from above.
        if (variant == 3)
            p.brushes.push_back({-1, grid::Coordinate::Radius, {{6000, 6371}}});
        if (variant == 4) {
            p.brushes.push_back({-1, grid::Coordinate::Lat, {{60, 90}}});
            p.camera.elevationDeg = 70;
        }
        if (variant == 5) {
            p.brushes.push_back({-1, grid::Coordinate::Lon, {{340, 360}}});
            p.camera.azimuthDeg = 80;
            p.transfer.opacity = {{0, 0.4f}, {1, 0.4f}};
        }
        // Several ranges on one axis: a brick is skipped only if it misses all of them.
        if (variant == 6)
            p.brushes.push_back({-1, grid::Coordinate::Radius, {{5900, 6371}, {3485, 3900}}});
        if (variant == 7)
            p.brushes.push_back({1, std::nullopt, {{4000, 4300}, {5000, 5200}, {6200, 6600}}});
        PassStats on;
        const auto a = render(renderer, p, 2, &on);
        p.skipBricks = false;
        PassStats off;
        const auto b = render(renderer, p, 2, &off);
        EXPECT_LE(maxAbsDiff(a, b), 1e-6) << "variant " << variant;
        EXPECT_GT(on.samplesSkipped, 0u) << "variant " << variant;  // the test would be vacuous otherwise
        EXPECT_GT(on.bricksSkipped, 0u);
        EXPECT_EQ(off.samplesSkipped, 0u);
        EXPECT_EQ(off.chunksJumped, 0u);
        jumped += on.chunksJumped;
    }
    EXPECT_GT(jumped, 1000u);
}

// Ranges on one axis are OR-ed: two that touch give the picture of their merged range, in both
// kernels; two apart give neither the picture of either one nor that of their hull.
TEST(Renderer, RangesOnOneAxisSelectTheirUnion)
{
    auto volume = makeVolume(makeGrid(36, 33, 72), {{"f", testing::plumeField},
                                                    {"r", [](double, double r, double) { return float(r); }}});
    VolumeRenderer renderer(volume);
    RenderParams p = smallParams();
    p.transfer.range = {-0.8f, 1.0f};
    p.transfer.opacity = {{0, 0.3f}, {1, 0.6f}};
    for (const KernelKind kernel : {KernelKind::Simd, KernelKind::Scalar}) {
        p.kernel = kernel;
        p.brushes = {{1, std::nullopt, {{4000, 4800}}}};
        const auto lower = render(renderer, p, 2);
        p.brushes = {{1, std::nullopt, {{4000, 5600}}}};
        const auto merged = render(renderer, p, 2);
        p.brushes = {{1, std::nullopt, {{4800, 5600}, {4000, 4800}}}};
        const auto touching = render(renderer, p, 2);
        EXPECT_LE(maxAbsDiff(touching, merged), 1e-6);
        EXPECT_GT(meanAbsDiff(merged, lower), 1e-3);  // the upper range adds to the picture

        // Apart: [4000, 4400] or [5200, 5600] (and a coordinate axis with two ranges beside it).
        p.brushes = {{1, std::nullopt, {{4000, 4400}, {5200, 5600}}}, {-1, grid::Coordinate::Lon, {{0, 90}, {180, 300}}}};
        const auto apart = render(renderer, p, 2);
        p.brushes = {{1, std::nullopt, {{4000, 4400}}}, {-1, grid::Coordinate::Lon, {{0, 90}, {180, 300}}}};
        const auto first = render(renderer, p, 2);
        p.brushes = {{1, std::nullopt, {{5200, 5600}}}, {-1, grid::Coordinate::Lon, {{0, 90}, {180, 300}}}};
        const auto second = render(renderer, p, 2);
        p.brushes = {{1, std::nullopt, {{4000, 5600}}}, {-1, grid::Coordinate::Lon, {{0, 90}, {180, 300}}}};
        const auto hull = render(renderer, p, 2);
        EXPECT_GT(meanAbsDiff(apart, first), 1e-3);
        EXPECT_GT(meanAbsDiff(apart, second), 1e-3);
        EXPECT_GT(meanAbsDiff(apart, hull), 1e-3);
        // Where only one range contributes (a pixel transparent in one picture), the union shows
        // the other's pixel; nowhere is it more opaque than the hull (but for early ray
        // termination, which stops either at an opacity of 0.995 or more).
        size_t onlyOne = 0;
        for (size_t i = 3; i < apart.size(); i += 4) {
            EXPECT_LE(apart[i], hull[i] + 1.0f - p.stopOpacity);
            if (first[i] == 0.0f && second[i] > 0.0f) {
                EXPECT_NEAR(apart[i], second[i], 1e-5f);
                ++onlyOne;
            }
        }
        EXPECT_GT(onlyOne, 10u);
    }
}

TEST(Renderer, BrushedOutVolumeShowsOnlyBackgroundAndCore)
{
    auto volume = makeVolume(makeGrid(18, 9, 36), {{"f", testing::plumeField}});
    VolumeRenderer renderer(volume);
    RenderParams p = smallParams(32);
    p.transfer.range = {-0.8f, 1.0f};
    p.transfer.opacity = {{0, 0.9f}, {1, 0.9f}};
    p.brushes = {{0, std::nullopt, {{5, 6}}}};  // no value is in [5, 6]
    p.core.color = {1, 0, 0};
    const auto img = render(renderer, p, 1);
    const CameraFrame cam(p.camera, p.width, p.height);
    for (int y = 0; y < p.height; ++y)
        for (int x = 0; x < p.width; ++x) {
            const size_t i = size_t(y) * p.width + x;
            const ShellSegments s = intersectShell(cam.eye, cam.direction(x + 0.5f, y + 0.5f), 3485, 6371, false);
            if (s.coreT >= 0) {
                EXPECT_EQ(img[4 * i + 3], 1.0f);
                EXPECT_EQ(img[4 * i + 1], 0.0f);  // pure red core, no volume colour
            } else {
                EXPECT_EQ(img[4 * i + 3], 0.0f);
            }
        }
}

// "Show the selection" (RenderState::selection): a selection in values the transfer function makes
// transparent is seen with the floor and not without it, in both kernels alike; skipping stays exact
// (bricks the transfer function alone would skip hold selected samples now); without brushes, or
// with brushes that select nothing, the floor changes nothing.
TEST(Renderer, ShownSelectionIsVisibleWhateverTheTransferFunctionSays)
{
    auto volume = makeVolume(makeGrid(36, 33, 72), {{"f", testing::plumeField}});
    VolumeRenderer renderer(volume);
    RenderParams p = smallParams();
    p.transfer.range = {-0.8f, 1.0f};
    p.transfer.opacity = {{0, 0.8f}, {0.35f, 0}, {0.65f, 0}, {1, 0.8f}};  // transparent over [-0.17, 0.37]
    p.brushes = {{0, std::nullopt, {{-0.1f, 0.3f}}}};
    // Pixels where the volume shows: those that differ from the picture of a selection of nothing
    // (the core and the background alone).
    RenderParams none = p;
    none.brushes = {{0, std::nullopt, {{5, 6}}}};
    const auto background = render(renderer, none, 2);
    auto volumePixels = [&](const std::vector<float>& img) {
        int n = 0;
        for (size_t i = 3; i < img.size(); i += 4)
            n += std::abs(img[i] - background[i]) > 0.05f;
        return n;
    };
    PassStats hiddenStats, shownStats;
    const auto hidden = render(renderer, p, 2, &hiddenStats);
    EXPECT_EQ(volumePixels(hidden), 0);
    p.selectionMinOpacity = 0.5f;
    const auto shown = render(renderer, p, 2, &shownStats);
    EXPECT_GT(volumePixels(shown), p.width * p.height / 10);
    EXPECT_LT(shownStats.bricksSkipped, hiddenStats.bricksSkipped);
    EXPECT_GT(shownStats.bricksSkipped, 0u);  // the brush still excludes bricks
    p.skipBricks = false;
    EXPECT_LE(maxAbsDiff(render(renderer, p, 2), shown), 1e-6);
    p.skipBricks = true;
    p.kernel = KernelKind::Scalar;
    const auto scalar = render(renderer, p, 2);
    EXPECT_LT(maxAbsDiff(shown, scalar), 0.02);
    EXPECT_LT(meanAbsDiff(shown, scalar), 2e-4);
    for (const KernelKind kernel : {KernelKind::Simd, KernelKind::Scalar}) {
        p.kernel = kernel;
        p.brushes = {{0, std::nullopt, {{5, 6}}}};  // selects nothing
        p.selectionMinOpacity = 0;
        const auto noneOff = render(renderer, p, 1);
        p.selectionMinOpacity = 0.5f;
        EXPECT_LE(maxAbsDiff(render(renderer, p, 1), noneOff), 0.0);
        p.brushes.clear();  // nothing brushed: the transfer function alone
        const auto plainOn = render(renderer, p, 1);
        p.selectionMinOpacity = 0;
        EXPECT_LE(maxAbsDiff(render(renderer, p, 1), plainOn), 0.0);
    }
    p.selectionMinOpacity = 1.5f;
    EXPECT_THROW(renderer.setParams(p), Error);
}

TEST(Renderer, CancelledPassLeavesTheFrameUnchanged)
{
    auto volume = makeVolume(makeGrid(18, 9, 36), {{"f", testing::plumeField}});
    VolumeRenderer renderer(volume);
    const RenderParams p = smallParams(64);
    renderer.setParams(p);
    FrameBuffer frame(p.width, p.height);
    std::atomic<bool> cancel{true};
    const PassStats s = renderer.renderPass(frame, &cancel);
    EXPECT_TRUE(s.cancelled);
    EXPECT_EQ(frame.passes(), 0);
    cancel = false;
    EXPECT_FALSE(renderer.renderPass(frame, &cancel).cancelled);
    EXPECT_EQ(frame.passes(), 1);
}

// Image-parallel frames (docs/scaling.md): three workers each render their interleaved tiles of
// every pass; their packed sums put into one frame give the frame rendered whole, bit for bit
// (jitter depends only on pixel and pass), depth included. 100x70 has partial tiles on two sides.
TEST(Renderer, SharedOutTilesGatherToTheWholeFrame)
{
    auto volume = makeVolume(makeGrid(18, 9, 36), {{"f", testing::plumeField}});
    VolumeRenderer renderer(volume);
    RenderParams p = smallParams();
    p.width = 100;
    p.height = 70;
    p.transfer.opacity = {{0, 0.3f}, {1, 0.8f}};
    renderer.setParams(p);
    constexpr int kPasses = 3, kWorkers = 3;
    FrameBuffer whole(p.width, p.height);
    for (int pass = 0; pass < kPasses; ++pass)
        renderer.renderPass(whole);
    FrameBuffer gathered(p.width, p.height);
    for (int pass = 0; pass < kPasses; ++pass)
        renderer.renderPass(gathered, nullptr, {0, kWorkers});  // worker 0 is the gathering one
    EXPECT_NE(gathered.averagedRgba(), whole.averagedRgba());  // it lacks the others' tiles
    for (int w = 1; w < kWorkers; ++w) {
        FrameBuffer part(p.width, p.height);
        for (int pass = 0; pass < kPasses; ++pass)
            renderer.renderPass(part, nullptr, {w, kWorkers});
        const std::vector<float> packed = part.packTiles({w, kWorkers});
        EXPECT_EQ(gathered.unpackTiles(packed, {w, kWorkers}), packed.size());
    }
    EXPECT_EQ(gathered.passes(), kPasses);
    EXPECT_EQ(gathered.averagedRgba(), whole.averagedRgba());
    const auto depthWhole = whole.averagedDepthKm(), depthGathered = gathered.averagedDepthKm();
    ASSERT_EQ(depthWhole.size(), depthGathered.size());
    for (size_t i = 0; i < depthWhole.size(); ++i)
        ASSERT_TRUE(depthWhole[i] == depthGathered[i] || (std::isinf(depthWhole[i]) && std::isinf(depthGathered[i])))
            << "pixel " << i;
    // Too few floats for a worker's tiles is an error, not a read past the end.
    EXPECT_THROW(gathered.unpackTiles(std::vector<float>(10), {1, kWorkers}), Error);
}

TEST(Renderer, BadParametersThrow)
{
    auto volume = makeVolume(makeGrid(18, 9, 36), {{"f", testing::plumeField}});
    VolumeRenderer renderer(volume);
    RenderParams p = smallParams();
    p.colorVariable = 3;
    EXPECT_THROW(renderer.setParams(p), Error);
    p = smallParams();
    p.brushes = {{0, std::nullopt, {{2, 1}}}};
    EXPECT_THROW(renderer.setParams(p), Error);
    p = smallParams();
    p.width = 0;
    EXPECT_THROW(renderer.setParams(p), Error);
}

TEST(Renderer, LevelSearchGoesFromCoarseToFineAndStopsAtTheFirstMiss)
{
    // Predicted seconds of levels 0 (finest) to 3.
    const std::vector<double> seconds{0.9, 0.4, 0.2, 0.1};
    std::vector<int> asked;
    auto at = [&](int level) {
        asked.push_back(level);
        return seconds[size_t(level)];
    };
    double s = 0;
    EXPECT_EQ(finestLevelWithin(4, 0.5, at, &s), 1);
    EXPECT_EQ(asked, (std::vector<int>{3, 2, 1, 0}));
    EXPECT_EQ(s, 0.4);
    asked.clear();
    EXPECT_EQ(finestLevelWithin(4, 0.05, at, &s), -1);
    EXPECT_EQ(asked, (std::vector<int>{3}));  // the finer levels are not even prepared
    EXPECT_EQ(s, 0.1);
    asked.clear();
    EXPECT_EQ(finestLevelWithin(4, 1.0, at, &s), 0);
    EXPECT_EQ(s, 0.9);
}

// chooseLevel, the rule StateRenderer::prepare chooses interactive levels with, on two real levels'
// predicted costs.
TEST(Renderer, LevelChoiceUsesTheThroughputAndShrinksTheImageWhenNeeded)
{
    auto fine = makeVolume(makeGrid(72, 41, 144), {{"f", testing::plumeField}});
    auto coarse = makeVolume(makeGrid(18, 11, 36), {{"f", testing::plumeField}});
    RenderParams p = smallParams(256);
    p.transfer.range = {-0.8f, 1.0f};
    VolumeRenderer rf(fine), rc(coarse);
    rf.setParams(p);
    rc.setParams(p);
    const double fineCost = rf.estimateSamplesPerPass(), coarseCost = rc.estimateSamplesPerPass();
    ASSERT_GT(fineCost, coarseCost);
    std::vector<int> asked;
    auto samplesAt = [&](int level) {
        asked.push_back(level);
        return level == 0 ? fineCost : coarseCost;
    };
    // Twice the fine level's samples per second: its pass takes 0.5 s of a 1 s budget.
    LevelChoice c = chooseLevel(2, 1.0, fineCost * 2, true, samplesAt);
    EXPECT_EQ(c.level, 0);
    EXPECT_EQ(c.divisor, 1);
    EXPECT_EQ(asked, (std::vector<int>{1, 0}));  // coarse to fine
    asked.clear();
    c = chooseLevel(2, 1.0, fineCost / 2, true, samplesAt);
    EXPECT_EQ(c.level, 1);
    EXPECT_EQ(c.divisor, 1);
    // Even the coarsest level misses the budget fourfold: half the pixels per side; the finer level
    // is not asked about.
    asked.clear();
    c = chooseLevel(2, 1.0, coarseCost / 4, true, samplesAt);
    EXPECT_EQ(c.level, 1);
    EXPECT_EQ(c.divisor, 2);
    EXPECT_EQ(std::count(asked.begin(), asked.end(), 0), 0);
    // Beyond fourfold: a quarter per side, never less; without reduceResolution the full size.
    EXPECT_EQ(chooseLevel(2, 1.0, coarseCost / 64, true, samplesAt).divisor, 4);
    EXPECT_EQ(chooseLevel(2, 1.0, coarseCost / 64, false, samplesAt).divisor, 1);
    EXPECT_EQ(resolutionDivisor(1.0, 1.0), 1);
    EXPECT_EQ(resolutionDivisor(4.0, 1.0), 2);
    EXPECT_EQ(resolutionDivisor(4.01, 1.0), 4);
    // The server's average of the throughput: the first measurement, then weight 0.3 for the newest.
    EXPECT_EQ(averagedMeasure(0, 5e7), 5e7);
    EXPECT_DOUBLE_EQ(averagedMeasure(5e7, 1e8), 0.7 * 5e7 + 0.3 * 1e8);
}

// An interactive frame's budget holds its pass and the time around it on the server (preparing,
// the picture and its JPEG): the pass gets what the measured overhead leaves of
// kInteractiveBudgetShare, shared by the views, and never less than a quarter of that share.
TEST(Renderer, ThePassGetsTheFramesBudgetLessItsOverhead)
{
    EXPECT_DOUBLE_EQ(passBudgetSeconds(50, 0, 1), kInteractiveBudgetShare * 0.05);
    EXPECT_DOUBLE_EQ(passBudgetSeconds(50, 0.0125, 1), kInteractiveBudgetShare * 0.05 - 0.0125);
    EXPECT_DOUBLE_EQ(passBudgetSeconds(50, 0.0125, 2), (kInteractiveBudgetShare * 0.05 - 0.0125) / 2);
    EXPECT_DOUBLE_EQ(passBudgetSeconds(50, 1.0, 1), 0.25 * kInteractiveBudgetShare * 0.05);
    // A pass predicted at 30 ms fits a 50 ms frame alone, not with 12.5 ms around it: the level
    // choice then renders a quarter of the pixels.
    const double samples = 3e6, rate = 1e8;  // 30 ms at `rate`
    auto samplesAt = [&](int) { return samples; };
    EXPECT_EQ(chooseLevel(1, passBudgetSeconds(50, 0, 1), rate, true, samplesAt).divisor, 1);
    EXPECT_EQ(chooseLevel(1, passBudgetSeconds(50, 0.0125, 1), rate, true, samplesAt).divisor, 2);
}

}  // namespace
}  // namespace raypc::render
