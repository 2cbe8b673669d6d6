// The names of the variables the program derives (preprocess/preprocess_numerics.h) or looks for
// by name, for the C++ code: the constants (varname::kTemperatureAnomaly, …, varname::kVelocity)
// come from src/grid/names.json (grid/names.h), which the UI and Python read too.
#pragma once

#include "grid/names.h"

#include <algorithm>
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

}  // namespace raypc::varname
