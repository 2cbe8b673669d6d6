// The values at one point and step, with units and quantisation bounds: what `raypc probe` prints,
// what Python's Dataset.probe returns and what the server's GET /api/probe answers (the UI's map
// and section pointer); one implementation for all.
#pragma once

#include "dataset/dataset.h"

#include <nlohmann/json.hpp>

#include <string>

namespace raypc::analysis {

// {step, time_myr, level, point: {lat, lon, radius, depth, x, y, z: {value, units}},
//  values: {NAME: {value, units, quantisation_error_max}}} of step `step` at `level`, interpolated
// as GridSampler does (trilinear, lon periodic, pole caps). `var` empty: every variable, else that
// one. Throws raypc::Error naming the option (--lat, --r, --var, --lod) for a point outside the
// shell, an unknown variable or a level out of range.
nlohmann::json probeJson(const dataset::Dataset& dataset, int step, int level, double latDeg, double lonDeg, double rKm,
                         const std::string& var = {});
// The same from a volume of that step and level already at hand (the server's step cache).
nlohmann::json probeJson(const dataset::Dataset& dataset, const dataset::StepVolume& volume, int step, int level, double latDeg,
                         double lonDeg, double rKm, const std::string& var = {});

}  // namespace raypc::analysis
