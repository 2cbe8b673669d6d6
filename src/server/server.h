// `raypc serve`: the HTTP and WebSocket server of docs/protocol.md. Beast stays inside the server
// library (server.cpp: the acceptor; http_session.cpp: routes and static files; ws_session.cpp).
//
// One network thread runs every connection; each WebSocket session renders on its own thread
// (render_session.h); screenshots, selections and samples run on a worker pool so that they never
// block the network thread.
//
// Thread safety: construct and run() on one thread; stop() may be called from any thread.
#pragma once

#include <cstdint>
#include <filesystem>
#include <memory>
#include <optional>
#include <string>

namespace raypc::server {

struct ServerOptions {
    std::filesystem::path dataset;
    std::string host = "127.0.0.1";
    uint16_t port = 8080;  // 0: an ephemeral port (see Server::port())
    std::optional<std::filesystem::path> assets;  // nullopt: the built-in page saying the UI is not built
    std::optional<std::filesystem::path> examples;  // presets (GET /api/presets); nullopt: none (findExamplesDir)
    size_t cacheBytes = size_t(2) << 30;          // bound of the shared StepVolume cache
    size_t cacheEntries = 12;
    bool handleSignals = true;                    // SIGINT/SIGTERM stop run()
};

// The UI's asset directory: `explicitDir` if given (throws raypc::Error if it is not a directory),
// else $RAYPC_ASSETS, the source tree's web/dist (compiled in), <exe dir>/web, <exe dir>/../web/dist;
// nullopt when none holds an index.html.
std::optional<std::filesystem::path> findAssetDir(const std::optional<std::filesystem::path>& explicitDir);

class Server {
public:
    // Opens the dataset and binds the port. Throws raypc::Error when the dataset cannot be opened
    // or the address cannot be bound (naming host and port).
    explicit Server(ServerOptions options);
    ~Server();

    uint16_t port() const;
    // Empty on loopback addresses; otherwise required by every request (docs/protocol.md, Access).
    const std::string& token() const;
    // "http://HOST:PORT/" plus "?token=…" when a token is needed.
    std::string url() const;

    void run();   // serves until stop()
    void stop();

private:
    struct Impl;
    std::unique_ptr<Impl> m_impl;
};

}  // namespace raypc::server
