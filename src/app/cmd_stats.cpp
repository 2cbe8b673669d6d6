// raypc stats DATASET --state S.json -o stats.csv: the selected volume of every step, exactly.
#include "app/command.h"
#include "app/options.h"
#include "core/atomic_file.h"
#include "core/error.h"
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

void run(const StatsArgs& args)
{
    const auto dataset = Dataset::open(args.dataset);
    std::vector<NamedRange> ranges;
    if (!args.statePath.empty())
        ranges = render::loadRenderState(args.statePath).brushes;
    applyRangeOptions(ranges, args.ranges);
    const auto filters = resolveRangeFilters(*dataset, ranges, args.statePath.empty() ? "--range" : "brushes");
    dataset->checkLevel(args.level, "--lod");
    const auto [first, last] = args.time.empty() ? std::pair<int, int>(0, static_cast<int>(dataset->steps().size()) - 1)
                                                 : parseStepRange(*dataset, args.time);

    const SphericalGrid& grid = dataset->levels()[args.level].grid;

    std::string csv = "step,time_myr,selected_volume_km3,selected_percent_of_mantle\n";
    std::string profile = "step,time_myr,radius_km,depth_km,selected_volume_km3,shell_volume_km3,selected_percent_of_shell\n";
    std::optional<Progress> progress;
    if (!args.quiet)
        progress.emplace("stats", last - first + 1, "steps");
    const auto selections = selectionOverTime(*dataset, filters, args.level, first, last, {}, [&] {
        if (progress)
            progress->advance();
    });
    for (const StepSelection& sel : selections) {
        const SelectionStats& s = sel.stats;
        const int step = sel.step;
        const double t = sel.timeMyr;
        fmt::format_to(std::back_inserter(csv), "{},{},{:.6e},{:.6f}\n", step, t, s.volumeKm3, 100.0 * s.fractionOfMantle);
        for (size_t iR = 0; iR < grid.nR(); ++iR) {
            const double shell = s.shellVolumeByRadiusKm3[iR];
            fmt::format_to(std::back_inserter(profile), "{},{},{:.3f},{:.3f},{:.6e},{:.6e},{:.6f}\n", step, t, grid.rKm[iR],
                           kSurfaceRadiusKm - grid.rKm[iR], s.volumeByRadiusKm3[iR], shell,
                           100.0 * s.volumeByRadiusKm3[iR] / shell);
        }
    }
    if (progress)
        progress->finish();
    writeFileAtomic(args.output, csv);
    if (!args.profile.empty())
        writeFileAtomic(args.profile, profile);
    fmt::print("{}: selected volume of {} steps ({}..{}) for {} range(s){}\n", args.output, last - first + 1, first, last,
               filters.size(), args.profile.empty() ? "" : fmt::format("; depth profile in {}", args.profile));
}

const CommandRegistration kRegistration(
    "stats",
    "Selected volume (km³, % of the mantle) and its depth distribution for every step, exact from the grid",
    [](CLI::App& cmd) {
        auto args = std::make_shared<StatsArgs>();
        cmd.add_option("dataset", args->dataset, "Dataset directory")->required();
        cmd.add_option("--state", args->statePath, "STATE.json whose brushes define the selection");
        cmd.add_option("--range", args->ranges, "Brush NAME=MIN:MAX on a variable or coordinate; repeatable, a name given twice selects "
                       "either range (OR); replaces the state's ranges of that name");
        cmd.add_option("-o,--output", args->output, "CSV: step, time, selected volume, percent of the mantle")->required();
        cmd.add_option("--profile", args->profile, "CSV: selected volume per radius (depth distribution) of every step");
        cmd.add_option("-t,--time", args->time, "Steps A or A:B (index or time like 24Myr); default all");
        cmd.add_option("--lod", args->level, "Level of detail (0 = full resolution, exact)")->capture_default_str();
        cmd.add_flag("-q,--quiet", args->quiet, "No progress output");
        cmd.callback([args] { run(*args); });
    },
    70);

}  // namespace
}  // namespace raypc::app
