// A map's or a section's values as a CF grid (io/cf_grid.h): what `raypc map --netcdf` and
// `raypc section --netcdf` write and what Python's Dataset.map_grid / section_grid return as xarray
// DataArrays, made in one place so that the two agree to the last digit.
#pragma once

#include "dataset/dataset.h"
#include "io/cf_grid.h"
#include "render/resolve_state.h"
#include "render/state_renderer.h"

#include <string>

namespace raypc::app {

// How the caller names the spacings in its messages: the CLI's flags or Python's arguments.
struct SliceGridNames {
    std::string gridStep = "--grid-step", depthStep = "--depth-step", depth = "--depth";
};

// Checks the spacings of a slice's grid: `gridStepDeg` 0 (the default: 1° on maps, 0.5° along
// sections) or, on maps, degrees that divide 180, along sections at least 0.001°; `depthStepKm` (a
// section's rows) at least 0.1 km. Throws raypc::Error naming the spacing.
void checkSliceGridSpacing(render::StateRenderer::Slice slice, double gridStepDeg, double depthStepKm,
                           const SliceGridNames& names = {});

// The state's map (a lat-lon grid at its depth) or section (a distance-depth grid along its great
// circle) of the colour variable of `volume` (the state's step and level), sampled as the picture
// is, with CF names, units and the title; `source` names what made it (e.g. "raypc map").
io::CfGridFile sliceGridFile(const dataset::Dataset& dataset, const dataset::StepVolume& volume,
                             const render::ResolvedState& resolved, render::StateRenderer::Slice slice, double gridStepDeg,
                             double depthStepKm, const std::string& source, const SliceGridNames& names = {});

}  // namespace raypc::app
