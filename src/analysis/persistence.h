// Topological persistence of a scalar field on the spherical grid's triangulation
// (grid/triangulation.h, the same one critical_points.h classifies on), and the persistence-based
// choice of pathline seeds (docs/persistence.md).
//
// Pairs, as TTK's PersistenceDiagram reports them from its merge trees (FTM, Gueunet et al. 2019):
//   - minimum-saddle: sweeping up, a minimum starts a component of the sublevel set; where
//     components meet (a vertex with several lower-link components: a 1-saddle or multi-saddle),
//     the younger one (higher minimum) dies, paired with that saddle (the elder rule of
//     Edelsbrunner, Letscher & Zomorodian 2002);
//   - saddle-maximum: the same sweeping down over superlevel sets, maxima dying at 2-saddles or
//     multi-saddles;
//   - global: the global minimum's component never dies (the essential class); by TTK's convention
//     it is paired with the global maximum, persistence = the field's range.
// A pair's birth is its lower value, its death its higher one, persistence = death - birth >= 0
// (so a saddle-maximum pair is born at the saddle). There are (#minima - 1) minimum-saddle pairs,
// (#maxima - 1) saddle-maximum pairs and one global pair, with minima and maxima as
// findCriticalPoints counts them. 1-saddle/2-saddle pairs (the tunnels of 3D fields) are not
// computed: no seed rule needs them.
//
// Method: every non-minimum vertex points at its lowest lower neighbour; these descending
// forests reach the minima, and all lower neighbours of a vertex whose lower link is connected
// are already in one sublevel component (they are joined by link edges below it), so only the
// vertices with a disconnected lower link are swept in order, with union-find on the forest
// (the same reduction as the discrete Morse sandwich of Guillou, Vidal & Tierny 2023 for D0).
// Upward likewise. Ties: Simulation of Simplicity by index.
//
// Thread safety: pure functions; persistencePairs uses oneTBB (the two sweeps run concurrently).
#pragma once

#include "analysis/critical_points.h"
#include "grid/grid.h"

#include <cstddef>
#include <cstdint>
#include <span>
#include <string>
#include <vector>

namespace raypc::analysis {

enum class PairKind : uint8_t { MinimumSaddle = 0, SaddleMaximum = 1, Global = 2 };

// "minimum-saddle", "saddle-maximum", "global".
const char* pairKindName(PairKind kind);

struct PersistencePair {
    PairKind kind = PairKind::MinimumSaddle;
    size_t birthIndex = 0, deathIndex = 0;  // grid indices of the lower and the higher end
    CriticalKind birthKind = CriticalKind::Minimum, deathKind = CriticalKind::Maximum;
    float birth = 0, death = 0;  // values at the two ends, birth <= death

    double persistence() const { return double(death) - double(birth); }
    // The pair's extremum: the minimum of a minimum-saddle pair, the maximum of a saddle-maximum
    // pair, the maximum of the global pair (whose birth is the global minimum).
    size_t extremumIndex() const { return kind == PairKind::MinimumSaddle ? birthIndex : deathIndex; }
};

// Every minimum-saddle and saddle-maximum pair of `values` (grid.cellCount() values, canonical
// order) and the global pair, by decreasing persistence (ties: kind, then extremum index).
// Throws raypc::Error when the sizes differ, the grid is smaller than 2x2x3 or has 2^32 points
// or more.
std::vector<PersistencePair> persistencePairs(const grid::SphericalGrid& grid, std::span<const float> values);

// findCriticalPoints and persistencePairs of `values` from the one pass over the vertices' links
// both need: the same points and pairs as the two calls. Throws like persistencePairs.
struct CriticalStructure {
    std::vector<CriticalPoint> points;   // findCriticalPoints'
    std::vector<PersistencePair> pairs;  // persistencePairs'
};
CriticalStructure criticalStructure(const grid::SphericalGrid& grid, std::span<const float> values);

// The seeds the filter's rule chooses among `all` (findCriticalPoints(grid, values)), most
// significant first, and the threshold it applied in the field's units.
//   SeedRule::Persistence: the extrema of the pairs whose persistence exceeds the threshold (both
//     ends of the global pair), with filter.saddles also the saddles of those pairs; ordered by
//     decreasing persistence (a point in several pairs counts with the largest); each point's
//     `persistence` is set.
//   SeedRule::Value: selectSignificant with the step's largest |value|; each point's `persistence`
//     is set as well (the largest of its pairs; 0 for a saddle that ends no extremum pair).
// Then at most filter.maxCount. Throws like persistencePairs, and raypc::Error for a filter that
// checkCriticalPointFilter refuses.
struct SeedSelection {
    std::vector<CriticalPoint> seeds;
    double threshold = 0;
};
SeedSelection selectSeeds(const grid::SphericalGrid& grid, std::span<const float> values,
                          const std::vector<CriticalPoint>& all, const CriticalPointFilter& filter);
// selectSeeds with the points and pairs of criticalStructure(grid, values), not computed again.
SeedSelection selectSeedsFrom(const grid::SphericalGrid& grid, std::span<const float> values,
                              const CriticalStructure& structure, const CriticalPointFilter& filter);

// The persistence diagram as CSV, one row per pair in the given order: kind, birth, death,
// persistence (in `units`), then for the birth end and the death end: critical kind, lat, lon,
// radius, x, y, z (degrees, km; frame of core/spherical.h).
std::string persistenceDiagramCsv(const grid::SphericalGrid& grid, const std::vector<PersistencePair>& pairs,
                                  const std::string& units);

}  // namespace raypc::analysis
