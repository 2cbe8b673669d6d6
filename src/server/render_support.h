// What the server's render paths share: the default state shown
// first in the UI (also the picture `raypc demo` writes), state validation against a dataset, and
// brushing ranges as selection filters.
#pragma once

#include "data/dataset.h"
#include "data/selection.h"
#include "render/render_state.h"

#include <vector>

namespace raypc::server {


// A state that shows the data well without tuning: the temperature anomaly (if the dataset has it,
// else the first variable) on the blue-white-red map, opacity only on the hot and cold tails.
render::RenderState defaultState(const Dataset& dataset);

struct ResolvedState {
    render::RenderState state;
    render::RenderParams params;
};
// Parses a state document and checks it against the dataset (step and level in range, names known).
// Throws raypc::Error naming the key, e.g. "step: 300 out of range 0..11".
ResolvedState resolveState(const nlohmann::json& document, const Dataset& dataset);

// The brushes of `params` as filters for selectedVolume.
std::vector<RangeFilter> selectionFilters(const render::RenderParams& params);

}  // namespace raypc::server
