// `raypc serve`: the HTTP and WebSocket server of docs/protocol.md. Beast stays inside the server
// library (server.cpp: the acceptor; http_session.cpp: routes and static files; ws_session.cpp).
//
// One network thread runs every connection and parses no JSON; WebSocket messages are parsed and
// handed over on a message thread, each session renders on its own thread (render_session.h), API
// requests run on lanes (server_context.h: a worker pool for the quick ones, one thread each for
// screenshots and for statistics over time), so that none of them blocks the network thread or the
// others. The limits (connections, sessions, memory, queues, screenshots) are in limits.h.
//
// Thread safety: construct and run() on one thread; stop() may be called from any thread.
#pragma once

#include "server/limits.h"

#include <cstdint>
#include <filesystem>
#include <memory>
#include <optional>
#include <string>
#include <vector>

namespace raypc::server {

class RankPool;
class SeriesProgress;

struct ServerOptions {
    std::filesystem::path dataset;
    // The second dataset of a pair (`raypc serve A B`, docs/compare.md, "Side by side"): its own
    // caches (each dataset gets half of cacheBytes), chosen by the `dataset` parameter of the HTTP
    // endpoints and of /ws. nullopt: one dataset.
    std::optional<std::filesystem::path> second;
    std::string host = "127.0.0.1";
    uint16_t port = 8080;  // 0: an ephemeral port (see Server::port())
    std::optional<std::filesystem::path> assets;  // nullopt: the built-in page saying the UI is not built
    std::optional<std::filesystem::path> examples;  // presets (GET /api/presets); nullopt: none (findExamplesDir)
    // Bound of the shared StepVolume cache (`--step-cache`; StepCache::defaultBytes: half the memory
    // available at start) and of its entries (a level-0 step and its coarser levels are each one).
    size_t cacheBytes = size_t(2) << 30;
    size_t cacheEntries = 64;
    bool handleSignals = true;                    // SIGINT/SIGTERM stop run()
    // Pages of other origins that may use the server ("http://host:port", `--allow-origin`); their
    // hosts are also accepted as Host on loopback (access.h, SitePolicy).
    std::vector<std::string> allowedOrigins;
    ServerLimits limits;
    // Under mpirun (rank 0 of a distributed server, rank_pool.h): every session's passes are shared
    // out over the ranks. nullptr: one process.
    RankPool* ranks = nullptr;
    // The access token on a non-loopback host; empty: a new random one. A server that replaces
    // another on the same port (serve_setup.cpp) keeps its token, so open pages stay valid.
    std::string token;
    // While `dataset` is the first step of a series preprocessed in the background: where that run
    // is (GET /api/progress). nullptr: the dataset is complete.
    std::shared_ptr<const SeriesProgress> series;
};


class Server {
public:
    // Opens the dataset and binds the port. Throws raypc::Error when the dataset cannot be opened,
    // an allowed origin is malformed, or the address cannot be bound (naming host and port).
    explicit Server(ServerOptions options);
    ~Server();

    uint16_t port() const;
    // Empty on loopback addresses; otherwise required by every request (docs/protocol.md, Access).
    const std::string& token() const;
    // "http://HOST:PORT/" plus "?token=…" when a token is needed.
    std::string url() const;

    void run();   // serves until stop(); an exception out of one connection is logged, not thrown
    // Stops serving and cancels running screenshots and statistics; the destructor then waits for
    // the worker and render threads (about one tile of work).
    void stop();

private:
    struct Impl;
    std::unique_ptr<Impl> m_impl;
};

}  // namespace raypc::server
