// raypc serve DATASET [--port 8080] [--host 127.0.0.1] [--assets DIR] [--examples DIR] [--allow-origin URL]...
// [--max-sessions N] [--max-connections N] [--session-memory MIB]: the browser UI and the protocol of
// docs/protocol.md, within the limits of docs/reliability.md.
#include "app/command.h"
#include "server/dataset_api.h"
#include "server/server.h"

#include <fmt/format.h>
#include <spdlog/spdlog.h>

#include <cstdio>

namespace raypc::app {
namespace {

struct ServeArgs {
    std::string dataset, host = "127.0.0.1", assets, examples;
    int port = 8080;
    std::vector<std::string> allowOrigins;
    server::ServerLimits limits;
    size_t sessionMemoryMiB = server::ServerLimits{}.sessionFrameBytes >> 20;
};

const CommandRegistration kRegistration(
    "serve", "Serve a dataset to the browser UI (HTTP + WebSocket, docs/protocol.md)",
    [](CLI::App& cmd) {
        auto args = std::make_shared<ServeArgs>();
        cmd.add_option("dataset", args->dataset, "Preprocessed dataset directory (raypc preprocess)")->required();
        cmd.add_option("--port", args->port, "TCP port; 0 picks a free one (printed at start)")
            ->capture_default_str()
            ->check(CLI::Range(0, 65535));
        cmd.add_option("--host", args->host,
                       "Address to listen on; anything but loopback requires the access token printed at start")
            ->capture_default_str();
        cmd.add_option("--assets", args->assets, "Directory of the built UI (default: $RAYPC_ASSETS, web/dist, ...)");
        cmd.add_option("--examples", args->examples,
                       "Directory of example states offered as presets (default: $RAYPC_EXAMPLES, the source tree's examples/)");
        cmd.add_option("--allow-origin", args->allowOrigins,
                       "Origin of another page allowed to use the server, e.g. http://viz.lab:8080 (repeatable); "
                       "its host is also accepted as Host on loopback");
        cmd.add_option("--max-sessions", args->limits.maxSessions, "Open WebSocket sessions (browser tabs) at most")
            ->capture_default_str()
            ->check(CLI::Range(1, 4096));
        cmd.add_option("--max-connections", args->limits.maxConnections, "Open connections (HTTP and WebSocket) at most")
            ->capture_default_str()
            ->check(CLI::Range(2, 100000));
        cmd.add_option("--session-memory", args->sessionMemoryMiB,
                       fmt::format("Frame memory of all sessions together, MiB (a session's image costs width x height "
                                   "x {} bytes)",
                                   server::kFrameBytesPerPixel))
            ->capture_default_str()
            ->check(CLI::Range(1, 1 << 24));
        cmd.callback([args] {
            server::ServerOptions options;
            options.dataset = args->dataset;
            options.host = args->host;
            options.port = uint16_t(args->port);
            options.assets = server::findAssetDir(args->assets.empty() ? std::nullopt
                                                                       : std::optional<std::filesystem::path>(args->assets));
            options.examples = server::findExamplesDir(
                args->examples.empty() ? std::nullopt : std::optional<std::filesystem::path>(args->examples));
            options.allowedOrigins = args->allowOrigins;
            options.limits = args->limits;
            options.limits.sessionFrameBytes = args->sessionMemoryMiB << 20;
            server::Server srv(options);
            if (options.assets)
                spdlog::info("serving the UI from {}", options.assets->string());
            else
                spdlog::warn("the browser UI is not built (no web/dist found); serving a placeholder page and the API");
            // One parseable line (tests and scripts read the port and token from it).
            fmt::print("raypc: serving {}\n", srv.url());
            std::fflush(stdout);
            srv.run();
        });
    },
    70);

}  // namespace
}  // namespace raypc::app
