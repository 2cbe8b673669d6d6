// The names of the variables the program derives (preprocess/preprocess_numerics.h) or looks for
// by name, in one place for the C++ code: the UI and Python take the names the server and the
// dataset's manifest give them.
#pragma once

#include <algorithm>
#include <array>
#include <string_view>

namespace raypc::varname {

inline constexpr const char* kTemperature = "temperature";
inline constexpr const char* kTemperatureAnomaly = "temperature anomaly";      // K, derived where absent
inline constexpr const char* kRadialVelocity = "radial velocity";              // cm/yr, derived, outward
inline constexpr const char* kVelocityMagnitude = "velocity magnitude";        // cm/yr, derived
inline constexpr const char* kThermalExpansivity = "thermal expansivity";
inline constexpr const char* kThermalExpansivityAnomaly = "thermal expansivity anomaly";  // 1/K, derived
// The velocity's Cartesian components, m/s.
inline constexpr std::array<const char*, 3> kVelocity = {"vx", "vy", "vz"};

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
