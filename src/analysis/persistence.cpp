#include "analysis/persistence.h"

#include "core/error.h"
#include "core/spherical.h"
#include "core/strings.h"
#include "grid/triangulation.h"

#include <tbb/blocked_range.h>
#include <tbb/enumerable_thread_specific.h>
#include <tbb/parallel_invoke.h>
#include <tbb/parallel_for.h>

#include <fmt/format.h>

#include <algorithm>
#include <bit>
#include <cmath>
#include <limits>
#include <unordered_map>

namespace raypc::analysis {
namespace {

using grid::triangulation::kLinkSize;
using grid::triangulation::linkTables;

// A vertex whose lower (or upper) link has several components: where sublevel (superlevel)
// components may meet.
struct Saddle {
    uint32_t index;
    uint8_t lowerComponents, upperComponents;
};

// Union-find root with path halving. Roots are extrema: parent[x] == x.
inline uint32_t findRoot(std::vector<uint32_t>& parent, uint32_t x)
{
    while (parent[x] != x) {
        parent[x] = parent[parent[x]];
        x = parent[x];
    }
    return x;
}

// One merge-tree sweep. `Up` = false: sublevel sets, saddles in increasing order, the roots of
// `parent` are minima and a lower-link component's representative is any of its vertices.
// `Up` = true: superlevel sets, everything mirrored. Appends one pair per dying extremum.
template <bool Up>
void sweep(const grid::SphericalGrid& grid, const float* values, std::vector<Saddle>& saddles, std::vector<uint32_t>& parent,
           std::vector<PersistencePair>& pairs)
{
    // SoS order along the sweep: "earlier" is lower sweeping up, higher sweeping down.
    auto earlier = [values](size_t a, size_t b) {
        return Up ? grid::triangulation::below(values, b, a) : grid::triangulation::below(values, a, b);
    };
    std::sort(saddles.begin(), saddles.end(),
              [&](const Saddle& a, const Saddle& b) { return earlier(a.index, b.index); });
    const auto& tables = linkTables();
    const size_t nLon = grid.nLon(), nR = grid.nR();
    std::array<size_t, kLinkSize> neighbours{};
    std::array<uint32_t, kLinkSize> components{};
    std::array<uint32_t, kLinkSize> roots{};
    for (const Saddle& s : saddles) {
        const size_t iLon = s.index % nLon, iR = (s.index / nLon) % nR, iLat = s.index / (nLon * nR);
        const auto m = grid::triangulation::vertexMasks(grid, values, iLat, iR, iLon, neighbours.data());
        const uint32_t side = Up ? (m.valid & ~m.lower) : m.lower;
        const int count = tables.componentMasks(side, components);
        // The distinct sweep components that the link components belong to.
        int distinct = 0;
        for (int c = 0; c < count; ++c) {
            const uint32_t root = findRoot(parent, static_cast<uint32_t>(neighbours[std::countr_zero(components[c])]));
            if (std::find(roots.begin(), roots.begin() + distinct, root) == roots.begin() + distinct)
                roots[distinct++] = root;
        }
        if (distinct < 2)
            continue;  // the link components were already joined: a tunnel, not a merge
        // Elder rule: the component with the earliest extremum lives on, the others die here.
        const uint32_t elder = *std::min_element(roots.begin(), roots.begin() + distinct, earlier);
        const CriticalKind saddleKind = classifyLink(s.lowerComponents, s.upperComponents).value();
        for (int k = 0; k < distinct; ++k) {
            if (roots[k] == elder)
                continue;
            PersistencePair p;
            p.kind = Up ? PairKind::SaddleMaximum : PairKind::MinimumSaddle;
            p.birthIndex = Up ? s.index : roots[k];
            p.deathIndex = Up ? roots[k] : s.index;
            p.birthKind = Up ? saddleKind : CriticalKind::Minimum;
            p.deathKind = Up ? CriticalKind::Maximum : saddleKind;
            p.birth = values[p.birthIndex];
            p.death = values[p.deathIndex];
            pairs.push_back(p);
            parent[roots[k]] = elder;
        }
    }
}

}  // namespace

const char* pairKindName(PairKind kind)
{
    switch (kind) {
    case PairKind::MinimumSaddle: return "minimum-saddle";
    case PairKind::SaddleMaximum: return "saddle-maximum";
    case PairKind::Global: return "global";
    }
    return "?";
}

namespace {

// Every neighbour of a vertex inside the grid: its link mask off the boundaries.
constexpr uint32_t kAllNeighbours = (1u << kLinkSize) - 1;

// What pairsAndPoints needs of the vertices of one row (iLat, iR) that touch neither a boundary nor
// the seam (0 < iLat < nLat − 1, 0 < iR < nR − 1, 0 < iLon < nLon − 1), the same bits as
// vertexMasks and the searches over its masks give each alone: there every neighbour is inside the
// grid at a fixed index offset, below the vertex in index exactly when that offset is negative, so
// the row is worked neighbour by neighbour in loops over lon the compiler vectorises, not vertex by
// vertex through bounds checks and data-dependent branches.
struct InteriorRow {
    std::vector<uint32_t> lower;                       // vertexMasks' lower mask; entries 1 … nLon − 2
    std::vector<int32_t> lowestOffset, highestOffset;  // the lowest lower and highest upper neighbour − the vertex
    std::vector<float> lowest, highest;                // their values

