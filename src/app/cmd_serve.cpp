// raypc serve DATASET [--port 8080] [--host 127.0.0.1] [--assets DIR] [--examples DIR] [--allow-origin URL]...
// [--max-sessions N] [--max-connections N] [--session-memory MIB]: the browser UI and the protocol of
// docs/protocol.md, within the limits of docs/reliability.md (options: app/serve_setup.h). Under
// mpirun, rank 0 serves and every rank renders its share of each pass (server/rank_pool.h).
#include "app/command.h"
#include "app/serve_setup.h"

namespace raypc::app {
namespace {

const CommandRegistration kRegistration(
    "serve", "Serve a dataset to the browser UI (HTTP + WebSocket, docs/protocol.md)",
    [](CLI::App& cmd) {
        auto dataset = std::make_shared<std::string>();
        auto flags = std::make_shared<ServeFlags>();
        cmd.add_option("dataset", *dataset, "Preprocessed dataset directory (raypc preprocess)")->required();
        flags->add(cmd);
        cmd.callback([dataset, flags] { serveDataset(*dataset, *flags); });
    },
    70, Ranks::AllRanks);

}  // namespace
}  // namespace raypc::app
