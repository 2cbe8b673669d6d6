// Two datasets side by side (docs/compare.md, "Side by side"): the state a pair's second dataset is
// drawn with, from the state of the first, so that both show the same thing. The one place this is
// decided: the server's sessions of the second dataset (`/ws?dataset=1`) and `raypc render --state`
// of a state with `pair` both call it.
#pragma once

#include "dataset/dataset.h"
#include "render/image_io.h"
#include "state/render_state.h"

#include <string>
#include <vector>

namespace raypc::render {

// The second's step for the first's `step`: the same index (the second's last if it has fewer), or
// its step nearest in model time (the earlier of two as near). Throws raypc::Error when `step` is
// not a step of `first`.
int pairedStep(const dataset::Dataset& first, int step, const dataset::Dataset& second, state::PairSteps steps);

struct PairedState {
    state::RenderState state;        // for the second dataset
    std::vector<std::string> notes;  // what differs from the first's, one sentence each, for the UI
};

// `state` (for `first`; its `pair` says how steps are matched, time when absent) made the second's:
// its step matched (pairedStep); the colour and core ranges the first's (its own default range when
// the state gives none), so that one colour means one value in both; the colour variable named; what
// the second lacks left out with a note each (a brush or pathline filter on a name it does not have,
// a colour or core variable it lacks: its first variable / plain colour; a level: its coarsest;
// pathlines when it has none). Throws raypc::Error as resolveState(state, first) does.
PairedState secondOfPair(state::RenderState state, const dataset::Dataset& first, const dataset::Dataset& second);

// A pair's picture of `state` (width W): the first's state at the left W/2 (rounded down) and the
// second's (secondOfPair) at the right W − W/2, both the full height. Throws raypc::Error when W < 2,
// and as secondOfPair.
struct PairHalves {
    state::RenderState left;
    PairedState right;
};
PairHalves pairHalves(state::RenderState state, const dataset::Dataset& first, const dataset::Dataset& second);

// `left` and `right` (of one height) side by side.
ImageRgba8 sideBySide(const ImageRgba8& left, const ImageRgba8& right);

}  // namespace raypc::render
