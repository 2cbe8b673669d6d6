// A quantity against depth drawn as a curve (`raypc correlate --png`: the correlation of two fields per
// depth): depth down the plot, the quantity across it, laid out as the time–depth pictures are
// (slice_drawing.h: the same frame, depth ticks, marks at the reference shells, title and notes).
//
// Units: km (depth), the quantity's own. Thread safety: a plain function over its inputs.
#pragma once

#include "render/image_io.h"
#include "render/color_map.h"
#include "state/render_state.h"

#include <string>
#include <vector>

namespace raypc::render {

struct DepthProfileInputs {
    std::vector<double> depthsKm;  // per point, any order
    std::vector<double> values;    // per point; NaN leaves a gap in the curve (said in a note)
    double depthSpanKm = 2891;     // the plot's depth range, from the surface
    double xMin = -1, xMax = 1;    // the quantity's axis
    std::vector<double> xTicks;    // the axis's labelled values (a line across the plot at 0 when it lies inside)
    std::string xTitle;            // below the axis, e.g. "correlation of A and B"
    std::vector<std::string> titleLines;  // above the plot, one line each (each cut to the picture's width)
    std::string note;                     // below the axis's title
    int width = 640, height = 800;
    Rgb background{0, 0, 0};
    Rgb curve{0.35f, 0.75f, 1.0f};
    state::ReferenceState::Shells marks;  // e.g. 410 and 660 km, visible
};
// Throws raypc::Error when the inputs disagree in size, the axis is empty, or the picture has no room
// for the plot.
ImageRgba8 depthProfilePicture(const DepthProfileInputs& inputs);

}  // namespace raypc::render
