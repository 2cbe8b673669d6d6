// The Cartesian skip grid: its distance transform against brute force, and that no sample the
// kernel would take inside a cell it calls empty (or along a ray stretch it skips) is active —
// on non-uniform grids with pole caps and a lon axis that does not start at 0.
#include "render/skip_grid.h"

#include "render/test_volumes.h"
#include "render/volume_renderer.h"

#include <gtest/gtest.h>

#include <cmath>
#include <random>

namespace raypc::render {
namespace {

using testing::makeGrid;
using testing::makeVolume;

TEST(SkipGrid, DistanceIsTheChebyshevDistanceToTheNearestOccupiedCell)
{
    // One brick per cell (lat = z, r = y, lon = x), some cells outside the shell or in a cap.
    const int n = 13;
    SkipGridGeometry g;
    g.n = n;
    g.bricksLat = g.bricksR = g.bricksLon = n;
    const size_t cells = size_t(n) * n * n;
    g.kind.assign(cells, SkipGridGeometry::Box);
    g.box.assign(6 * cells, 0);
    std::mt19937 rng(7);
    std::vector<int32_t> active(cells, 0);
    for (int z = 0; z < n; ++z)
        for (int y = 0; y < n; ++y)
            for (int x = 0; x < n; ++x) {
                const size_t c = (size_t(z) * n + y) * n + x;
                const uint16_t b[6] = {uint16_t(z), uint16_t(z), uint16_t(y), uint16_t(y), uint16_t(x), 1};
                std::copy(b, b + 6, &g.box[6 * c]);
                const uint32_t roll = rng() % 1000;
                if (roll < 4)
                    g.kind[c] = SkipGridGeometry::Always;
                else if (roll < 100)
                    g.kind[c] = SkipGridGeometry::None;
                active[c] = roll >= 50 && roll < 110;  // None cells (4..99) stay empty even where "their" brick is active
            }
    std::vector<uint8_t> dist;
    skipGridDistance(g, active, dist);
    std::vector<std::array<int, 3>> occupied;
    for (int z = 0; z < n; ++z)
        for (int y = 0; y < n; ++y)
            for (int x = 0; x < n; ++x) {
                const size_t c = (size_t(z) * n + y) * n + x;
                if (g.kind[c] == SkipGridGeometry::Always || (g.kind[c] == SkipGridGeometry::Box && active[c]))
                    occupied.push_back({x, y, z});
            }
    ASSERT_GT(occupied.size(), 5u);
    for (int z = 0; z < n; ++z)
        for (int y = 0; y < n; ++y)
            for (int x = 0; x < n; ++x) {
                int best = 255;
                for (const auto& o : occupied)
                    best = std::min(best, std::max({std::abs(o[0] - x), std::abs(o[1] - y), std::abs(o[2] - z)}));
                ASSERT_EQ(int(dist[(size_t(z) * n + y) * n + x]), best) << x << " " << y << " " << z;
            }
}

TEST(SkipGrid, LonBoxesWrapAcrossTheSeam)
{
    SkipGridGeometry g;
    g.n = 1;
    g.bricksLat = g.bricksR = 1;
    g.bricksLon = 6;
    g.kind = {SkipGridGeometry::Box};
    g.box = {0, 0, 0, 0, 4, 3};  // lon bricks 4, 5, 0
    std::vector<uint8_t> dist;
    for (int b = 0; b < 6; ++b) {
        std::vector<int32_t> active(6, 0);
        active[size_t(b)] = 1;
        skipGridDistance(g, active, dist);
        EXPECT_EQ(dist[0] == 0, b == 4 || b == 5 || b == 0) << "brick " << b;
    }
}

// A sparse active set on a stretched grid (lat rows at cell centres, so both poles have caps) whose
// lon axis starts at 2.5 degrees.
struct Scene {
    std::shared_ptr<dataset::StepVolume> volume;
    std::unique_ptr<VolumeRenderer> renderer;
};

Scene sparseScene()
{
    grid::SphericalGrid grid = makeGrid(36, 33, 72, 0.3);
    for (double& lon : grid.lonDeg)
        lon += 2.5;
    Scene s;
    s.volume = makeVolume(grid, {{"f", [](double lat, double r, double lon) {
                                      // Two blobs, one across the lon seam.
                                      auto blob = [&](double la, double lo, double rr) {
                                          double dl = std::remainder(lon - lo, 360.0);
                                          return std::exp(-((lat - la) * (lat - la) + dl * dl) / 60.0 - (r - rr) * (r - rr) / 2e5);
                                      };
                                      return float(blob(20, 358, 5000) + blob(-50, 120, 4200));
                                  }}});
    s.renderer = std::make_unique<VolumeRenderer>(s.volume);
    RenderParams p;
    p.width = p.height = 16;
    p.transfer.range = {0, 1};
    p.transfer.opacity = {{0, 0}, {0.3f, 0}, {0.31f, 0.5f}, {1, 0.5f}};  // transparent below 0.3
    s.renderer->setParams(p);
    return s;
}

TEST(SkipGrid, EmptyCellsHoldNoActiveSample)
{
    const Scene s = sparseScene();
    const kernel::KernelParams& k = s.renderer->kernelParams();
    ASSERT_NE(k.cellDistance, nullptr);
    std::mt19937 rng(11);
    std::uniform_real_distribution<float> u(-6371.0f, 6371.0f);
    int emptyChecked = 0, occupiedSeen = 0;
    for (int i = 0; i < 400000; ++i) {
        const Vec3 p{u(rng), u(rng), u(rng)};
        const float r = length(p);
        if (r < 3485.0f || r > 6371.0f)
            continue;
        const int ix = int((p.x - k.cellOriginKm) * k.cellInvKm), iy = int((p.y - k.cellOriginKm) * k.cellInvKm),
                  iz = int((p.z - k.cellOriginKm) * k.cellInvKm);
        const int D = k.cellDistance[(size_t(iz) * k.cellN + iy) * k.cellN + ix];
        const bool active = kernel::brickActive(k, kernel::locate(k, p.x, p.y, p.z));
        if (D == 0) {
            occupiedSeen += active;
            continue;
        }
        ++emptyChecked;
        ASSERT_FALSE(active) << "active sample in an empty cell at " << p.x << " " << p.y << " " << p.z;
    }
    EXPECT_GT(emptyChecked, 10000);
    EXPECT_GT(occupiedSeen, 100);
}

TEST(SkipGrid, SkippedRayStretchesHoldNoActiveSample)
{
    const Scene s = sparseScene();
    const kernel::KernelParams& k = s.renderer->kernelParams();
    std::mt19937 rng(5);
    std::normal_distribution<float> nd;
    double skippedKm = 0;
    for (int ray = 0; ray < 3000; ++ray) {
        const Vec3 o = normalize(Vec3{nd(rng), nd(rng), nd(rng)}) * 12000.0f;
        // Towards a random point in the shell, so rays cross it at every angle.
        const Vec3 target = normalize(Vec3{nd(rng), nd(rng), nd(rng)}) * (3500.0f + 2800.0f * float(ray % 7) / 6.0f);
        const Vec3 d = normalize(target - o);
        const ShellSegments seg = intersectShell(o, d, 3485.0f, 6371.0f, true);
        for (int sgi = 0; sgi < seg.count; ++sgi) {
            for (float t = seg.t0[sgi]; t < seg.t1[sgi];) {
                const float end = std::min(kernel::cellSkipTo(k, kernel::cellRay(k, o, d), t, 8), seg.t1[sgi]);
                for (float q = t; q < end; q += 2.0f) {
                    const Vec3 p = o + d * q;
                    ASSERT_FALSE(kernel::brickActive(k, kernel::locate(k, p.x, p.y, p.z))) << "ray " << ray << " t " << q;
                }
                skippedKm += end - t;
                t = std::max(end, t) + 37.0f;  // the next probe somewhere further on
            }
        }
    }
    EXPECT_GT(skippedKm, 1e6);
}

}  // namespace
}  // namespace raypc::render
