// The names of the variables the program derives (preprocess/preprocess_numerics.h) or looks for
// by name, for the C++ code: the constants (varname::kTemperatureAnomaly, …, varname::kVelocity)
// come from src/grid/names.json (grid/names.h), which the UI and Python read too.
#pragma once

#include "grid/names.h"

#include <algorithm>
#include <span>
#include <string>
#include <string_view>

namespace raypc::varname {

// Whether `name` is one of kVelocity.
inline bool isVelocityComponent(std::string_view name)
{
    return std::find(kVelocity.begin(), kVelocity.end(), name) != kVelocity.end();
}

// Whether `has(name)` holds for the three velocity components.
template <class Has>
bool hasVelocity(Has has)
{
    return std::all_of(kVelocity.begin(), kVelocity.end(), [&](const char* c) { return has(c); });
}

// The variable a dataset is first looked at by (the default view's colour, the pathlines' seeds, the
// persistence diagram): its temperature anomaly, else the first variable's shell anomaly (a
// tomography model's "vs anomaly"), else the first variable that is not a velocity component; empty
// when `names` holds none of these.
inline std::string anomalyToShow(std::span<const std::string> names)
{
    const auto has = [&](const std::string& name) { return std::find(names.begin(), names.end(), name) != names.end(); };
    if (has(kTemperatureAnomaly))
        return kTemperatureAnomaly;
    for (const std::string& name : names)
        if (has(name + kShellAnomalySuffix))
            return name + kShellAnomalySuffix;
    for (const std::string& name : names)
        if (!isVelocityComponent(name))
            return name;
    return "";
}

}  // namespace raypc::varname
