// raypc diff A B -o D.ds | raypc diff A --steps k -o D.ds: a difference dataset (preprocess/difference.h).
#include "app/command.h"
#include "core/error.h"
#include "dataset/dataset.h"
#include "dataset/value_encoding.h"
#include "preprocess/difference.h"

#include <fmt/format.h>

namespace raypc::app {
namespace {

struct DiffArgs {
    std::vector<std::string> datasets;
    std::string output, match = "index", encoding;
    std::vector<std::string> variables;
    int steps = 0;
    bool quiet = false;
};

const CommandRegistration kDiffCommand(
    "diff",
    "A difference dataset: A − B on A's grid (B regridded by the sampler where its grid differs), or a dataset's "
    "step differences X(t) − X(t−k) (--steps k)",
    [](CLI::App& cmd) {
        auto args = std::make_shared<DiffArgs>();
        cmd.add_option("datasets", args->datasets, "Dataset A, then dataset B (B left out with --steps)")
            ->required()
            ->expected(1, 2);
        cmd.add_option("-o,--output", args->output, "Dataset directory to write (the difference)")->required();
        cmd.add_option("--variable", args->variables,
                       "A variable to difference (repeatable; default: the stored variables both have)");
        cmd.add_option("--match", args->match, "Pair the steps of A and B by 'index' or by 'time' (Myr)")
            ->capture_default_str();
        cmd.add_option("--steps", args->steps, "Step differences X(t) − X(t−k) of dataset A for t >= k (k >= 1)");
        cmd.add_option("--encoding", args->encoding, "Level arrays: 'u16' (quantised per brick) or 'float32' (exact)")
            ->default_str("u16");
        cmd.add_flag("-q,--quiet", args->quiet, "No progress output");
        cmd.callback([args] {
            preprocess::DifferenceRequest request;
            request.a = args->datasets.front();
            if (args->datasets.size() == 2)
                request.b = args->datasets[1];
            request.variables = args->variables;
            request.match = preprocess::parseStepMatch(args->match, "--match");
            request.stepLag = args->steps;
            if (args->steps < 0 || (args->datasets.size() == 1 && args->steps == 0))
                fail("--steps: {}, expected a step lag k >= 1 (or a dataset B to subtract)", args->steps);
            preprocess::PreprocessOptions options;
            if (!args->encoding.empty())
                options.encoding = dataset::parseEncoding(args->encoding, "--encoding");
            options.quiet = args->quiet;
            const auto summary = preprocess::preprocessDifference(request, args->output, options);
            const auto d = dataset::Dataset::open(args->output);
            const auto& g = d->levels().front().grid;
            fmt::print("{}: {} steps ({} written, {} already done) of {}x{}x{} (lat x r x lon), {} variables, in {:.1f} s\n",
                       args->output, d->steps().size(), summary.stepsWritten, summary.stepsSkipped, g.nLat(), g.nR(),
                       g.nLon(), d->variables().size(), summary.seconds);
        });
    },
    // One process: the pipeline's collective phases would wait for ranks that a root-only command
    // leaves waiting outside it; a difference costs about what reading both datasets does.
    25, Ranks::OneProcess);

}  // namespace
}  // namespace raypc::app