    explicit InteriorRow(size_t nLon)
        : lower(nLon), lowestOffset(nLon), highestOffset(nLon), lowest(nLon), highest(nLon)
    {
    }

    void compute(const grid::SphericalGrid& grid, const float* values, size_t iLat, size_t iR)
    {
        const size_t nR = grid.nR(), nLon = grid.nLon();
        const float* row = values + grid.index(iLat, iR, 0);
        for (size_t i = 1; i + 1 < nLon; ++i) {
            lower[i] = 0;
            lowestOffset[i] = highestOffset[i] = 0;
            lowest[i] = highest[i] = row[i];
        }
        // Neighbours in vertexMasks' order (bit k), which the searches follow too: a lower
        // neighbour replaces the lowest so far when below it, an upper one the highest so far when
        // above it (Simulation of Simplicity: by value, then by index, i.e. by offset).
        for (int k = 0; k < kLinkSize; ++k) {
            const auto& o = grid::triangulation::kOffsets[size_t(k)];
            const int32_t offset = int32_t((ptrdiff_t(o.lat) * ptrdiff_t(nR) + o.r) * ptrdiff_t(nLon) + o.lon);
            const float* n = row + offset;
            if (offset > 0)
                neighbour<true>(row, n, k, offset, nLon);
            else
                neighbour<false>(row, n, k, offset, nLon);
        }
    }

private:
    // One neighbour (bit k at `offset`) of every vertex of the row; `After`: offset > 0. The tests
    // are combined with & and |, not && and ||, so that the loop has no branch to vectorise around.
    template <bool After>
    void neighbour(const float* __restrict row, const float* __restrict n, int k, int32_t offset, size_t nLon)
    {
        uint32_t* __restrict lowerOf = lower.data();
        float* __restrict lo = lowest.data();
        float* __restrict hi = highest.data();
        int32_t* __restrict loOffset = lowestOffset.data();
        int32_t* __restrict hiOffset = highestOffset.data();
        for (size_t i = 1; i + 1 < nLon; ++i) {
            const float x = row[i], w = n[i];
            // vertexMasks: w < x, or w == x and the neighbour's index is the smaller.
            const bool isLower = After ? w < x : ((w < x) | (w == x));
            lowerOf[i] |= uint32_t(isLower) << k;
            const bool newLowest = isLower & ((w < lo[i]) | ((w == lo[i]) & (offset < loOffset[i])));
            const bool isUpper = !isLower;
            const bool newHighest = isUpper & ((hi[i] < w) | ((hi[i] == w) & (hiOffset[i] < offset)));
            lo[i] = newLowest ? w : lo[i];
            loOffset[i] = newLowest ? offset : loOffset[i];
            hi[i] = newHighest ? w : hi[i];
            hiOffset[i] = newHighest ? offset : hiOffset[i];
        }
    }
};

// persistencePairs, and with `points` findCriticalPoints too, from the one pass over the vertices'
// links both need.
std::vector<PersistencePair> pairsAndPoints(const grid::SphericalGrid& grid, std::span<const float> values,
                                            std::vector<CriticalPoint>* points)
{
    grid::triangulation::checkTriangulable(grid, values.size(), "persistence");
    if (grid.cellCount() >= std::numeric_limits<uint32_t>::max())
        fail("persistence: grid of {} points, at most {} are supported", grid.cellCount(),
             std::numeric_limits<uint32_t>::max() - 1);
    const float* v = values.data();
    const auto& tables = linkTables();

    // Descending (ascending) forests: each vertex points at its lowest lower (highest upper)
    // neighbour; extrema point at themselves. Saddles are collected for the sweeps.
    std::vector<uint32_t> down(grid.cellCount()), up(grid.cellCount());
    tbb::enumerable_thread_specific<std::vector<Saddle>> joinsLocal, splitsLocal;
    tbb::enumerable_thread_specific<std::vector<CriticalPoint>> pointsLocal;
    const size_t nLat = grid.nLat(), nR = grid.nR(), nLon = grid.nLon();
    tbb::parallel_for(tbb::blocked_range<size_t>(0, nLat), [&](const tbb::blocked_range<size_t>& rows) {
        auto& joins = joinsLocal.local();
        auto& splits = splitsLocal.local();
        auto& found = pointsLocal.local();
        std::array<size_t, kLinkSize> nb{};
        InteriorRow interior(nLon);
        // A vertex's forests' pointers, saddles and critical point, from its link's masks and its
        // lowest lower and highest upper neighbour (itself when there is none).
        auto add = [&](size_t iLat, size_t iR, size_t iLon, uint32_t lower, uint32_t upper, size_t lowest,
                       size_t highest) {
            const size_t self = grid.index(iLat, iR, iLon);
            down[self] = static_cast<uint32_t>(lowest);
            up[self] = static_cast<uint32_t>(highest);
            const uint8_t cl = tables.components[lower], cu = tables.components[upper];
            if (cl >= 2)
                joins.push_back({static_cast<uint32_t>(self), cl, cu});
            if (cu >= 2)
                splits.push_back({static_cast<uint32_t>(self), cl, cu});
            if (points)
                if (const auto kind = classifyLink(cl, cu)) {
                    CriticalPoint p;
                    p.index = self;
                    p.kind = *kind;
                    p.value = v[self];
                    p.lowerComponents = cl;
                    p.upperComponents = cu;
                    p.latDeg = grid.latDeg[iLat];
                    p.rKm = grid.rKm[iR];
                    p.lonDeg = grid.lonDeg[iLon];
                    found.push_back(p);
                }
        };
        // Any vertex: its link as vertexMasks finds it (boundaries, the seam).
        auto addAny = [&](size_t iLat, size_t iR, size_t iLon) {
            const size_t self = grid.index(iLat, iR, iLon);
            const auto m = grid::triangulation::vertexMasks(grid, v, iLat, iR, iLon, nb.data());
            const uint32_t lower = m.lower, upper = m.valid & ~m.lower;
            size_t lowest = self, highest = self;
            for (uint32_t bits = lower; bits; bits &= bits - 1) {
                const size_t n = nb[std::countr_zero(bits)];
                if (grid::triangulation::below(v, n, lowest))
                    lowest = n;
            }
            for (uint32_t bits = upper; bits; bits &= bits - 1) {
                const size_t n = nb[std::countr_zero(bits)];
                if (grid::triangulation::below(v, highest, n))
                    highest = n;
            }
            add(iLat, iR, iLon, lower, upper, lowest, highest);
        };
        for (size_t iLat = rows.begin(); iLat != rows.end(); ++iLat)
            for (size_t iR = 0; iR < nR; ++iR) {
                if (iLat == 0 || iLat + 1 == nLat || iR == 0 || iR + 1 == nR) {
                    for (size_t iLon = 0; iLon < nLon; ++iLon)
                        addAny(iLat, iR, iLon);
                    continue;
                }
                interior.compute(grid, v, iLat, iR);
                addAny(iLat, iR, 0);
                const size_t rowStart = grid.index(iLat, iR, 0);
                for (size_t iLon = 1; iLon + 1 < nLon; ++iLon)
                    add(iLat, iR, iLon, interior.lower[iLon], kAllNeighbours & ~interior.lower[iLon],
                        size_t(ptrdiff_t(rowStart + iLon) + interior.lowestOffset[iLon]),
                        size_t(ptrdiff_t(rowStart + iLon) + interior.highestOffset[iLon]));
                addAny(iLat, iR, nLon - 1);
            }
    });
    if (points) {
        points->clear();
        for (auto& part : pointsLocal)
            points->insert(points->end(), part.begin(), part.end());
        std::sort(points->begin(), points->end(), [](const auto& a, const auto& b) { return a.index < b.index; });
    }
    std::vector<Saddle> joins, splits;
    for (auto& part : joinsLocal)
        joins.insert(joins.end(), part.begin(), part.end());
    for (auto& part : splitsLocal)
        splits.insert(splits.end(), part.begin(), part.end());

    // The two sweeps touch disjoint forests: run them side by side.
    std::vector<PersistencePair> minPairs, maxPairs;
    tbb::parallel_invoke([&] { sweep<false>(grid, v, joins, down, minPairs); },
                         [&] { sweep<true>(grid, v, splits, up, maxPairs); });

    // The essential class: what survives both sweeps, the global minimum and maximum.
    PersistencePair global;
    global.kind = PairKind::Global;
    global.birthIndex = findRoot(down, 0);
    global.deathIndex = findRoot(up, 0);
    global.birthKind = CriticalKind::Minimum;
    global.deathKind = CriticalKind::Maximum;
    global.birth = v[global.birthIndex];
    global.death = v[global.deathIndex];

    std::vector<PersistencePair> pairs = std::move(minPairs);
    pairs.insert(pairs.end(), maxPairs.begin(), maxPairs.end());
    pairs.push_back(global);
    std::sort(pairs.begin(), pairs.end(), [](const PersistencePair& a, const PersistencePair& b) {
        const double pa = a.persistence(), pb = b.persistence();
        if (pa != pb)
            return pa > pb;
        if (a.kind != b.kind)
            return a.kind < b.kind;
        return a.extremumIndex() < b.extremumIndex();
    });
    return pairs;
}

}  // namespace

std::vector<PersistencePair> persistencePairs(const grid::SphericalGrid& grid, std::span<const float> values)
{
    return pairsAndPoints(grid, values, nullptr);
}

CriticalStructure criticalStructure(const grid::SphericalGrid& grid, std::span<const float> values)
{
    CriticalStructure out;
    out.pairs = pairsAndPoints(grid, values, &out.points);
    return out;
}

SeedSelection selectSeeds(const grid::SphericalGrid& grid, std::span<const float> values,
                          const std::vector<CriticalPoint>& all, const CriticalPointFilter& filter)
{
    checkCriticalPointFilter(filter);
    grid::triangulation::checkTriangulable(grid, values.size(), "seed selection");
    return selectSeedsFrom(grid, values, CriticalStructure{all, persistencePairs(grid, values)}, filter);
}

SeedSelection selectSeedsFrom(const grid::SphericalGrid& grid, std::span<const float> values,
                              const CriticalStructure& structure, const CriticalPointFilter& filter)
{
    checkCriticalPointFilter(filter);
    grid::triangulation::checkTriangulable(grid, values.size(), "seed selection");
    const std::vector<CriticalPoint>& all = structure.points;
    const std::vector<PersistencePair>& pairs = structure.pairs;
    SeedSelection out;
    if (filter.rule == SeedRule::Value) {
        double maxAbs = 0;
        for (const float x : values)
            maxAbs = std::max(maxAbs, std::abs(double(x)));
        out.seeds = selectSignificant(all, maxAbs, filter);
        out.threshold = significanceThreshold(filter, maxAbs);
        // The seeds' persistence too (the pathlines' "seed persistence" attribute), so that a set
        // chosen by value can still be thresholded by persistence.
        std::unordered_map<size_t, double> largest;
        for (const auto& p : pairs)  // by decreasing persistence: the first met is the largest
            for (const size_t index : {p.birthIndex, p.deathIndex})
                largest.try_emplace(index, p.persistence());
        for (auto& s : out.seeds) {
            const auto it = largest.find(s.index);
            s.persistence = it == largest.end() ? 0.0 : it->second;
        }
        return out;
    }
    const PersistencePair& global =
        *std::find_if(pairs.begin(), pairs.end(), [](const PersistencePair& p) { return p.kind == PairKind::Global; });
    out.threshold = filter.persistenceIsFraction ? filter.minPersistence * global.persistence() : filter.minPersistence;
    // Pairs come by decreasing persistence, so a point in several pairs is first met with its
    // largest, and the first maxCount points met are the most persistent.
    auto add = [&](size_t index, double persistence) {
        if (out.seeds.size() >= filter.maxCount)
            return;
        for (const auto& s : out.seeds)
            if (s.index == index)
                return;
        const auto it = std::lower_bound(all.begin(), all.end(), index,
                                         [](const CriticalPoint& p, size_t i) { return p.index < i; });
        RAYPC_CHECK(it != all.end() && it->index == index);  // both sides classify by the same links
        out.seeds.push_back(*it);
        out.seeds.back().persistence = persistence;
    };
    for (const auto& p : pairs) {
        if (!(p.persistence() > out.threshold) || out.seeds.size() >= filter.maxCount)
            break;
        switch (p.kind) {
        case PairKind::Global:
            add(p.deathIndex, p.persistence());
            add(p.birthIndex, p.persistence());
            break;
        case PairKind::MinimumSaddle:
            add(p.birthIndex, p.persistence());
            if (filter.saddles)
                add(p.deathIndex, p.persistence());
            break;
        case PairKind::SaddleMaximum:
            add(p.deathIndex, p.persistence());
            if (filter.saddles)
                add(p.birthIndex, p.persistence());
            break;
        }
    }
    return out;
}

std::string persistenceDiagramCsv(const grid::SphericalGrid& grid, const std::vector<PersistencePair>& pairs,
                                  const std::string& units)
{
    const std::string u = units.empty() ? "" : " [" + units + "]";
    std::string out = csvQuote("kind") + "," + csvQuote("birth" + u) + "," + csvQuote("death" + u) + "," +
                      csvQuote("persistence" + u);
    for (const char* end : {"birth", "death"})
        out += fmt::format(",{0} kind,{0} lat [degrees_north],{0} lon [degrees_east],{0} radius [km],{0} x [km],"
                           "{0} y [km],{0} z [km]",
                           end);
    out += '\n';
    auto it = std::back_inserter(out);
    const size_t nLon = grid.nLon(), nR = grid.nR();
    for (const auto& p : pairs) {
        fmt::format_to(it, "{},{:.7g},{:.7g},{:.7g}", pairKindName(p.kind), p.birth, p.death, p.persistence());
        for (const auto& [index, kind] : {std::pair{p.birthIndex, p.birthKind}, std::pair{p.deathIndex, p.deathKind}}) {
            const double lat = grid.latDeg[index / (nLon * nR)], r = grid.rKm[(index / nLon) % nR],
                         lon = grid.lonDeg[index % nLon];
            const Vec3d x = sphericalToCartesianKm(lat, lon, r);
            fmt::format_to(it, ",{},{:.7g},{:.7g},{:.7g},{:.7g},{:.7g},{:.7g}", criticalKindName(kind), lat, lon, r,
                           x.x, x.y, x.z);
        }
        out += '\n';
    }
    return out;
}

}  // namespace raypc::analysis
