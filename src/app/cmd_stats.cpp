// raypc stats DATASET --state S.json -o stats.csv [--profile p.csv] [--profile-var NAME]
// [--hovmoller hov.png [--hovmoller-of share|selected-mean|shell-mean] [--depth KM]... [--size WxH]]:
// the selected volume of every step, exactly; its depth profile, a variable's mean per depth, and
// a time–depth picture of either.
#include "app/command.h"
#include "app/options.h"
#include "core/atomic_file.h"
#include "core/error.h"
#include "core/mpi.h"
#include "core/progress.h"
#include "core/spherical.h"
#include "core/system_memory.h"
#include "dataset/dataset.h"
#include "grid/names.h"
#include "analysis/feature_csv.h"
#include "analysis/selection.h"
#include "render/image_io.h"
#include "render/legend.h"
#include "state/render_state.h"
#include "render/time_depth_view.h"
#include "render/state_renderer.h"

#include <fmt/format.h>
#include <fmt/ranges.h>

#include <cmath>
#include <optional>

namespace raypc::app {
namespace {

struct StatsArgs {
    SeriesSelectionFlags selection;
    std::string output, profile, profileVar;
    std::string hovmoller, hovmollerOf = "share", size = "960x540";
    std::vector<double> depthsKm;
    bool pictureOptionsGiven = false;  // --hovmoller-of, --depth or --size on the command line
    bool quiet = false;
};

// The CSV rows of the steps in `selections`: the selected volume, and its depth profile.
struct StatsRows {
    std::string csv, profile;
};
StatsRows formatRows(const std::vector<analysis::StepSelection>& selections, const grid::SphericalGrid& grid)
{
    StatsRows rows;
    for (const analysis::StepSelection& sel : selections)
        fmt::format_to(std::back_inserter(rows.csv), "{},{},{:.6e},{:.6f}\n", sel.step, sel.timeMyr,
                       sel.stats.volumeKm3, 100.0 * sel.stats.fractionOfMantle);
    rows.profile = analysis::profileCsvRows(selections, grid);
    return rows;
}

// Under mpirun the steps are split into contiguous blocks over the ranks (every step costs the
// same); rank 0 gathers the rows in rank order, which is step order, and writes the files.
void run(const StatsArgs& args)
{
    SeriesSelection sel;
    mpi::together([&] {
        checkOutputExtension(args.output, {".csv", ".txt"}, "CSV", "-o");
        if (!args.profile.empty())
            checkOutputExtension(args.profile, {".csv", ".txt"}, "CSV", "--profile");
        if (!args.hovmoller.empty())
            checkOutputExtension(args.hovmoller, {".png"}, "PNG", "--hovmoller");
        sel = resolveSeriesSelection(args.selection);
    });
    const dataset::Dataset& dataset = *sel.dataset;
    const std::vector<analysis::RangeFilter>& filters = sel.filters;
    const int first = sel.first, last = sel.last, level = args.selection.level;
    const grid::SphericalGrid& grid = dataset.levels()[size_t(level)].grid;
    const mpi::Block block = mpi::blockOf(last - first + 1);
    std::optional<size_t> meanVariable;
    const render::TimeDepthOf hovmollerOf = render::parseTimeDepthOf(args.hovmollerOf, "--hovmoller-of");
    // Plain variables, not a structured binding: the lambda below captures them (clang 14 cannot
    // capture bindings).
    const std::pair<int, int> pictureSize = parseSize(args.size);
    const int pictureWidth = pictureSize.first, pictureHeight = pictureSize.second;
    if (!args.hovmoller.empty()) {
        render::checkTimeDepthPictureSize(pictureWidth, pictureHeight);
        // Before anything is allocated, as for `raypc render`: a picture larger than memory is
        // refused with the figures.
        state::RenderState pictureState;
        pictureState.width = pictureWidth;
        pictureState.height = pictureHeight;
        render::checkPictureFitsMemory(pictureState, false, availableMemory());
    }
    if (args.hovmoller.empty() && args.pictureOptionsGiven)
        fail("--hovmoller-of, --depth: need --hovmoller (the picture they describe, as --size does)");
    if (hovmollerOf != render::TimeDepthOf::Share && args.profileVar.empty())
        fail("--hovmoller-of {}: needs --profile-var NAME (the variable whose mean it shows)", args.hovmollerOf);
    for (const double d : args.depthsKm)
        if (!(d > 0 && d < kSurfaceRadiusKm))
            fail("--depth {}: expected a depth in km between 0 and {}", d, kSurfaceRadiusKm);
    if (!args.profileVar.empty()) {
        if (args.profile.empty() && args.hovmoller.empty())
            fail("--profile-var: needs --profile or --hovmoller (the depth profile or picture it adds to)");
        const int index = dataset.variableIndex(args.profileVar);
        if (index < 0)
            fail("--profile-var: unknown variable '{}'; the dataset has: {}", args.profileVar,
                 fmt::join(dataset.variableNames(), ", "));
        meanVariable = size_t(index);
    }

    StatsRows mine;
    std::vector<float> hovmollerMine;
    std::optional<Progress> progress;
    if (!args.quiet && mpi::isRoot())
        progress.emplace(mpi::distributed() ? fmt::format("stats (rank 0 of {})", mpi::size()) : "stats",
                         block.end - block.begin, "steps");
    mpi::together([&] {
        if (block.end > block.begin) {
            const auto selections = analysis::selectionOverTime(dataset, filters, level, first + int(block.begin),
                                                      first + int(block.end) - 1, {}, [&] {
                                                          if (progress)
                                                              progress->advance();
                                                      }, meanVariable);
            mine = formatRows(selections, grid);
            if (!args.hovmoller.empty())
                render::appendTimeDepthValues(selections, hovmollerOf, hovmollerMine);
        }
    });
    if (progress)
        progress->finish();
    const auto csvParts = mpi::gatherToRoot(mine.csv);
    const auto profileParts = mpi::gatherToRoot(mine.profile);
    const std::vector<float> hovmollerValues = args.hovmoller.empty() ? std::vector<float>{} : mpi::gatherToRoot(hovmollerMine);
    mpi::together([&] {
        if (!mpi::isRoot())
            return;
        // The columns as src/grid/names.json names them (Python's Dataset.stats and the UI too).
        std::string csv = columns::csvHeader(columns::kSelectionOverTime) + '\n';
        std::string profile = analysis::profileCsvHeader(meanVariable ? &dataset.variables()[*meanVariable] : nullptr);
        for (const auto& part : csvParts)
            csv += part;
        for (const auto& part : profileParts)
            profile += part;
        // The picture first: a picture that cannot be drawn leaves no file written.
        std::optional<render::ImageRgba8> picture;
        if (!args.hovmoller.empty()) {
            render::TimeDepthInputs in = render::timeDepthInputs(
                dataset, first, last, level, hovmollerValues, hovmollerOf,
                meanVariable ? &dataset.variables()[*meanVariable] : nullptr, filters.size());
            in.width = pictureWidth;
            in.height = pictureHeight;
            if (!args.selection.statePath.empty())
                in.marks = state::loadRenderState(args.selection.statePath).reference.shells;
            in.marks.visible = true;
            if (!args.depthsKm.empty())
                in.marks.depthsKm.assign(args.depthsKm.begin(), args.depthsKm.end());
            picture = render::timeDepthPicture(in);
        }
        writeFileAtomic(args.output, csv);
        if (!args.profile.empty())
            writeFileAtomic(args.profile, profile);
        if (picture)
            render::writePng(args.hovmoller, *picture);
        fmt::print("{}: selected volume of {} steps ({}..{}) for {} range(s){}{}\n", args.output, last - first + 1,
                   first, last, filters.size(),
                   (args.profile.empty() ? "" : fmt::format("; depth profile in {}", args.profile)) +
                       (args.hovmoller.empty() ? "" : fmt::format("; time-depth picture in {}", args.hovmoller)),
                   mpi::distributed() ? fmt::format(" on {} ranks", mpi::size()) : "");
    });
}

const CommandRegistration kStatsCommand(
    "stats",
    "Selected volume (km³, % of the mantle) and its depth distribution for every step, exact from the grid",
    [](CLI::App& cmd) {
        auto args = std::make_shared<StatsArgs>();
        args->selection.add(cmd);
        cmd.add_option("-o,--output", args->output, "CSV: step, time, selected volume, percent of the mantle")->required();
        cmd.add_option("--profile", args->profile, "CSV: selected volume per radius (depth distribution) of every step");
        cmd.add_option("--profile-var", args->profileVar,
                       "With --profile: also this variable's volume-weighted mean per radius over the selection and over "
                       "the whole shell (a time-depth view of it); with --hovmoller: the variable of its means");
        cmd.add_option("--hovmoller", args->hovmoller,
                       "PNG: a time-depth (Hovmoller) picture of every step's depth profile, the chosen depths marked");
        const auto* of = cmd.add_option("--hovmoller-of", args->hovmollerOf,
                       "What the picture shows: share (of each shell selected, %), selected-mean or shell-mean (of "
                       "--profile-var)")
            ->default_str("share");
        const auto* depth = cmd.add_option("--depth", args->depthsKm, "Depth in km marked on the picture; repeatable (default: the state's "
                                                 "reference shells, 410, 660, 1000, 1600, 2200)");
        const auto* size = cmd.add_option("--size", args->size, "The picture's size WIDTHxHEIGHT")->default_str("960x540");
        cmd.add_flag("-q,--quiet", args->quiet, "No progress output");
        cmd.callback([args, of, depth, size] {
            args->pictureOptionsGiven = of->count() > 0 || depth->count() > 0 || size->count() > 0;
            run(*args);
        });
    },
    70, Ranks::AllRanks);

}  // namespace
}  // namespace raypc::app
