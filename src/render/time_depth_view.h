// Time–depth (Hovmöller) pictures: a quantity per step and radius of a selection over time
// (`raypc stats --hovmoller`, POST /api/time-depth), laid out as a section is (slice_view.h).
//
// Units: Myr (model time), km (radius, depth), the quantity's own units. Thread safety: plain
// functions over their inputs.
#pragma once

#include "dataset/dataset.h"
#include "analysis/selection.h"
#include "render/image_io.h"
#include "state/render_state.h"
#include "render/transfer_function.h"

#include <span>
#include <string>
#include <vector>

namespace raypc::render {

// A time–depth (Hovmöller) picture of a quantity per step and radius (`raypc stats --hovmoller`):
// model time to the right, depth down; each step a column reaching half way to its neighbours' times
// (or, `columnsAre` Degree, each spherical-harmonic degree a column: a spectrum's degree–depth picture,
// `raypc spectrum --png`)
// and each radius a row reaching half way to its neighbours (values are not interpolated), NaN drawn
// as the background; `marks` (when visible) as dashed lines across, labelled at the right; the
// title, ticks and colour legend laid out as a section's.
struct TimeDepthInputs {
    // What the columns are, and their values ascending: per step its time (Myr), or per degree l.
    enum class Columns { TimeMyr, Degree } columnsAre = Columns::TimeMyr;
    std::vector<double> columns;
    std::vector<double> radiiKm;   // the grid's radii (rows), ascending
    std::vector<float> values;     // steps x radii, step-major
    TransferFunction colors;       // colour map and range (the opacity is not used)
    std::string colorTitle;        // the legend's, e.g. "selected share of the shell [%]"
    std::string title;
    int width = 960, height = 540;
    Rgb background{0, 0, 0};
    state::ReferenceState::Shells marks;
    std::string blankNote = "background: nothing selected at that depth and time";  // said when a value is NaN
};
// Throws raypc::Error when the inputs disagree in size or the picture has no room for the plot.
ImageRgba8 timeDepthPicture(const TimeDepthInputs& inputs);
// Throws raypc::Error when a time–depth picture of this size has no room for its plot (what
// timeDepthPicture checks first; callers check before computing its values).
void checkTimeDepthPictureSize(int width, int height);

// What a time–depth picture of a selection over time shows at each step and radius: the selected
// share of the shell (%), or a variable's mean over the selected points or over the whole shell
// (selectionOverTime's means, analysis/selection.h).
enum class TimeDepthOf { Share, SelectedMean, ShellMean };
// "share", "selected-mean" or "shell-mean"; throws raypc::Error naming `what` otherwise.
TimeDepthOf parseTimeDepthOf(const std::string& text, const std::string& what);
// Appends the picture's values of `selections` (steps in order), step-major; NaN where a mean has
// nothing selected.
void appendTimeDepthValues(std::span<const analysis::StepSelection> selections, TimeDepthOf of, std::vector<float>& out);
// The picture of steps first..last of `dataset` at `level` from their `values` (appendTimeDepthValues):
// colours (a share over [0, its largest], viridis; a mean over its range, centred vik when the values
// take both signs), the legend's and the picture's titles; `mean` (the means' variable) is needed
// unless `of` is Share; `ranges`: the selection's range count, for the title. Size, background and
// marks are left at their defaults for the caller.
TimeDepthInputs timeDepthInputs(const dataset::Dataset& dataset, int first, int last, int level, std::vector<float> values,
                                TimeDepthOf of, const dataset::VariableInfo* mean, size_t ranges);

}  // namespace raypc::render
