// Exact statistics of a brushing selection, from the grid's dual-cell volumes (not from the
// parallel-coordinates sample): the selected volume, its share of the mantle, and its
// distribution over depth. Used by the server's status line and `raypc stats`.
#pragma once

#include "core/huge_pages.h"
#include "dataset/dataset.h"

#include <functional>
#include <memory>
#include <optional>
#include <string>
#include <span>
#include <vector>

namespace raypc::analysis {

// The one brush model of RayPC. A brush names a variable or a coordinate (NamedRange, as in the
// state document and the --range options) and resolves against a volume's variable names into a
// RangeFilter, which selection, the renderer and pathline filtering all use.
//
// One axis may hold several ranges (the paper's "multi" brushes): a value is selected when it lies
// in at least one range of its axis, and a sample when that holds on every brushed axis (OR within
// an axis, AND over axes). In a list of NamedRanges a name that repeats adds a range to its axis.

// One brushed axis: a variable (index into the volume's variables) or a coordinate, and its ranges.
struct RangeFilter {
    int variable = -1;
    std::optional<grid::Coordinate> coordinate;
    std::vector<dataset::ValueRange> ranges;  // inclusive, min <= max each; at least one; may overlap

    // True when `v` lies in at least one range (false for NaN).
    bool contains(double v) const
    {
        for (const dataset::ValueRange& r : ranges)
            if (v >= r.min && v <= r.max)
                return true;
        return false;
    }
};

// A range named by a variable or coordinate name, as in the state document's brushes.
struct NamedRange {
    std::string name;
    float min = 0, max = 0;
};

// The ranges of one name, in the order given.
struct NamedRanges {
    std::string name;
    std::vector<dataset::ValueRange> ranges;
};

// Groups ranges by name, in the order the names first appear (each name's ranges in their order).
// Throws raypc::Error for min > max naming `what` and the range's index in `ranges`, e.g.
// "brushes[2] (depth): min 3 is greater than max 1".
std::vector<NamedRanges> groupRanges(std::span<const NamedRange> ranges, const std::string& what = "brushes");

// Resolves names against `variableNames` (a volume's variables, in order) and the coordinates, one
// RangeFilter per name (groupRanges). Throws raypc::Error naming `what` and the index, e.g.
// "brushes[1] (pressure): unknown variable or coordinate 'pressure'; variables: ...; coordinates: ..."
// or "brushes[0] (depth): min 3 is greater than max 1".
std::vector<RangeFilter> resolveRangeFilters(std::span<const std::string> variableNames,
                                             std::span<const NamedRange> ranges, const std::string& what = "brushes");
std::vector<RangeFilter> resolveRangeFilters(const dataset::Dataset& dataset, std::span<const NamedRange> ranges,
                                             const std::string& what = "brushes");

// The selection `filters` make as a canonical text, equal for filters that select the same points
// whatever order their axes and ranges were given in: axes sorted (variables by index, then
// coordinates), each axis' ranges sorted, numbers exact (shortest round trip). What caches of a
// selection's results are keyed by (server/analysis_caches.h, the painted features).
std::string selectionKey(std::span<const RangeFilter> filters);

struct SelectionStats {
    double volumeKm3 = 0;
    double fractionOfMantle = 0;             // of the grid's whole shell volume
    std::vector<double> volumeByRadiusKm3;   // per radius index of the grid (ascending r)
    std::vector<double> shellVolumeByRadiusKm3;  // whole dual-cell shell of each radius index
    // With a mean variable: its volume-weighted mean per radius index over the selected points
    // (NaN where none is selected) and over the whole shell; otherwise empty.
    std::vector<double> selectedMeanByRadius, shellMeanByRadius;
};

// A grid point is selected when every filter holds at it (its value lies in one of the filter's
// ranges); it counts with its dual-cell volume. With `meanVariable` (an index of the volume's
// variables) also that variable's means per radius (a time-depth view of it). Throws raypc::Error
// for a variable index out of range, a filter without ranges or min > max. Parallel over lat rows.
SelectionStats selectedVolume(const dataset::StepVolume& volume, std::span<const RangeFilter> filters,
                              std::optional<size_t> meanVariable = std::nullopt);

// Whether each grid point is selected (1) or not (0), canonical order, by the rule of
// selectedVolume. `radii`: per radius index whether to look there (0 at every point of a radius
// not looked at), or empty for every radius. Throws raypc::Error as selectedVolume does. Parallel
// over lat rows.
HugePageVector<uint8_t> selectedPoints(const dataset::StepVolume& volume, std::span<const RangeFilter> filters,
                                       std::span<const uint8_t> radii = {});

// The selection split by a labelling of the grid's points: `classes` holds one class in
// [0, classCount) per grid point (canonical order), e.g. what the synthetic generator put there
// (syntheticTruth), and the answer the whole and the selected dual-cell volume of each class. The
// points are selected exactly as by selectedVolume. Throws raypc::Error as selectedVolume does,
// and when `classes` does not have one entry per grid point or holds a class >= classCount.
struct ClassVolumes {
    std::vector<double> totalKm3, selectedKm3;  // per class
};
ClassVolumes selectedVolumeByClass(const dataset::StepVolume& volume, std::span<const RangeFilter> filters,
                                   std::span<const uint32_t> classes, size_t classCount);

// The selection of every step in [firstStep, lastStep] at one level, in step order: what
// `raypc stats` writes and the server's /api/stats answers. `load` gives a step's volume at the
// level (default: Dataset::load); `onStep` is called after each step (progress). Throws
// raypc::Error for a step or level out of range (Dataset::checkStep/checkLevel).
struct StepSelection {
    int step = 0;
    double timeMyr = 0;
    SelectionStats stats;
};
using VolumeLoader = std::function<std::shared_ptr<const dataset::StepVolume>(int step, int level)>;
std::vector<StepSelection> selectionOverTime(const dataset::Dataset& dataset, std::span<const RangeFilter> filters, int level,
                                             int firstStep, int lastStep, const VolumeLoader& load = {},
                                             const std::function<void()>& onStep = {},
                                             std::optional<size_t> meanVariable = std::nullopt);

}  // namespace raypc::analysis
