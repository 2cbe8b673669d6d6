// Exact statistics of a brushing selection, from the grid's dual-cell volumes (not from the
// parallel-coordinates sample): the selected volume, its share of the mantle, and its
// distribution over depth. Used by the server's status line and `raypc stats`.
#pragma once

#include "data/dataset.h"

#include <optional>
#include <string>
#include <span>
#include <vector>

namespace raypc {

// One brushed range: a variable (index into the volume's variables) or a coordinate.
struct RangeFilter {
    int variable = -1;
    std::optional<Coordinate> coordinate;
    float min = 0, max = 0;  // inclusive
};

// A range named by a variable or coordinate name, as in the state document's brushes.
struct NamedRange {
    std::string name;
    float min = 0, max = 0;
};

// Resolves names against the dataset's variables and coordinates. Throws raypc::Error naming
// `what` (e.g. "brushes[1]") for an unknown name (listing the known ones) or min > max.
std::vector<RangeFilter> resolveRangeFilters(const Dataset& dataset, std::span<const NamedRange> ranges,
                                             const std::string& what = "brushes");

struct SelectionStats {
    double volumeKm3 = 0;
    double fractionOfMantle = 0;             // of the grid's whole shell volume
    std::vector<double> volumeByRadiusKm3;   // per radius index of the grid (ascending r)
    std::vector<double> shellVolumeByRadiusKm3;  // whole dual-cell shell of each radius index
};

// A grid point is selected when every filter holds at it; it counts with its dual-cell volume.
// Throws raypc::Error for a variable index out of range or min > max. Parallel over lat rows.
SelectionStats selectedVolume(const StepVolume& volume, std::span<const RangeFilter> filters);

}  // namespace raypc
