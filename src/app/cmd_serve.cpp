// raypc serve DATASET | FILE.nc… [--dataset DIR] [--port 8080] [--host 127.0.0.1] [--assets DIR]
// [--examples DIR] [--allow-origin URL]... [--max-sessions N] [--max-connections N] [--session-memory MIB]
// [preprocessing options]: the browser UI and the protocol of docs/protocol.md, within the limits of
// docs/reliability.md (options: app/serve_setup.h). netCDF files are preprocessed into a dataset that
// later runs reuse, the first step first (app/series_inputs.h). Under mpirun, rank 0 serves and every
// rank renders its share of each pass (server/rank_pool.h).
#include "app/command.h"
#include "app/options.h"
#include "app/serve_setup.h"
#include "core/mpi.h"

namespace raypc::app {
namespace {

struct ServeArgs {
    std::vector<std::string> inputs;
    std::string dataset;
    ServeFlags flags;
    PreprocessFlags preprocess;
};

const CommandRegistration kRegistration(
    "serve", "Serve a dataset, or netCDF files, to the browser UI (HTTP + WebSocket, docs/protocol.md)",
    [](CLI::App& cmd) {
        auto args = std::make_shared<ServeArgs>();
        cmd.add_option("inputs", args->inputs,
                       "A dataset directory (raypc preprocess), or netCDF files / directories of *.nc: the first "
                       "step is shown at once, the rest is preprocessed in the background")
            ->required();
        cmd.add_option("--dataset", args->dataset,
                       "Where the dataset of netCDF inputs is written and found again (default: beside the first "
                       "file, e.g. spherical.raypc)");
        args->flags.add(cmd);
        auto* preprocessing = cmd.add_option_group("preprocessing", "For netCDF inputs: as raypc preprocess");
        args->preprocess.add(*preprocessing, false);
        cmd.callback([args, preprocessing] {
            SeriesInputs inputs;
            PreprocessOptions options;
            mpi::together([&] {  // under mpirun: one message for a bad input, not one per rank
                inputs = resolveSeriesInputs(args->inputs, args->dataset);
                options = args->preprocess.toOptions(*preprocessing);
            });
            serveSeries(inputs, options, args->flags);
        });
    },
    70, Ranks::AllRanks);

}  // namespace
}  // namespace raypc::app
