// One time step of simulation output in memory, in canonical grid order (see grid.h).
#pragma once

#include "data/grid.h"

#include <string>
#include <vector>

namespace raypc {

struct Field {
    std::string name;   // as in the contest files, e.g. "temperature anomaly"
    std::string units;  // CF units string, e.g. "K", "m/s"
    std::vector<float> values;  // grid.cellCount() values, canonical order
};

struct Snapshot {
    SphericalGrid grid;
    std::vector<Field> fields;

    // The field named `name`, or nullptr.
    const Field* find(const std::string& name) const;
    Field* find(const std::string& name);
};

// The eight variables of the SciVis 2021 contest files, in their file order.
inline const std::vector<std::string>& contestVariableNames()
{
    static const std::vector<std::string> names = {
        "temperature", "vx", "vy", "vz", "thermal conductivity", "thermal expansivity",
        "temperature anomaly", "spin transition-induced density anomaly"};
    return names;
}

}  // namespace raypc
