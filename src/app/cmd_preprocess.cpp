// raypc preprocess INPUT... -o DATASET_DIR
#include "app/command.h"
#include "app/options.h"
#include "data/preprocess.h"

#include <fmt/format.h>

namespace raypc::app {
namespace {

struct PreprocessArgs {
    std::vector<std::string> inputs;
    std::string output;
    ReaderFlags reader;
    PreprocessOptions options;
    bool noPathlines = false, noSaddles = false;
};

const CommandRegistration kRegistration(
    "preprocess", "Turn netCDF snapshots into a render-ready dataset (resumable)",
    [](CLI::App& cmd) {
        auto args = std::make_shared<PreprocessArgs>();
        cmd.add_option("inputs", args->inputs, "netCDF files, or directories of *.nc (steps in natural order)")
            ->required();
        cmd.add_option("-o,--output", args->output, "Dataset directory to write")->required();
        cmd.add_option("--dt-myr", args->options.dtMyr, "Time between steps in Myr")->capture_default_str();
        cmd.add_option("--sample-rows", args->options.sampleRows, "Cells in the parallel-coordinates sample")
            ->capture_default_str();
        cmd.add_option("--seed", args->options.seed, "Seed of the sample")->capture_default_str();
        cmd.add_flag("-q,--quiet", args->options.quiet, "No progress output");
        auto& pl = args->options.pathlines;
        cmd.add_flag("--no-pathlines", args->noPathlines,
                     "Skip the critical points of --pathline-field and the pathlines seeded there");
        cmd.add_option("--pathline-field", pl.field, "Variable whose critical points seed pathlines")
            ->capture_default_str();
        cmd.add_option("--pathline-steps", pl.steps, "Steps each pathline is traced forward")->capture_default_str();
        cmd.add_option("--cp-min-abs", pl.filter.minAbsValue,
                       "Critical points: keep maxima >= V, minima <= -V, saddles |value| >= V (field units)")
            ->capture_default_str();
        cmd.add_option("--cp-min-fraction", pl.filter.minFractionOfMaxAbs,
                       "Critical points: the threshold is at least this fraction of the step's largest |value|")
            ->capture_default_str();
        cmd.add_option("--cp-max-count", pl.filter.maxCount,
                       "Critical points: at most this many per step (the largest |value| first)")
            ->capture_default_str();
        cmd.add_flag("--cp-no-saddles", args->noSaddles, "Critical points: seed pathlines at extrema only");
        args->reader.add(cmd);
        cmd.callback([args] {
            std::vector<std::filesystem::path> inputs(args->inputs.begin(), args->inputs.end());
            auto options = args->options;
            options.reader = args->reader.toOptions();
            options.pathlines.enabled = !args->noPathlines;
            options.pathlines.filter.saddles = !args->noSaddles;
            const auto files = listSnapshotFiles(inputs);
            const auto summary = preprocess(files, args->output, options);
            const auto dataset = Dataset::open(args->output);
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
    },
    20);

}  // namespace
}  // namespace raypc::app
