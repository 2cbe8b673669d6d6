#include "data/critical_points.h"

#include "core/error.h"

#include <tbb/enumerable_thread_specific.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <array>
#include <bit>
#include <cmath>

namespace raypc {
namespace {

constexpr int kNeighbours = 14;

struct Offset {
    int lat, r, lon;
};

// The Freudenthal neighbours: d and -d for d in {0,1}^3 \ {0}.
constexpr std::array<Offset, kNeighbours> kOffsets = {{
    {0, 0, 1}, {0, 1, 0}, {0, 1, 1}, {1, 0, 0}, {1, 0, 1}, {1, 1, 0}, {1, 1, 1},
    {0, 0, -1}, {0, -1, 0}, {0, -1, -1}, {-1, 0, 0}, {-1, 0, -1}, {-1, -1, 0}, {-1, -1, -1},
}};

// The link of an interior vertex as a graph on its 14 neighbours, plus its triangles, and the
// number of connected components of every induced subgraph (2^14 masks). Boundary links are
// induced subgraphs of the interior one (a triangle (v, a, b) exists iff a and b are in the grid),
// so one table serves every vertex.
struct LinkTables {
    std::array<uint16_t, kNeighbours> adjacency{};  // bit b of adjacency[a]: a-b is a link edge
    std::vector<std::array<int, 3>> triangles;
    std::vector<uint8_t> components = std::vector<uint8_t>(1u << kNeighbours);

