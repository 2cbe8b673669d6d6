// raypc preprocess INPUT... -o DATASET_DIR
#include "app/command.h"
#include "app/options.h"
#include "core/error.h"
#include "core/mpi.h"
#include "core/spare_blocks.h"
#include "core/system_memory.h"
#include "preprocess/preprocess.h"
#include "io/series_input.h"

#include <fmt/format.h>

namespace raypc::app {
namespace {

struct PreprocessArgs {
    std::vector<std::string> inputs;
    std::string output;
    PreprocessFlags flags;
};

const CommandRegistration kPreprocessCommand(
    "preprocess", "Turn netCDF snapshots or an ASPECT (VTK XML) series into a render-ready dataset (resumable)",
    [](CLI::App& cmd) {
        auto args = std::make_shared<PreprocessArgs>();
        cmd.add_option("inputs", args->inputs,
                       "netCDF files or directories of *.nc (steps in natural order); or ASPECT's output: solution.pvd, "
                       "its directory, or .pvtu / .vtu steps (resampled onto a spherical grid, see --grid)")
            ->required();
        cmd.add_option("-o,--output", args->output, "Dataset directory to write")->required();
        args->flags.add(cmd);
        cmd.callback([args, &cmd] {
            std::vector<std::filesystem::path> files;
            preprocess::PreprocessOptions options;
            mpi::together([&] {
                options = args->flags.toOptions(cmd);
                io::SeriesListing listing =
                    io::listSeries(std::vector<std::filesystem::path>(args->inputs.begin(), args->inputs.end()), options.reader);
                files = std::move(listing.steps);
                options.timesMyr = std::move(listing.timesMyr);
            });
            // Every step allocates and frees the same arrays of tens of MB: reused from the heap,
            // their pages are not faulted and zeroed by the kernel again for each step. So are the
            // blocks the pathlines decode each step's velocity and seed field into (core/spare_blocks.h).
            keepLargeBlocksForReuse();
            reuseGivenBackBlocks(kMaxSpareBytes);
            // Under mpirun every rank takes steps (preprocess.h); rank 0 reports.
            const auto summary = preprocess::preprocess(files, args->output, options);
            mpi::together([&] {
                if (!mpi::isRoot())
                    return;
                const auto dataset = dataset::Dataset::open(args->output);
                const auto& g = dataset->levels().front().grid;
                fmt::print("{}: {} steps ({} written, {} already done) of {}x{}x{} (lat x r x lon), {} variables, "
                           "in {:.1f} s\n",
                           args->output, dataset->steps().size(), summary.stepsWritten, summary.stepsSkipped, g.nLat(),
                           g.nR(), g.nLon(), dataset->variables().size(), summary.seconds);
                if (options.pathlines.enabled)
                    fmt::print("{}: pathlines of {} steps ({} written with {} lines, {} already done)\n", args->output,
                               dataset->steps().size(), summary.pathlineSetsWritten, summary.pathlineCount,
                               summary.pathlineSetsSkipped);
            });
        });
    },
    20, Ranks::AllRanks);

}  // namespace
}  // namespace raypc::app
