// One time step of simulation output in memory, in canonical grid order (see grid.h).
#pragma once

#include "core/system_memory.h"
#include "grid/grid.h"

#include <nlohmann/json.hpp>

#include <cstdint>
#include <functional>
#include <string>
#include <vector>

namespace raypc::grid {

// The most grid points RayPC reads: the parallel-coordinates sample indexes points with 32 bits.
inline constexpr uint64_t kMaxGridPoints = UINT32_MAX;

struct Field {
    std::string name;   // as in the contest files, e.g. "temperature anomaly"
    std::string units;  // CF units string, e.g. "K", "m/s"
    std::vector<float> values;  // grid.cellCount() values, canonical order
    std::vector<std::string> derivedFrom = {};  // for a derived field: the fields it is computed from
};

struct Snapshot {
    SphericalGrid grid;
    std::vector<Field> fields;
    // How the step was made from an input that is not on the grid (a resampled mesh: its cells and
    // how many grid points were inside one, snapped to one or missing); null for netCDF steps.
    nlohmann::json origin;

    // The field named `name`, or nullptr.
    const Field* find(const std::string& name) const;
    Field* find(const std::string& name);
};

// Throws raypc::Error naming `file`, the grid, the bytes needed to `purpose` ("read",
// "preprocess") and what is available when `neededBytes` exceed `available` (checked before
// allocating), or when the grid has more than kMaxGridPoints points.
void checkGridFitsMemory(const SphericalGrid& grid, uint64_t neededBytes, const std::string& file,
                         const std::string& purpose, const AvailableMemory& available);

// Where grid point `index` (canonical order) is, for messages: its coordinates and its indices
// in ascending order, e.g. "lat -87.5°, r 3485 km, lon 0° (point 0, 0, 0 of lat, r, lon ascending)".
std::string describeGridPoint(const SphericalGrid& grid, size_t index);

// Replaces every NaN of `values` (canonical order) by the mean of the other values on its radius
// shell (--fill-missing); with `holdsData`, only at the columns (iLat, iLon) it accepts, and of their
// values (a regional grid's padding stays missing). Throws raypc::Error naming `what` (file and
// variable) and the shell when all of a shell's values are NaN.
void fillMissingByShellMean(const SphericalGrid& grid, std::vector<float>& values, const std::string& what,
                            const std::function<bool(size_t iLat, size_t iLon)>& holdsData = {});

// Throws raypc::Error if a value of `field` is infinite, or NaN where it is not missing (a derived
// field's NaN where all its inputs have values), naming `source` (the input file), the field, the
// first such point and, for a derived field, its inputs' values there. A NaN is a missing value.
void checkFinite(const Snapshot& snapshot, const Field& field, const std::string& source);

// The eight variables of the SciVis 2021 contest files, in their file order.
inline const std::vector<std::string>& contestVariableNames()
{
    static const std::vector<std::string> names = {
        "temperature", "vx", "vy", "vz", "thermal conductivity", "thermal expansivity",
        "temperature anomaly", "spin transition-induced density anomaly"};
    return names;
}

}  // namespace raypc::grid
