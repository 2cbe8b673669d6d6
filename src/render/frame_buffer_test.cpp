// Adaptive refinement of still frames (FrameBuffer's Refinement): the adaptive still against the
// full N-pass still, blocks in empty space stopping after the minimum passes, blocks on a sharp edge
// refining to the end, and per-block pass counts through packTiles / unpackTiles.
#include "render/frame_buffer.h"

#include "core/error.h"
#include "state/render_state.h"
#include "render/test_volumes.h"
#include "render/volume_renderer.h"

#include <gtest/gtest.h>

#include <cmath>

namespace raypc::render {
namespace {

using testing::makeGrid;
using testing::makeVolume;

constexpr int kMaxPasses = 8;

RenderParams viewParams(int width, int height)
{
    RenderParams p;
    p.width = width;
    p.height = height;
    p.camera.distanceKm = 19000;
    p.camera.fovYDeg = 42;
    return p;
}

// The plume field with opacity on both tails: soft structures with edges inside the volume.
RenderParams plumeParams(int width, int height)
{
    RenderParams p = viewParams(width, height);
    p.transfer.colorMap = ColorMapId::BlueWhiteRed;
    p.transfer.range = {-1, 1};
    p.transfer.opacity = {{0, 0.8f}, {0.35f, 0.0f}, {0.65f, 0.0f}, {1, 0.8f}};
    p.transfer.opacityUnitKm = 300;
    return p;
}

std::shared_ptr<dataset::StepVolume> plumeVolume() { return makeVolume(makeGrid(36, 17, 72), {{"f", testing::plumeField}}); }

FrameBuffer renderFrame(VolumeRenderer& r, int width, int height, Refinement refinement, TileShare share = {})
{
    FrameBuffer f(width, height);
    f.setRefinement(refinement);
    for (int i = 0; i < kMaxPasses; ++i)
        r.renderPass(f, nullptr, share);
    return f;
}

struct Difference {
    int max = 0;
    double mean = 0, over10 = 0;  // mean over RGB channels; share of pixels off by more than 10 levels
};
Difference difference8(const FrameBuffer& a, const FrameBuffer& b)
{
    const std::vector<uint8_t> x = a.resolveRgba8({0.1f, 0.1f, 0.12f}), y = b.resolveRgba8({0.1f, 0.1f, 0.12f});
    Difference d;
    size_t over = 0;
    for (size_t i = 0; i < x.size(); i += 4) {
        int worst = 0;
        for (int c = 0; c < 3; ++c) {
            const int v = std::abs(int(x[i + c]) - int(y[i + c]));
            worst = std::max(worst, v);
            d.mean += v;
        }
        d.max = std::max(d.max, worst);
        over += worst > 10;
    }
    d.mean /= double(x.size() / 4 * 3);
    d.over10 = double(over) / double(x.size() / 4);
    return d;
}

int blockPassesTotal(const FrameBuffer& f)
{
    int n = 0;
    for (int b = 0; b < f.blockCount(); ++b)
        n += f.blockPasses(b);
    return n;
}

// The adaptive still is the full 8-pass still where blocks refined to the end, and elsewhere differs
// by what the stopped blocks' remaining passes would have moved their mean. A block stops when its
// estimated error is below the threshold (0.5 levels, and the state's default), so the images must
// agree within the golden tests' tolerance (at most 0.5 % of pixels off by more than 10 levels, mean
// below 1 level) and, tighter, a mean difference below a quarter level (the worst pixel of a stopped
// block is estimated within the threshold, most pixels far within); and the refinement must have
// skipped work.
TEST(Refinement, AdaptiveStillMatchesTheFullStill)
{
    VolumeRenderer r(plumeVolume());
    const RenderParams p = plumeParams(160, 128);
    r.setParams(p);
    const FrameBuffer full = renderFrame(r, p.width, p.height, {});
    EXPECT_EQ(blockPassesTotal(full), kMaxPasses * full.blockCount());
    for (const float threshold : {0.5f, state::RenderState{}.convergenceGreyLevels}) {
        const FrameBuffer adaptive = renderFrame(r, p.width, p.height, {threshold});
        const Difference d = difference8(adaptive, full);
        EXPECT_LE(d.over10, 0.005) << "threshold " << threshold;
        EXPECT_LT(d.mean, 0.25) << "threshold " << threshold;
        const double share = double(blockPassesTotal(adaptive)) / double(blockPassesTotal(full));
        EXPECT_LT(share, 0.75) << "adaptive refinement rendered " << 100 * share << " % of the block-passes";
        std::printf("threshold %.1f: adaptive vs full 8 passes: max %d, mean %.3f levels, %.3f %% off by > 10; %.0f %% "
                    "of the block-passes\n",
                    threshold, d.max, d.mean, 100 * d.over10, 100 * share);
        // Blocks that took every pass are the full still's, bit for bit.
        const std::vector<float> a = adaptive.averagedRgba(), f = full.averagedRgba();
        for (int b = 0; b < adaptive.blockCount(); ++b) {
            if (adaptive.blockPasses(b) != kMaxPasses)
                continue;
            const TileRect rect = adaptive.block(b);
            for (int y = rect.y0; y < rect.y1; ++y)
                for (int x = rect.x0; x < rect.x1; ++x)
                    for (int c = 0; c < 4; ++c) {
                        const size_t i = 4 * (size_t(y) * size_t(p.width) + size_t(x)) + size_t(c);
                        ASSERT_EQ(a[i], f[i]) << "block " << b << " pixel " << x << "," << y;
                    }
        }
    }
}

// Nothing visible (a transparent volume, no core): every block is flat after one pass and stops
// there; with minPasses 2 after two. Further passes render nothing.
TEST(Refinement, EmptySpaceStopsAfterTheMinimumPasses)
{
    VolumeRenderer r(plumeVolume());
    RenderParams p = plumeParams(96, 80);
    p.transfer.opacity = {{0, 0}, {1, 0}};
    p.core.visible = false;
    r.setParams(p);
    for (int minPasses : {1, 2}) {
        FrameBuffer f(p.width, p.height);
        f.setRefinement({0.5f, minPasses});
        for (int i = 0; i < minPasses; ++i) {
            EXPECT_FALSE(f.converged());
            r.renderPass(f);
        }
        EXPECT_TRUE(f.converged()) << "minPasses " << minPasses;
        const PassStats s = r.renderPass(f);
        EXPECT_EQ(s.rays, 0u);
        EXPECT_EQ(f.passes(), minPasses + 1);
        for (int b = 0; b < f.blockCount(); ++b) {
            EXPECT_EQ(f.blockPasses(b), minPasses);
            EXPECT_EQ(f.blockErrorGreyLevels(b), 0.0f);
        }
    }
}

// The opaque core alone: its silhouette is a sharp edge whose pixels change with every pass's
// subpixel offset, so the blocks it crosses refine to the last pass; the blocks of background
// around it stop after the first.
TEST(Refinement, SharpEdgeKeepsRefining)
{
    VolumeRenderer r(plumeVolume());
    RenderParams p = plumeParams(128, 128);
    p.transfer.opacity = {{0, 0}, {1, 0}};
    r.setParams(p);
    const FrameBuffer f = renderFrame(r, p.width, p.height, {0.5f});
    const std::vector<float> rgba = f.averagedRgba();
    const int blocksX = (p.width + FrameBuffer::kBlockSize - 1) / FrameBuffer::kBlockSize;
    std::vector<float> lo(size_t(f.blockCount()), 1.0f), hi(size_t(f.blockCount()), 0.0f);
    for (int b = 0; b < f.blockCount(); ++b) {
        const TileRect rect = f.block(b);
        for (int y = rect.y0; y < rect.y1; ++y)
            for (int x = rect.x0; x < rect.x1; ++x) {
                const float a = rgba[4 * (size_t(y) * size_t(p.width) + size_t(x)) + 3];
                lo[size_t(b)] = std::min(lo[size_t(b)], a);
                hi[size_t(b)] = std::max(hi[size_t(b)], a);
            }
    }
    // Empty and away from the silhouette (a block next to it sees the core in neighbouring pixels).
    auto emptyAround = [&](int b) {
        const int bx = b % blocksX, by = b / blocksX;
        for (int y = by - 1; y <= by + 1; ++y)
            for (int x = bx - 1; x <= bx + 1; ++x)
                if (x >= 0 && x < blocksX && y >= 0 && y * blocksX < f.blockCount() && hi[size_t(y * blocksX + x)] > 0)
                    return false;
        return true;
    };
    int edgeBlocks = 0, emptyBlocks = 0;
    for (int b = 0; b < f.blockCount(); ++b) {
        if (lo[size_t(b)] == 0 && hi[size_t(b)] == 1) {  // background and core: the silhouette crosses it
            ++edgeBlocks;
            EXPECT_EQ(f.blockPasses(b), kMaxPasses) << "edge block " << b;
        } else if (emptyAround(b)) {
            ++emptyBlocks;
            EXPECT_EQ(f.blockPasses(b), 1) << "empty block " << b;
        }
    }
    EXPECT_GT(edgeBlocks, 8);
    EXPECT_GT(emptyBlocks, 4);
}

// A shared-out adaptive frame (TileShare) gathered by packTiles / unpackTiles equals the frame
// rendered whole, bit for bit, block pass counts and stops included: each block decides from its
// own tile only. 100x70 has partial tiles and blocks on two sides.
TEST(Refinement, PackedTilesCarryBlockPasses)
{
    VolumeRenderer r(plumeVolume());
    const RenderParams p = plumeParams(100, 70);
    r.setParams(p);
    const Refinement refinement{0.5f};
    const FrameBuffer whole = renderFrame(r, p.width, p.height, refinement);
    constexpr int kWorkers = 3;
    FrameBuffer gathered = renderFrame(r, p.width, p.height, refinement, {0, kWorkers});
    for (int w = 1; w < kWorkers; ++w) {
        const FrameBuffer part = renderFrame(r, p.width, p.height, refinement, {w, kWorkers});
        const std::vector<float> packed = part.packTiles({w, kWorkers});
        EXPECT_EQ(gathered.unpackTiles(packed, {w, kWorkers}), packed.size());
    }
    bool someStopped = false, someRefined = false;
    for (int b = 0; b < whole.blockCount(); ++b) {
        EXPECT_EQ(gathered.blockPasses(b), whole.blockPasses(b)) << "block " << b;
        EXPECT_EQ(gathered.blockRefining(b), whole.blockRefining(b)) << "block " << b;
        someStopped = someStopped || whole.blockPasses(b) < kMaxPasses;
        someRefined = someRefined || whole.blockPasses(b) == kMaxPasses;
    }
    EXPECT_TRUE(someStopped && someRefined);
    EXPECT_EQ(gathered.averagedRgba(), whole.averagedRgba());
    // Round trip of the whole frame: the same sums and counts.
    FrameBuffer copy(p.width, p.height);
    for (int i = 0; i < kMaxPasses; ++i)
        r.renderPass(copy, nullptr, {0, 2});  // the same pass count; its own tiles are overwritten below
    const std::vector<float> packed = whole.packTiles({});
    EXPECT_EQ(copy.unpackTiles(packed, {}), packed.size());
    EXPECT_EQ(copy.averagedRgba(), whole.averagedRgba());
    for (int b = 0; b < whole.blockCount(); ++b)
        EXPECT_EQ(copy.blockPasses(b), whole.blockPasses(b));
    // A block claiming more passes than the frame has taken is refused.
    std::vector<float> bad = packed;
    bad[6 * 32 * 32] = float(kMaxPasses + 1);  // the first block count of tile 0 (32x32 pixels)
    FrameBuffer other(p.width, p.height);
    for (int i = 0; i < kMaxPasses; ++i)
        r.renderPass(other);
    EXPECT_THROW(other.unpackTiles(bad, {}), Error);
}

TEST(Refinement, BadSettingsThrow)
{
    FrameBuffer f(16, 16);
    EXPECT_THROW(f.setRefinement({-1.0f}), Error);
    EXPECT_THROW(f.setRefinement({NAN}), Error);
    EXPECT_THROW(f.setRefinement({0.5f, 0}), Error);
}

}  // namespace
}  // namespace raypc::render