    LinkTables()
    {
        auto isOffset = [](int dl, int dr, int dn) {
            for (const auto& o : kOffsets)
                if (o.lat == dl && o.r == dr && o.lon == dn)
                    return true;
            return false;
        };
        for (int a = 0; a < kNeighbours; ++a)
            for (int b = 0; b < kNeighbours; ++b)
                if (a != b && isOffset(kOffsets[b].lat - kOffsets[a].lat, kOffsets[b].r - kOffsets[a].r,
                                       kOffsets[b].lon - kOffsets[a].lon))
                    adjacency[a] |= uint16_t(1u << b);
        for (int a = 0; a < kNeighbours; ++a)
            for (int b = a + 1; b < kNeighbours; ++b)
                for (int c = b + 1; c < kNeighbours; ++c)
                    if ((adjacency[a] >> b & 1) && (adjacency[a] >> c & 1) && (adjacency[b] >> c & 1))
                        triangles.push_back({a, b, c});
        for (uint32_t mask = 0; mask < components.size(); ++mask) {
            uint32_t left = mask;
            int count = 0;
            while (left) {
                // Flood one component from its lowest vertex.
                uint32_t frontier = left & (~left + 1), seen = 0;
                while (frontier) {
                    seen |= frontier;
                    uint32_t next = 0;
                    for (uint32_t f = frontier; f; f &= f - 1)
                        next |= adjacency[std::countr_zero(f)];
                    frontier = next & mask & ~seen;
                }
                left &= ~seen;
                ++count;
            }
            components[mask] = static_cast<uint8_t>(count);
        }
    }
};

const LinkTables& linkTables()
{
    static const LinkTables tables;
    return tables;
}

void checkInput(const SphericalGrid& grid, std::span<const float> values)
{
    if (values.size() != grid.cellCount())
        fail("critical points: {} values for a grid of {} points", values.size(), grid.cellCount());
    if (grid.nLat() < 2 || grid.nR() < 2 || grid.nLon() < 3)
        fail("critical points: grid {}x{}x{} (lat x r x lon) is too small, need at least 2x2x3", grid.nLat(),
             grid.nR(), grid.nLon());
}

// Masks of the neighbours inside the grid and of those below the vertex (value, index) in SoS order.
struct VertexMasks {
    uint32_t valid = 0, lower = 0;
};

inline VertexMasks vertexMasks(const SphericalGrid& g, const float* values, size_t iLat, size_t iR, size_t iLon)
{
    const size_t nLat = g.nLat(), nR = g.nR(), nLon = g.nLon();
    const size_t self = g.index(iLat, iR, iLon);
    const float v = values[self];
    VertexMasks m;
    for (int k = 0; k < kNeighbours; ++k) {
        const auto& o = kOffsets[k];
        const ptrdiff_t a = static_cast<ptrdiff_t>(iLat) + o.lat, b = static_cast<ptrdiff_t>(iR) + o.r;
        if (a < 0 || a >= static_cast<ptrdiff_t>(nLat) || b < 0 || b >= static_cast<ptrdiff_t>(nR))
            continue;
        // Lon wraps across the seam.
        const size_t c = o.lon < 0 ? (iLon == 0 ? nLon - 1 : iLon - 1) : (o.lon > 0 ? (iLon + 1 == nLon ? 0 : iLon + 1) : iLon);
        const size_t n = (static_cast<size_t>(a) * nR + static_cast<size_t>(b)) * nLon + c;
        const float w = values[n];
        m.valid |= 1u << k;
        if (w < v || (w == v && n < self))  // Simulation of Simplicity by index
            m.lower |= 1u << k;
    }
    return m;
}

CriticalKind classify(int lower, int upper, bool& critical)
{
    critical = true;
    if (lower == 0)
        return CriticalKind::Minimum;
    if (upper == 0)
        return CriticalKind::Maximum;
    if (lower == 1 && upper == 1) {
        critical = false;
        return CriticalKind::Minimum;
    }
    if (upper == 1)
        return CriticalKind::Saddle1;
    if (lower == 1)
        return CriticalKind::Saddle2;
    return CriticalKind::MultiSaddle;
}

}  // namespace

const char* criticalKindName(CriticalKind kind)
{
    switch (kind) {
    case CriticalKind::Minimum: return "minimum";
    case CriticalKind::Saddle1: return "1-saddle";
    case CriticalKind::Saddle2: return "2-saddle";
    case CriticalKind::Maximum: return "maximum";
    case CriticalKind::MultiSaddle: return "multi-saddle";
    }
    return "?";
}

std::vector<CriticalPoint> findCriticalPoints(const SphericalGrid& grid, std::span<const float> values)
{
    checkInput(grid, values);
    const auto& tables = linkTables();
    tbb::enumerable_thread_specific<std::vector<CriticalPoint>> found;
    tbb::parallel_for(size_t(0), grid.nLat(), [&](size_t iLat) {
        auto& out = found.local();
        for (size_t iR = 0; iR < grid.nR(); ++iR)
            for (size_t iLon = 0; iLon < grid.nLon(); ++iLon) {
                const VertexMasks m = vertexMasks(grid, values.data(), iLat, iR, iLon);
                const int lower = tables.components[m.lower];
                const int upper = tables.components[m.valid & ~m.lower];
                bool critical = false;
                const CriticalKind kind = classify(lower, upper, critical);
                if (!critical)
                    continue;
                CriticalPoint p;
                p.index = grid.index(iLat, iR, iLon);
                p.kind = kind;
                p.value = values[p.index];
                p.lowerComponents = static_cast<uint8_t>(lower);
                p.upperComponents = static_cast<uint8_t>(upper);
                p.latDeg = grid.latDeg[iLat];
                p.rKm = grid.rKm[iR];
                p.lonDeg = grid.lonDeg[iLon];
                out.push_back(p);
            }
    });
    std::vector<CriticalPoint> all;
    for (auto& part : found)
        all.insert(all.end(), part.begin(), part.end());
    std::sort(all.begin(), all.end(), [](const auto& a, const auto& b) { return a.index < b.index; });
    return all;
}

double significanceThreshold(const CriticalPointFilter& filter, double maxAbs)
{
    return std::max(filter.minAbsValue, filter.minFractionOfMaxAbs * maxAbs);
}

std::vector<CriticalPoint> selectSignificant(std::vector<CriticalPoint> points, double maxAbs,
                                             const CriticalPointFilter& filter)
{
    const double threshold = significanceThreshold(filter, maxAbs);
    std::erase_if(points, [&](const CriticalPoint& p) {
        switch (p.kind) {
        case CriticalKind::Maximum: return !(p.value >= threshold);
        case CriticalKind::Minimum: return !(p.value <= -threshold);
        default: return !filter.saddles || !(std::abs(p.value) >= threshold);
        }
    });
    std::sort(points.begin(), points.end(), [](const CriticalPoint& a, const CriticalPoint& b) {
        const float x = std::abs(a.value), y = std::abs(b.value);
        return x != y ? x > y : a.index < b.index;
    });
    if (points.size() > filter.maxCount)
        points.resize(filter.maxCount);
    return points;
}

int lowerStarEulerContribution(const SphericalGrid& grid, std::span<const float> values, size_t index)
{
    checkInput(grid, values);
    const auto& tables = linkTables();
    const size_t iLon = index % grid.nLon(), iR = (index / grid.nLon()) % grid.nR(),
                 iLat = index / (grid.nLon() * grid.nR());
    const uint32_t lower = vertexMasks(grid, values.data(), iLat, iR, iLon).lower;
    int vertices = std::popcount(lower), edges = 0, triangles = 0;
    for (int a = 0; a < kNeighbours; ++a)
        if (lower >> a & 1)
            edges += std::popcount(uint32_t(tables.adjacency[a]) & lower);
    edges /= 2;
    for (const auto& t : tables.triangles)
        if ((lower >> t[0] & 1) && (lower >> t[1] & 1) && (lower >> t[2] & 1))
            ++triangles;
    return 1 - (vertices - edges + triangles);
}

}  // namespace raypc
