// raypc stats DATASET --state S.json -o stats.csv [--profile p.csv [--profile-var NAME]]: the selected
// volume of every step, exactly; its depth profile, and a variable's mean per depth.
#include "app/command.h"
#include "app/options.h"
#include "core/atomic_file.h"
#include "core/error.h"
#include "core/mpi.h"
#include "core/progress.h"
#include "core/spherical.h"
#include "data/dataset.h"
#include "data/selection.h"

#include <fmt/format.h>
#include <fmt/ranges.h>

#include <cmath>
#include <optional>

namespace raypc::app {
namespace {

struct StatsArgs {
    SeriesSelectionFlags selection;
    std::string output, profile, profileVar;
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
            fmt::format_to(std::back_inserter(rows.profile), "{},{},{:.3f},{:.3f},{:.6e},{:.6e},{:.6f}", step, t,
                           grid.rKm[iR], kSurfaceRadiusKm - grid.rKm[iR], s.volumeByRadiusKm3[iR], shell,
                           100.0 * s.volumeByRadiusKm3[iR] / shell);
            // The mean variable's columns (empty where nothing is selected).
            if (!s.shellMeanByRadius.empty()) {
                const double selected = s.selectedMeanByRadius[iR];
                fmt::format_to(std::back_inserter(rows.profile), ",{},{:.9g}",
                               std::isnan(selected) ? std::string() : fmt::format("{:.9g}", selected), s.shellMeanByRadius[iR]);
            }
            rows.profile += '\n';
        }
    }
    return rows;
}

// Under mpirun the steps are split into contiguous blocks over the ranks (every step costs the
// same); rank 0 gathers the rows in rank order, which is step order, and writes the files.
void run(const StatsArgs& args)
{
    SeriesSelection sel;
    mpi::together([&] { sel = resolveSeriesSelection(args.selection); });
    const Dataset& dataset = *sel.dataset;
    const std::vector<RangeFilter>& filters = sel.filters;
    const int first = sel.first, last = sel.last, level = args.selection.level;
    const SphericalGrid& grid = dataset.levels()[size_t(level)].grid;
    const mpi::Block block = mpi::blockOf(last - first + 1);
    std::optional<size_t> meanVariable;
    if (!args.profileVar.empty()) {
        if (args.profile.empty())
            fail("--profile-var: needs --profile (the depth profile it adds columns to)");
        const int index = dataset.variableIndex(args.profileVar);
        if (index < 0)
            fail("--profile-var: unknown variable '{}'; the dataset has: {}", args.profileVar,
                 fmt::join(dataset.variableNames(), ", "));
        meanVariable = size_t(index);
    }

    StatsRows mine;
    std::optional<Progress> progress;
    if (!args.quiet && mpi::isRoot())
        progress.emplace(mpi::distributed() ? fmt::format("stats (rank 0 of {})", mpi::size()) : "stats",
                         block.end - block.begin, "steps");
    mpi::together([&] {
        if (block.end > block.begin) {
            const auto selections = selectionOverTime(dataset, filters, level, first + int(block.begin),
                                                      first + int(block.end) - 1, {}, [&] {
                                                          if (progress)
                                                              progress->advance();
                                                      }, meanVariable);
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
        std::string profile = "step,time_myr,radius_km,depth_km,selected_volume_km3,shell_volume_km3,selected_percent_of_shell";
        if (meanVariable) {
            const VariableInfo& v = dataset.variables()[*meanVariable];
            profile += fmt::format(",{0} selected mean [{1}],{0} shell mean [{1}]", v.name, v.units);
        }
        profile += '\n';
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
        args->selection.add(cmd);
        cmd.add_option("-o,--output", args->output, "CSV: step, time, selected volume, percent of the mantle")->required();
        cmd.add_option("--profile", args->profile, "CSV: selected volume per radius (depth distribution) of every step");
        cmd.add_option("--profile-var", args->profileVar,
                       "With --profile: also this variable's volume-weighted mean per radius over the selection and over "
                       "the whole shell (a time-depth view of it)");
        cmd.add_flag("-q,--quiet", args->quiet, "No progress output");
        cmd.callback([args] { run(*args); });
    },
    70, Ranks::AllRanks);

}  // namespace
}  // namespace raypc::app
