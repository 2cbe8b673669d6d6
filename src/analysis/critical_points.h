// Critical points of a scalar field on the spherical grid (minima, saddles, maxima), found by
// the piecewise-linear rule of Banchoff / Edelsbrunner et al. as TTK's ScalarFieldCriticalPoints
// applies it: a vertex is classified by the connected components of its lower and upper link.
//
// Triangulation, boundaries (lon seam, r boundaries, outermost lat rows) and the Simulation of
// Simplicity order that breaks ties by index: grid/triangulation.h (docs/format.md, "Pathlines").
// The triangulated domain is [lat rows] x [radii] x circle, a solid torus (Euler
// characteristic 0). A feature centred on a pole shows up on the outermost row.
//
// Classification from c- = #components of the lower link and c+ = #components of the upper link:
//   minimum (c- = 0), maximum (c+ = 0), regular (c- = c+ = 1), 1-saddle (c- > 1, c+ = 1),
//   2-saddle (c- = 1, c+ > 1), multi-saddle (c- > 1 and c+ > 1).
// On boundary vertices the link is a disk, not a sphere; the same rule applies (as in TTK), so an
// extremum on the shell's surface is reported like an interior one.
//
// Thread safety: pure functions; findCriticalPoints uses oneTBB over lat rows.
#pragma once

#include "grid/grid.h"

#include <cstddef>
#include <cstdint>
#include <limits>
#include <optional>
#include <span>
#include <string>
#include <vector>

namespace raypc::analysis {

enum class CriticalKind : uint8_t { Minimum = 0, Saddle1 = 1, Saddle2 = 2, Maximum = 3, MultiSaddle = 4 };

// "minimum", "1-saddle", "2-saddle", "maximum", "multi-saddle".
const char* criticalKindName(CriticalKind kind);

struct CriticalPoint {
    size_t index = 0;  // grid index, canonical order
    CriticalKind kind = CriticalKind::Minimum;
    float value = 0;
    uint8_t lowerComponents = 0, upperComponents = 0;
    double latDeg = 0, lonDeg = 0, rKm = 0;  // the grid point's coordinates
    // Of the persistence pair(s) it belongs to (the largest), as selectSeeds sets it (0 for a
    // saddle in no extremum pair); NaN where nothing set it.
    double persistence = std::numeric_limits<double>::quiet_NaN();
};

// The kind of a vertex whose lower and upper links have `lower` and `upper` connected components
// (the rule above), or nullopt for a regular vertex (one of each).
std::optional<CriticalKind> classifyLink(int lower, int upper);

// Every non-regular vertex of `values` (grid.cellCount() values, canonical order), sorted by
// index. NaN values are not expected (the reader rejects them). Throws raypc::Error when the
// sizes differ or the grid has fewer than 2 lat rows, 2 radii or 3 lon columns.
std::vector<CriticalPoint> findCriticalPoints(const grid::SphericalGrid& grid, std::span<const float> values);

// Which critical points seed pathlines (docs/persistence.md).
//   SeedRule::Persistence (the default, as TTK practice): the extrema whose persistence (see
//     persistence.h) exceeds a threshold, so that noise makes no seeds and every feature that
//     stands out from its surroundings by more than the threshold gets one, however weak.
//   SeedRule::Value (the rule before persistence): a maximum needs value >= T, a minimum value
//     <= -T, a saddle |value| >= T (temperature anomaly: hot upwellings, cold downwellings), where
//     T = max(minAbsValue, minFractionOfMaxAbs * max|value| over the step).
// Under both, the `maxCount` most significant are kept (largest persistence or |value|, ties by
// index), so a noisy step cannot make thousands of seeds.
enum class SeedRule : uint8_t { Persistence = 0, Value = 1 };

// "persistence", "value".
const char* seedRuleName(SeedRule rule);
// Parses a seedRuleName; throws raypc::Error naming --cp-select otherwise.
SeedRule parseSeedRule(const std::string& text);

struct CriticalPointFilter {
    SeedRule rule = SeedRule::Persistence;
    // Persistence rule: the threshold in the field's units (K), or with persistenceIsFraction
    // this fraction of the step's range (max - min).
    double minPersistence = 0.05;
    bool persistenceIsFraction = true;
    // Value rule.
    double minAbsValue = 0;             // in the field's units (K)
    double minFractionOfMaxAbs = 0.25;  // of the step's largest |value|
    size_t maxCount = 200;
    // Seed at saddles too: under the persistence rule the saddles paired with the kept extrema,
    // under the value rule the saddles (and multi-saddles) with |value| >= T.
    bool saddles = false;
};

// Parses --cp-persistence into `filter`: "30" (field units) or "5%" (of the step's range).
// Throws raypc::Error naming the option for anything else or a negative value.
void parsePersistenceThreshold(const std::string& text, CriticalPointFilter& filter);

// Throws raypc::Error naming the option (--cp-persistence, --cp-min-abs, --cp-min-fraction,
// --cp-max-count) when a threshold is negative, NaN, a fraction above 1 or maxCount is 0.
void checkCriticalPointFilter(const CriticalPointFilter& filter);

// The value rule's threshold T for a step whose largest |value| is `maxAbs`.
double significanceThreshold(const CriticalPointFilter& filter, double maxAbs);

// Applies the value rule of `filter` (whatever filter.rule says) to `points`; the result is
// ordered by decreasing |value| (ties by index).
std::vector<CriticalPoint> selectSignificant(std::vector<CriticalPoint> points, double maxAbs,
                                             const CriticalPointFilter& filter);

// 1 - χ(lower link of vertex `index`): the vertex's contribution to the Euler characteristic of
// the triangulated domain (each simplex counted at its highest vertex). Summed over all vertices
// it is 0 for this grid's solid torus, whatever the field: a test of the triangulation's links.
int lowerStarEulerContribution(const grid::SphericalGrid& grid, std::span<const float> values, size_t index);

}  // namespace raypc::analysis
