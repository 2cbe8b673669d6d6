// raypc serve DATASET [DATASET2] | FILE.nc… [--dataset DIR] [--port 8080] [--host 127.0.0.1] [--assets DIR]
// [--examples DIR] [--allow-origin URL]... [--max-sessions N] [--max-connections N] [--session-memory MIB]
// [preprocessing options]: the browser UI and the protocol of docs/protocol.md, within the limits of
// docs/reliability.md (options: app/serve_setup.h). netCDF files are preprocessed into a dataset that
// later runs reuse, the first step first (app/series_inputs.h). Under mpirun, rank 0 serves and every
// rank renders its share of each pass (server/rank_pool.h). Two datasets are served as a pair, side
// by side in the UI (docs/compare.md, "Side by side").
#include "app/command.h"
#include "app/serve_setup.h"

namespace raypc::app {
namespace {

struct ServeArgs {
    SeriesFlags series;
    ServeFlags flags;
};

const CommandRegistration kServeCommand(
    "serve", "Serve a dataset (or two, side by side), or netCDF files, to the browser UI (HTTP + WebSocket, docs/protocol.md)",
    [](CLI::App& cmd) {
        auto args = std::make_shared<ServeArgs>();
        args->series.add(cmd, "the first step is shown at once, the rest is preprocessed in the background");
        args->flags.add(cmd);
        cmd.callback([args] {
            if (const auto pair = args->series.pair(); !pair.empty()) {
                serveDataset(pair[0], args->flags, pair[1]);
                return;
            }
            const auto [inputs, options] = args->series.resolve();
            serveSeries(inputs, options, args->flags);
        });
    },
    70, Ranks::AllRanks);

}  // namespace
}  // namespace raypc::app
