// raypc preprocess INPUT... -o DATASET_DIR
#include "app/command.h"
#include "app/options.h"
#include "core/error.h"
#include "core/mpi.h"
#include "data/preprocess.h"

#include <fmt/format.h>

namespace raypc::app {
namespace {

struct PreprocessArgs {
    std::vector<std::string> inputs;
    std::string output;
    ReaderFlags reader;
    PreprocessOptions options;
    bool noPathlines = false;
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
        cmd.add_option_function<std::string>(
               "--encoding",
               [args](const std::string& text) { args->options.encoding = parseEncoding(text, "--encoding"); },
               "Level arrays: 'u16' (quantised per brick, error <= brick range / 131070; half the size) or "
               "'float32' (exact)")
            ->default_str(std::string(encodingName(args->options.encoding)));
        auto& pl = args->options.pathlines;
        cmd.add_flag("--no-pathlines", args->noPathlines,
                     "Skip the critical points of --pathline-field and the pathlines seeded there");
        cmd.add_option("--pathline-field", pl.field, "Variable whose critical points seed pathlines")
            ->capture_default_str();
        cmd.add_option("--pathline-steps", pl.steps, "Steps each pathline is traced forward")->capture_default_str();
        cmd.add_option_function<std::string>(
               "--cp-select",
               [args](const std::string& text) { args->options.pathlines.filter.rule = parseSeedRule(text); },
               "Seeds: 'persistence' (extrema of persistent pairs) or 'value' (the largest |value|)")
            ->default_str(seedRuleName(pl.filter.rule));
        cmd.add_option_function<std::string>(
               "--cp-persistence",
               [args](const std::string& text) { parsePersistenceThreshold(text, args->options.pathlines.filter); },
               "Seeds by persistence: extrema whose persistence exceeds K (field units) or P% of the step's range")
            ->default_str("5%");
        cmd.add_option("--cp-min-abs", pl.filter.minAbsValue,
                       "Seeds by value: keep maxima >= V, minima <= -V, saddles |value| >= V (field units)")
            ->capture_default_str();
        cmd.add_option("--cp-min-fraction", pl.filter.minFractionOfMaxAbs,
                       "Seeds by value: the threshold is at least this fraction of the step's largest |value|")
            ->capture_default_str();
        cmd.add_option("--cp-max-count", pl.filter.maxCount,
                       "Seeds: at most this many per step (the most persistent, or the largest |value|, first)")
            ->capture_default_str();
        cmd.add_flag("--cp-saddles,!--cp-no-saddles", pl.filter.saddles,
                     "Seeds: also at saddles (by persistence: those paired with the kept extrema); "
                     "default: extrema only");
        args->reader.add(cmd);
        cmd.callback([args, &cmd] {
            std::vector<std::filesystem::path> files;
            auto options = args->options;
            mpi::together([&] {
                // An option of the other seed rule would be silently ignored.
                const bool byValue = args->options.pathlines.filter.rule == SeedRule::Value;
                for (const char* option : {"--cp-persistence", "--cp-min-abs", "--cp-min-fraction"})
                    if (cmd.count(option) && byValue == (option == std::string("--cp-persistence")))
                        fail("{}: applies to seeds chosen by {}, but --cp-select is {}", option,
                             byValue ? "persistence" : "value", seedRuleName(args->options.pathlines.filter.rule));
                std::vector<std::filesystem::path> inputs(args->inputs.begin(), args->inputs.end());
                options.reader = args->reader.toOptions();
                options.pathlines.enabled = !args->noPathlines;
                files = listSnapshotFiles(inputs);
            });
            // Under mpirun every rank takes steps (preprocess.h); rank 0 reports.
            const auto summary = preprocess(files, args->output, options);
            mpi::together([&] {
                if (!mpi::isRoot())
                    return;
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
        });
    },
    20, Ranks::AllRanks);

}  // namespace
}  // namespace raypc::app
