#include "render/pair_state.h"

#include "analysis/pathline_storage.h"
#include "analysis/pathlines.h"
#include "core/error.h"
#include "grid/coordinates.h"
#include "render/resolve_state.h"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <filesystem>

namespace raypc::render {

int pairedStep(const dataset::Dataset& first, int step, const dataset::Dataset& second, state::PairSteps steps)
{
    first.checkStep(step);
    const auto& theirs = second.steps();
    if (steps == state::PairSteps::Index)
        return std::min(step, int(theirs.size()) - 1);
    const double timeMyr = first.steps()[size_t(step)].timeMyr;
    int nearest = 0;
    for (int s = 1; s < int(theirs.size()); ++s)
        if (std::abs(theirs[size_t(s)].timeMyr - timeMyr) < std::abs(theirs[size_t(nearest)].timeMyr - timeMyr))
            nearest = s;
    return nearest;
}

PairedState secondOfPair(state::RenderState state, const dataset::Dataset& first, const dataset::Dataset& second)
{
    // The first's resolution names the colour variable and gives the ranges in effect there.
    const ResolvedState ofFirst = resolveState(state, first);
    const std::string colorName = first.variableNames()[size_t(ofFirst.params.colorVariable)];
    PairedState out;
    auto note = [&](std::string text) { out.notes.push_back(std::move(text)); };
    const auto has = [&](const std::string& name) { return second.variableIndex(name) >= 0; };
    const auto hasAxis = [&](const std::string& name) { return has(name) || grid::findCoordinate(name).has_value(); };

    const state::PairSteps steps = state.pair ? state.pair->steps : state::PairSteps::Time;
    state.step = pairedStep(first, state.step, second, steps);
    if (state.level && *state.level >= int(second.levels().size())) {
        note(fmt::format("level {}: the second dataset has {} levels; its coarsest is drawn", *state.level,
                         second.levels().size()));
        state.level = int(second.levels().size()) - 1;
    }
    if (has(colorName)) {
        state.colorVariable = colorName;
        state.colorRange = ofFirst.params.transfer.range;
    } else {
        note(fmt::format("colour: the second dataset has no '{}'; coloured by '{}'", colorName,
                         second.variableNames().front()));
        state.colorVariable.clear();
        state.colorRange.reset();
        state.logScale = false;
    }
    if (!state.core.variable.empty()) {
        if (has(state.core.variable)) {
            state.core.range = ofFirst.params.core.range;
        } else {
            note(fmt::format("core: the second dataset has no '{}'; plain colour", state.core.variable));
            state.core.variable.clear();
            state.core.range.reset();
        }
    }
    // A repeated name is one axis (its ranges OR-ed): one note for it.
    std::vector<std::string> dropped;
    std::erase_if(state.brushes, [&](const analysis::NamedRange& b) {
        if (hasAxis(b.name))
            return false;
        if (std::find(dropped.begin(), dropped.end(), b.name) == dropped.end()) {
            dropped.push_back(b.name);
            note(fmt::format("brush on '{}' left out: the second dataset has no such variable", b.name));
        }
        return true;
    });
    const std::vector<std::string> columns = analysis::pathlineColumns(second.variableNames());
    auto hasColumn = [&](const std::string& name) { return std::find(columns.begin(), columns.end(), name) != columns.end(); };
    if (state.pathlines.colorBy != "age" && !hasColumn(state.pathlines.colorBy)) {
        note(fmt::format("pathlines: the second dataset's lines have no '{}'; coloured by age", state.pathlines.colorBy));
        state.pathlines.colorBy = "age";
        state.pathlines.range.reset();
        state.pathlines.colorMap.reset();
    }
    std::erase_if(state.pathlines.filters, [&](const analysis::NamedRange& f) {
        if (hasColumn(f.name))
            return false;
        note(fmt::format("pathline filter on '{}' left out: the second dataset's lines have no such attribute", f.name));
        return true;
    });
    if (state.pathlines.visible && !std::filesystem::exists(analysis::pathlineDir(second.dir(), 0) / "lines.json")) {
        note("pathlines: the second dataset has none");
        state.pathlines.visible = false;
    }
    out.state = std::move(state);
    return out;
}

PairHalves pairHalves(state::RenderState state, const dataset::Dataset& first, const dataset::Dataset& second)
{
    if (state.width < 2)
        fail("image.width: {} pixels cannot be split between a pair's two datasets; expected at least 2", state.width);
    const int leftWidth = state.width / 2, rightWidth = state.width - leftWidth;
    state.width = leftWidth;
    PairHalves halves{state, secondOfPair(state, first, second)};
    halves.right.state.width = rightWidth;
    return halves;
}

ImageRgba8 sideBySide(const ImageRgba8& left, const ImageRgba8& right)
{
    RAYPC_CHECK_EQ(left.height, right.height);
    ImageRgba8 out;
    out.width = left.width + right.width;
    out.height = left.height;
    out.pixels.resize(size_t(out.width) * size_t(out.height) * 4);
    for (int y = 0; y < out.height; ++y) {
        uint8_t* row = out.pixels.data() + size_t(y) * size_t(out.width) * 4;
        std::copy_n(left.pixels.data() + size_t(y) * size_t(left.width) * 4, size_t(left.width) * 4, row);
        std::copy_n(right.pixels.data() + size_t(y) * size_t(right.width) * 4, size_t(right.width) * 4,
                    row + size_t(left.width) * 4);
    }
    return out;
}

}  // namespace raypc::render
