#include "render/skip_grid.h"

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <cmath>
#include <mutex>
#include <numbers>

namespace raypc::render {
namespace {

constexpr double kRadToDeg = 180.0 / std::numbers::pi;
// Angles are padded by this much (degrees): more than the kernel's arctangent error (1e-5 rad).
constexpr double kAnglePadDeg = 0.002;

// The kernel's own index rules (render_kernel.h, locate), so that a cell's bricks are the bricks
// its samples are assigned to.
int latIndex(const kernel::KernelParams& k, double latDeg)
{
    const float f = std::clamp(k.lat.map(float(latDeg)), 0.0f, float(k.nLat - 1));
    return std::min(int(f), k.nLat - 2);
}
int rIndex(const kernel::KernelParams& k, double rKm)
{
    const float f = std::clamp(k.r.map(float(rKm)), 0.0f, float(k.nR - 1));
    return std::min(int(f), k.nR - 2);
}
int lonIndex(const kernel::KernelParams& k, double lonDeg)
{
    lonDeg = std::fmod(lonDeg, 360.0);
    if (lonDeg < 0)
        lonDeg += 360.0;
    float f = k.lon.map(float(lonDeg));
    f = f < 0.0f ? f + float(k.nLon) : f;
    f = f >= float(k.nLon) ? f - float(k.nLon) : f;
    return std::clamp(int(f), 0, k.nLon - 1);
}

// One cell (grown by the pad): its kind and brick box.
void classifyCell(const kernel::KernelParams& k, const double lo[3], const double hi[3], uint8_t& kind, uint16_t* box)
{
    auto nearest = [](double a, double b) { return a > 0 ? a : (b < 0 ? b : 0.0); };
    auto farthest = [](double a, double b) { return std::max(std::abs(a), std::abs(b)); };
    const double nx = nearest(lo[0], hi[0]), ny = nearest(lo[1], hi[1]), nz = nearest(lo[2], hi[2]);
    const double fx = farthest(lo[0], hi[0]), fy = farthest(lo[1], hi[1]), fz = farthest(lo[2], hi[2]);
    const double rhoMin = std::hypot(nx, ny), rhoMax = std::hypot(fx, fy);
    const double rMin = std::hypot(rhoMin, nz), rMax = std::hypot(rhoMax, fz);
    // Samples lie in the shell (up to rounding).
    if (rMin > double(k.rOuterKm) + 0.5 || rMax < double(k.rInnerKm) - 0.5) {
        kind = SkipGridGeometry::None;
        return;
    }
    // lat = atan2(z, rho) grows with z, and with rho where z < 0.
    const double latMin = std::atan2(lo[2], lo[2] >= 0 ? rhoMax : rhoMin) * kRadToDeg - kAnglePadDeg;
    const double latMax = std::atan2(hi[2], hi[2] >= 0 ? rhoMin : rhoMax) * kRadToDeg + kAnglePadDeg;
    if ((k.capScaleSouth > 0.0f && latMin <= double(k.latSouthDeg)) ||
        (k.capScaleNorth > 0.0f && latMax >= double(k.latNorthDeg))) {
        kind = SkipGridGeometry::Always;
        return;
    }
    kind = SkipGridGeometry::Box;
    const int s = k.brickShift;
    box[0] = uint16_t(latIndex(k, latMin) >> s);
    box[1] = uint16_t(latIndex(k, latMax) >> s);
    box[2] = uint16_t(rIndex(k, rMin) >> s);
    box[3] = uint16_t(rIndex(k, rMax) >> s);
    // Lon: every brick when the cell touches the polar axis; otherwise the arc spanned by the
    // rectangle's corners (less than 180 degrees since the rectangle misses the axis).
    if (rhoMin <= 0.0) {
        box[4] = 0;
        box[5] = uint16_t(k.bricksLon);
        return;
    }
    const double centre = std::atan2(0.5 * (lo[1] + hi[1]), 0.5 * (lo[0] + hi[0])) * kRadToDeg;
    double dMin = 0, dMax = 0;
    for (int c = 0; c < 4; ++c) {
        const double x = (c & 1) ? hi[0] : lo[0], y = (c & 2) ? hi[1] : lo[1];
        double delta = std::atan2(y, x) * kRadToDeg - centre;
        delta -= 360.0 * std::round(delta / 360.0);
        dMin = std::min(dMin, delta);
        dMax = std::max(dMax, delta);
    }
    const int first = lonIndex(k, centre + dMin - kAnglePadDeg) >> s;
    const int last = lonIndex(k, centre + dMax + kAnglePadDeg) >> s;
    box[4] = uint16_t(first);
    box[5] = uint16_t((last - first + k.bricksLon) % k.bricksLon + 1);
}

std::shared_ptr<const SkipGridGeometry> buildGeometry(const kernel::KernelParams& k, const grid::BrickLayout& bricks,
                                                      float cellKm)
{
    auto g = std::make_shared<SkipGridGeometry>();
    const double extent = double(k.rOuterKm) + 1.0;
    g->n = std::clamp(int(std::ceil(2.0 * extent / double(cellKm))), 4, 256);
    g->cellKm = float(2.0 * extent / double(g->n));
    g->originKm = float(-extent);
    g->bricksLat = int(bricks.count[0]);
    g->bricksR = int(bricks.count[1]);
    g->bricksLon = int(bricks.count[2]);
    const int n = g->n;
    const size_t cells = size_t(n) * size_t(n) * size_t(n);
    g->kind.assign(cells, SkipGridGeometry::None);
    g->box.assign(6 * cells, 0);
    tbb::parallel_for(tbb::blocked_range<int>(0, n), [&](const tbb::blocked_range<int>& zs) {
        for (int z = zs.begin(); z != zs.end(); ++z)
            for (int y = 0; y < n; ++y)
                for (int x = 0; x < n; ++x) {
                    const int i[3] = {x, y, z};
                    double lo[3], hi[3];
                    for (int a = 0; a < 3; ++a) {
                        lo[a] = double(g->originKm) + double(i[a]) * double(g->cellKm) - double(kSkipCellPadKm);
                        hi[a] = double(g->originKm) + double(i[a] + 1) * double(g->cellKm) + double(kSkipCellPadKm);
                    }
                    const size_t c = (size_t(z) * size_t(n) + size_t(y)) * size_t(n) + size_t(x);
                    classifyCell(k, lo, hi, g->kind[c], &g->box[6 * c]);
                }
    });
    return g;
}

uint64_t hashGrid(const grid::SphericalGrid& grid, const grid::BrickLayout& bricks, float cellKm)
{
    uint64_t h = 1469598103934665603ull;
    auto mix = [&](const void* p, size_t bytes) {
        const auto* b = static_cast<const unsigned char*>(p);
        for (size_t i = 0; i < bytes; ++i)
            h = (h ^ b[i]) * 1099511628211ull;
    };
    for (const auto* axis : {&grid.latDeg, &grid.rKm, &grid.lonDeg}) {
        const size_t n = axis->size();
        mix(&n, sizeof n);
        mix(axis->data(), n * sizeof(double));
    }
    mix(&bricks.size, sizeof bricks.size);
    mix(&cellKm, sizeof cellKm);
    return h;
}

}  // namespace

std::shared_ptr<const SkipGridGeometry> skipGridGeometry(const grid::SphericalGrid& grid, const grid::BrickLayout& bricks,
                                                         const kernel::KernelParams& gridPart, float cellKm)
{
    // A few recent grids (a dataset's levels); building one at full resolution takes tens of ms.
    static std::mutex mutex;
    static std::vector<std::pair<uint64_t, std::shared_ptr<const SkipGridGeometry>>> cache;
    const uint64_t key = hashGrid(grid, bricks, cellKm);
    {
        std::lock_guard lock(mutex);
        for (auto it = cache.begin(); it != cache.end(); ++it)
            if (it->first == key) {
                auto found = it->second;
                cache.erase(it);
                cache.emplace_back(key, found);
                return found;
            }
    }
    auto built = buildGeometry(gridPart, bricks, cellKm);
    std::lock_guard lock(mutex);
    if (cache.size() >= 6)
        cache.erase(cache.begin());
    cache.emplace_back(key, built);
    return built;
}

void skipGridDistance(const SkipGridGeometry& g, const std::vector<int32_t>& brickActive, std::vector<uint8_t>& distance)
{
    // Prefix sums of the active flags with the lon axis doubled, so a cyclic lon range is one box.
    const int A = g.bricksLat, R = g.bricksR, L = g.bricksLon, L2 = 2 * L;
    const size_t sa = size_t(R + 1) * size_t(L2 + 1), sr = size_t(L2 + 1);
    std::vector<int32_t> sum(size_t(A + 1) * sa, 0);
    for (int a = 0; a < A; ++a)
        for (int r = 0; r < R; ++r)
            for (int l = 0; l < L2; ++l) {
                const size_t i = size_t(a + 1) * sa + size_t(r + 1) * sr + size_t(l + 1);
                const int32_t v = brickActive[(size_t(a) * size_t(R) + size_t(r)) * size_t(L) + size_t(l % L)] != 0;
                sum[i] = v + sum[i - sa] + sum[i - sr] + sum[i - 1] - sum[i - sa - sr] - sum[i - sa - 1] -
                         sum[i - sr - 1] + sum[i - sa - sr - 1];
            }
    auto anyActive = [&](const uint16_t* b) {
        const size_t a0 = b[0], a1 = size_t(b[1]) + 1, r0 = b[2], r1 = size_t(b[3]) + 1, l0 = b[4], l1 = size_t(b[4]) + b[5];
        const int64_t s = int64_t(sum[a1 * sa + r1 * sr + l1]) - sum[a0 * sa + r1 * sr + l1] - sum[a1 * sa + r0 * sr + l1] -
                          sum[a1 * sa + r1 * sr + l0] + sum[a0 * sa + r0 * sr + l1] + sum[a0 * sa + r1 * sr + l0] +
                          sum[a1 * sa + r0 * sr + l0] - sum[a0 * sa + r0 * sr + l0];
        return s > 0;
    };
    const int n = g.n;
    const size_t cells = g.kind.size();
    distance.resize(cells);
    tbb::parallel_for(tbb::blocked_range<size_t>(0, cells, 4096), [&](const tbb::blocked_range<size_t>& range) {
        for (size_t c = range.begin(); c != range.end(); ++c) {
            const uint8_t kind = g.kind[c];
            const bool occupied = kind == SkipGridGeometry::Always || (kind == SkipGridGeometry::Box && anyActive(&g.box[6 * c]));
            distance[c] = occupied ? 0 : 255;
        }
    });

    // Chebyshev distance by the two-pass chamfer transform with the 3x3x3 unit mask: a forward
    // raster pass over the 13 neighbours already visited, then a backward pass over the other 13.
    std::vector<uint8_t> neighbourMin(static_cast<size_t>(n));
    auto pass = [&](bool forward) {
        const int step = forward ? -1 : 1;  // direction of the already visited rows
        for (int zi = 0; zi < n; ++zi) {
            const int z = forward ? zi : n - 1 - zi;
            for (int yi = 0; yi < n; ++yi) {
                const int y = forward ? yi : n - 1 - yi;
                uint8_t* row = &distance[(size_t(z) * size_t(n) + size_t(y)) * size_t(n)];
                std::fill(neighbourMin.begin(), neighbourMin.end(), uint8_t(255));
                auto takeRow = [&](int zz, int yy) {
                    if (zz < 0 || zz >= n || yy < 0 || yy >= n)
                        return;
                    const uint8_t* q = &distance[(size_t(zz) * size_t(n) + size_t(yy)) * size_t(n)];
                    neighbourMin[0] = std::min({neighbourMin[0], q[0], q[1]});
                    for (int x = 1; x + 1 < n; ++x)
                        neighbourMin[size_t(x)] = std::min({neighbourMin[size_t(x)], q[x - 1], q[x], q[x + 1]});
                    neighbourMin[size_t(n - 1)] = std::min({neighbourMin[size_t(n - 1)], q[n - 2], q[n - 1]});
                };
                takeRow(z, y + step);
                for (int dy = -1; dy <= 1; ++dy)
                    takeRow(z + step, y + dy);
                auto relax = [&](int x, int prev) {
                    int v = std::min<int>(row[x], neighbourMin[size_t(x)] + 1);
                    if (prev >= 0)
                        v = std::min<int>(v, row[prev] + 1);
                    row[x] = uint8_t(std::min(v, 255));
                };
                if (forward)
                    for (int x = 0; x < n; ++x)
                        relax(x, x - 1);
                else
                    for (int x = n - 1; x >= 0; --x)
                        relax(x, x + 1 < n ? x + 1 : -1);
            }
        }
    };
    pass(true);
    pass(false);
}

}  // namespace raypc::render
