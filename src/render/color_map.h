// Colour maps sampled for pictures: stops interpolated linearly in RGB. The maps themselves (names,
// kinds, control points) are the state's vocabulary: state/color_maps.h.
#pragma once

#include "state/color_maps.h"

#include <span>

namespace raypc::render {

using state::ColorMapId;
using state::ColorStop;
using state::Rgb;

// The colour at u in [0, 1] (clamped) of piecewise-linear `stops` (ascending u, at least one).
Rgb sampleStops(std::span<const ColorStop> stops, float u);

// The colour at u in [0, 1] (clamped).
Rgb sampleColorMap(ColorMapId map, float u);

}  // namespace raypc::render
