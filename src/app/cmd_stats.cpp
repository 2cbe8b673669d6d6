// raypc stats DATASET --state S.json -o stats.csv: the selected volume of every step, exactly.
#include "app/command.h"
#include "app/options.h"
#include "core/atomic_file.h"
#include "core/error.h"
#include "core/mpi.h"
#include "core/progress.h"
#include "core/spherical.h"
#include "data/dataset.h"
#include "data/selection.h"
#include "render/render_state.h"

#include <fmt/format.h>

#include <optional>

namespace raypc::app {
namespace {

struct StatsArgs {
    std::string dataset, statePath, output, profile, time;
    std::vector<std::string> ranges;
    int level = 0;
    bool quiet = false;
};

// The CSV rows of the steps in `selections`: the selected volume, and its depth profile.
struct StatsRows {
    std::string csv, profile;
};
StatsRows formatRows(const std::vector<StepSelection>& selections, const SphericalGrid& grid)
{
    StatsRows rows;
    for (const StepSelection& sel : selections) {
        const SelectionStats& s = sel.stats;
        const int step = sel.step;
        const double t = sel.timeMyr;
        fmt::format_to(std::back_inserter(rows.csv), "{},{},{:.6e},{:.6f}\n", step, t, s.volumeKm3,
                       100.0 * s.fractionOfMantle);
        for (size_t iR = 0; iR < grid.nR(); ++iR) {
            const double shell = s.shellVolumeByRadiusKm3[iR];
            fmt::format_to(std::back_inserter(rows.profile), "{},{},{:.3f},{:.3f},{:.6e},{:.6e},{:.6f}\n", step, t,
                           grid.rKm[iR], kSurfaceRadiusKm - grid.rKm[iR], s.volumeByRadiusKm3[iR], shell,
                           100.0 * s.volumeByRadiusKm3[iR] / shell);
        }
    }
    return rows;
}

// Under mpirun the steps are split into contiguous blocks over the ranks (every step costs the
// same); rank 0 gathers the rows in rank order, which is step order, and writes the files.
void run(const StatsArgs& args)
{
    std::shared_ptr<const Dataset> dataset;
    std::vector<RangeFilter> filters;
    int first = 0, last = 0;
    mpi::together([&] {
        dataset = Dataset::open(args.dataset);
        std::vector<NamedRange> ranges;
        if (!args.statePath.empty())
            ranges = render::loadRenderState(args.statePath).brushes;
        applyRangeOptions(ranges, args.ranges);
        filters = resolveRangeFilters(*dataset, ranges, args.statePath.empty() ? "--range" : "brushes");
        dataset->checkLevel(args.level, "--lod");
        std::tie(first, last) = args.time.empty()
                                    ? std::pair<int, int>(0, static_cast<int>(dataset->steps().size()) - 1)
                                    : parseStepRange(*dataset, args.time);
    });
    const SphericalGrid& grid = dataset->levels()[args.level].grid;
    const mpi::Block block = mpi::blockOf(last - first + 1);

    StatsRows mine;
    std::optional<Progress> progress;
    if (!args.quiet && mpi::isRoot())
        progress.emplace(mpi::distributed() ? fmt::format("stats (rank 0 of {})", mpi::size()) : "stats",
                         block.end - block.begin, "steps");
    mpi::together([&] {
        if (block.end > block.begin) {
            const auto selections = selectionOverTime(*dataset, filters, args.level, first + int(block.begin),
                                                      first + int(block.end) - 1, {}, [&] {
                                                          if (progress)
                                                              progress->advance();
                                                      });
            mine = formatRows(selections, grid);
        }
    });
    if (progress)
        progress->finish();
    const auto csvParts = mpi::gatherToRoot(mine.csv);
    const auto profileParts = mpi::gatherToRoot(mine.profile);
    mpi::together([&] {
        if (!mpi::isRoot())
            return;
        std::string csv = "step,time_myr,selected_volume_km3,selected_percent_of_mantle\n";
        std::string profile =
            "step,time_myr,radius_km,depth_km,selected_volume_km3,shell_volume_km3,selected_percent_of_shell\n";
        for (const auto& part : csvParts)
            csv += part;
        for (const auto& part : profileParts)
            profile += part;
        writeFileAtomic(args.output, csv);
        if (!args.profile.empty())
            writeFileAtomic(args.profile, profile);
        fmt::print("{}: selected volume of {} steps ({}..{}) for {} range(s){}{}\n", args.output, last - first + 1,
                   first, last, filters.size(),
                   args.profile.empty() ? "" : fmt::format("; depth profile in {}", args.profile),
                   mpi::distributed() ? fmt::format(" on {} ranks", mpi::size()) : "");
    });
}

const CommandRegistration kStatsCommand(
    "stats",
    "Selected volume (km³, % of the mantle) and its depth distribution for every step, exact from the grid",
    [](CLI::App& cmd) {
        auto args = std::make_shared<StatsArgs>();
        cmd.add_option("dataset", args->dataset, "Dataset directory")->required();
        cmd.add_option("--state", args->statePath, "STATE.json whose brushes define the selection");
        cmd.add_option("--range", args->ranges, "Brush NAME=MIN:MAX on a variable or coordinate; repeatable, overrides the state");
        cmd.add_option("-o,--output", args->output, "CSV: step, time, selected volume, percent of the mantle")->required();
        cmd.add_option("--profile", args->profile, "CSV: selected volume per radius (depth distribution) of every step");
        cmd.add_option("-t,--time", args->time, "Steps A or A:B (index or time like 24Myr); default all");
        cmd.add_option("--lod", args->level, "Level of detail (0 = full resolution, exact)")->capture_default_str();
        cmd.add_flag("-q,--quiet", args->quiet, "No progress output");
        cmd.callback([args] { run(*args); });
    },
    70, Ranks::AllRanks);

}  // namespace
}  // namespace raypc::app
