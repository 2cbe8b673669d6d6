// One resolution of a state document (state/render_state.h) against a volume: names of variables
// and coordinates checked and turned into indices, defaults filled in from the data (the colour
// range from a variable's global range, the opacity from the colour map), the result the
// renderer's parameters (RenderParams); and the state a dataset is first shown with.
#pragma once

#include "dataset/dataset.h"
#include "state/render_state.h"
#include "render/volume_renderer.h"

#include <nlohmann/json.hpp>

#include <string>
#include <vector>

namespace raypc::render {

// What a volume offers to resolve names against: variable names, their global ranges and (when
// known) their global histograms (VariableStats::histogram; for the default colour range).
struct VariableCatalog {
    std::vector<std::string> names;
    std::vector<dataset::ValueRange> ranges;
    std::vector<std::vector<double>> histograms;  // empty, or one per variable
};

// The catalog of a dataset: its variables' names, global ranges and histograms (over all steps).
VariableCatalog catalogOf(const dataset::Dataset& dataset);

// Resolves names and defaults. Throws raypc::Error for an unknown variable or coordinate (listing
// the known ones), a brush with min > max, a degenerate colour range, or camera views that do not
// fit the stereo mode.
RenderParams resolveParams(const state::RenderState& state, const VariableCatalog& catalog);

// A state that shows the data well without tuning (the UI's first view, `raypc render` without a
// state and `raypc demo`'s picture): the temperature anomaly (if the dataset has it, else the first
// variable) on the blue-white-red map over the default colour range (no range: defaultColorRange,
// as the presets), opaque only on the hot and cold tails, lit, a dark core, the
// planet filling 94 % of the image's shorter side, the 410 and 660 km shells and the legend.
state::RenderState defaultState(const dataset::Dataset& dataset);
// The same for any volume's variables (their names and global ranges).
state::RenderState defaultState(const VariableCatalog& catalog);

struct ResolvedState {
    state::RenderState state;
    RenderParams params;
};
// Checks a state against the dataset (step and level in range, names known) and resolves it.
// Throws raypc::Error naming the key, e.g. "step: 300 out of range 0..11".
ResolvedState resolveState(state::RenderState state, const dataset::Dataset& dataset);
// Parses a state document first (parseRenderState; `what` names the source in messages).
ResolvedState resolveState(const nlohmann::json& document, const dataset::Dataset& dataset, const std::string& what = "state");

// What a state is rendered as: the state itself when stereo is off, else its left and right eye
// (render/stereo.h): each with its eye's camera (stereoEye: parallel axes, off-axis frustum
// converging at stereo.convergenceKm), its eye's size and pixel aspect (stereoLayout) and stereo
// off. Throws raypc::Error for an unusable separation or convergence.
std::vector<ResolvedState> stereoViews(const ResolvedState& resolved);

}  // namespace raypc::render
