// The values at one point and step, with units and quantisation bounds: what `raypc probe` prints,
// what Python's Dataset.probe returns and what the server's GET /api/probe answers (the UI's map
// and section pointer); one implementation for all.
#pragma once

#include "dataset/dataset.h"

#include <nlohmann/json.hpp>

#include <string>

namespace raypc::analysis {

// What the messages call the arguments: the CLI's options by default; Python names its keyword
// arguments, so that its messages name what its user typed.
struct ProbeArgumentNames {
    std::string step = "--time", level = "--lod", lat = "--lat", r = "--r", var = "--var";
};

// {step, time_myr, level, point: {lat, lon, radius, depth, x, y, z: {value, units}},
//  values: {NAME: {value, units, quantisation_error_max}}} of step `step` at `level`, interpolated
// as GridSampler does (trilinear, lon periodic, pole caps). `var` empty: every variable, else that
// one. Throws raypc::Error naming the argument (`names`) for a point outside the shell,
// raypc::UnknownNameError for an unknown variable and raypc::OutOfRangeError for a step or level
// out of range (core/error_kinds.h).
nlohmann::json probeJson(const dataset::Dataset& dataset, int step, int level, double latDeg, double lonDeg, double rKm,
                         const std::string& var = {}, const ProbeArgumentNames& names = {});
// The same from a volume of that step and level already at hand (the server's step cache).
nlohmann::json probeJson(const dataset::Dataset& dataset, const dataset::StepVolume& volume, int step, int level, double latDeg,
                         double lonDeg, double rKm, const std::string& var = {}, const ProbeArgumentNames& names = {});

}  // namespace raypc::analysis
