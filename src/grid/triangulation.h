// The triangulation of the spherical grid that critical points and persistence pairs are defined
// on (critical_points.h, persistence.h): one place, so that both see the same links.
//
// Freudenthal (Kuhn) triangulation of the index space (iLat, iR, iLon): each unit cube is cut
// into 6 tetrahedra along its main diagonal, so an interior vertex has 14 neighbours, the offsets
// d and -d for every d in {0,1}^3 \ {0}. Two neighbours a, b of v span a triangle (v, a, b)
// exactly when b - a is itself a neighbour offset (the triangulation is a flag complex), which
// gives the link's edges.
//
// Boundaries: lon is periodic (neighbours wrap across the seam); the first and last radius and
// the outermost lat rows are boundaries (no virtual pole vertex; a boundary vertex's link is the
// part of the interior link inside the grid). The domain is [lat rows] x [radii] x circle.
// Order: Simulation of Simplicity by index (Edelsbrunner & Mücke 1990): u is below v when
// (value_u, index_u) < (value_v, index_v), so no two vertices compare equal.
//
// Thread safety: the tables are built once (thread-safe static) and immutable.
#pragma once

#include "grid/grid.h"

#include <array>
#include <cstddef>
#include <cstdint>
#include <vector>

namespace raypc::grid::triangulation {

inline constexpr int kLinkSize = 14;

struct Offset {
    int lat, r, lon;
};

// The Freudenthal neighbours: d and -d for d in {0,1}^3 \ {0}; bit k of a link mask is kOffsets[k].
inline constexpr std::array<Offset, kLinkSize> kOffsets = {{
    {0, 0, 1}, {0, 1, 0}, {0, 1, 1}, {1, 0, 0}, {1, 0, 1}, {1, 1, 0}, {1, 1, 1},
    {0, 0, -1}, {0, -1, 0}, {0, -1, -1}, {-1, 0, 0}, {-1, 0, -1}, {-1, -1, 0}, {-1, -1, -1},
}};

// The link of an interior vertex as a graph on its 14 neighbours, its triangles, and the number
// of connected components of every induced subgraph (2^14 masks). Boundary links are induced
// subgraphs of the interior one (a triangle (v, a, b) exists iff a and b are in the grid), so one
// table serves every vertex.
struct LinkTables {
    std::array<uint16_t, kLinkSize> adjacency{};  // bit b of adjacency[a]: a-b is a link edge
    std::vector<std::array<int, 3>> triangles;
    std::vector<uint8_t> components = std::vector<uint8_t>(1u << kLinkSize);

    LinkTables();
    // The connected components of the link subgraph induced by `mask`, as masks, lowest bit first;
    // returns how many were written to `out`.
    int componentMasks(uint32_t mask, std::array<uint32_t, kLinkSize>& out) const;
};

const LinkTables& linkTables();

// Masks of the neighbours inside the grid and of those below the vertex in SoS order; with
// `neighbours`, also the grid index of every neighbour inside the grid (entry k for bit k).
struct VertexMasks {
    uint32_t valid = 0, lower = 0;
};

inline VertexMasks vertexMasks(const SphericalGrid& g, const float* values, size_t iLat, size_t iR, size_t iLon,
                               size_t* neighbours = nullptr)
{
    const size_t nLat = g.nLat(), nR = g.nR(), nLon = g.nLon();
    const size_t self = g.index(iLat, iR, iLon);
    const float v = values[self];
    VertexMasks m;
    for (int k = 0; k < kLinkSize; ++k) {
        const auto& o = kOffsets[k];
        const ptrdiff_t a = static_cast<ptrdiff_t>(iLat) + o.lat, b = static_cast<ptrdiff_t>(iR) + o.r;
        if (a < 0 || a >= static_cast<ptrdiff_t>(nLat) || b < 0 || b >= static_cast<ptrdiff_t>(nR))
            continue;
        // Lon wraps across the seam.
        const size_t c = o.lon < 0 ? (iLon == 0 ? nLon - 1 : iLon - 1)
                                   : (o.lon > 0 ? (iLon + 1 == nLon ? 0 : iLon + 1) : iLon);
        const size_t n = (static_cast<size_t>(a) * nR + static_cast<size_t>(b)) * nLon + c;
        const float w = values[n];
        m.valid |= 1u << k;
        if (w < v || (w == v && n < self))  // Simulation of Simplicity by index
            m.lower |= 1u << k;
        if (neighbours)
            neighbours[k] = n;
    }
    return m;
}

// True when vertex a is below vertex b in SoS order.
inline bool below(const float* values, size_t a, size_t b)
{
    return values[a] < values[b] || (values[a] == values[b] && a < b);
}

// Throws raypc::Error naming `what` when `valueCount` differs from the grid's or the grid has
// fewer than 2 lat rows, 2 radii or 3 lon columns (a smaller grid has no such triangulation).
void checkTriangulable(const SphericalGrid& grid, size_t valueCount, const char* what);

}  // namespace raypc::grid::triangulation
