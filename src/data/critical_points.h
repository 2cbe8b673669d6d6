// Critical points of a scalar field on the spherical grid (minima, saddles, maxima), found by
// the piecewise-linear rule of Banchoff / Edelsbrunner et al. as TTK's ScalarFieldCriticalPoints
// applies it: a vertex is classified by the connected components of its lower and upper link.
//
// Triangulation: the Freudenthal (Kuhn) triangulation of the index-space grid (iLat, iR, iLon),
// each unit cube cut into 6 tetrahedra along its main diagonal, so an interior vertex has 14
// neighbours: the offsets d and -d for every d in {0,1}^3 \ {0}. Two neighbours a, b of v span
// a triangle (v, a, b) exactly when b - a is itself a neighbour offset (the triangulation is a
// flag complex), which gives the link's edges.
//
// Boundaries (docs/format.md, "Pathlines"):
//   - lon is periodic: neighbours wrap across the seam, so the seam is an ordinary place;
//   - r: the shell's inner and outer radii are boundaries; the link is its part inside the grid;
//   - poles: the outermost lat rows are treated like a boundary too (no virtual pole vertex), so
//     the triangulated domain is [lat rows] x [radii] x circle, a solid torus (Euler
//     characteristic 0). A feature centred on a pole shows up on the outermost row.
// Ties: Simulation of Simplicity (Edelsbrunner & Mücke 1990) by index: u is below v when
// (value_u, index_u) < (value_v, index_v), so every vertex is classified and no two compare equal.
//
// Classification from c- = #components of the lower link and c+ = #components of the upper link:
//   minimum (c- = 0), maximum (c+ = 0), regular (c- = c+ = 1), 1-saddle (c- > 1, c+ = 1),
//   2-saddle (c- = 1, c+ > 1), multi-saddle (c- > 1 and c+ > 1).
// On boundary vertices the link is a disk, not a sphere; the same rule applies (as in TTK), so an
// extremum on the shell's surface is reported like an interior one.
//
// Thread safety: pure functions; findCriticalPoints uses oneTBB over lat rows.
#pragma once

#include "data/grid.h"

#include <cstddef>
#include <cstdint>
#include <span>
#include <string>
#include <vector>

namespace raypc {

enum class CriticalKind : uint8_t { Minimum = 0, Saddle1 = 1, Saddle2 = 2, Maximum = 3, MultiSaddle = 4 };

// "minimum", "1-saddle", "2-saddle", "maximum", "multi-saddle".
const char* criticalKindName(CriticalKind kind);

struct CriticalPoint {
    size_t index = 0;  // grid index, canonical order
    CriticalKind kind = CriticalKind::Minimum;
    float value = 0;
    uint8_t lowerComponents = 0, upperComponents = 0;
    double latDeg = 0, lonDeg = 0, rKm = 0;  // the grid point's coordinates
};

// Every non-regular vertex of `values` (grid.cellCount() values, canonical order), sorted by
// index. NaN values are not expected (the reader rejects them). Throws raypc::Error when the
// sizes differ or the grid has fewer than 2 lat rows, 2 radii or 3 lon columns.
std::vector<CriticalPoint> findCriticalPoints(const SphericalGrid& grid, std::span<const float> values);

// Which critical points seed pathlines: the significant ones.
// A maximum needs value >= threshold, a minimum value <= -threshold, a saddle |value| >=
// threshold (temperature anomaly: hot upwellings, cold downwellings), where threshold =
// max(minAbsValue, minFractionOfMaxAbs * max|value| over the step). Then the `maxCount` with the
// largest |value| are kept (ties by index), so a noisy step cannot make thousands of seeds.
struct CriticalPointFilter {
    double minAbsValue = 0;             // in the field's units (K)
    double minFractionOfMaxAbs = 0.25;  // of the step's largest |value|
    size_t maxCount = 200;
    bool saddles = true;                // keep saddles (and multi-saddles) at all
};

// The threshold `filter` gives for a step whose largest |value| is `maxAbs`.
double significanceThreshold(const CriticalPointFilter& filter, double maxAbs);

// Applies `filter` to `points`; the result is ordered by decreasing |value| (ties by index).
std::vector<CriticalPoint> selectSignificant(std::vector<CriticalPoint> points, double maxAbs,
                                             const CriticalPointFilter& filter);

// 1 - χ(lower link of vertex `index`): the vertex's contribution to the Euler characteristic of
// the triangulated domain (each simplex counted at its highest vertex). Summed over all vertices
// it is 0 for this grid's solid torus, whatever the field: a test of the triangulation's links.
int lowerStarEulerContribution(const SphericalGrid& grid, std::span<const float> values, size_t index);

}  // namespace raypc
