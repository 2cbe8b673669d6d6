// What every connection of one `raypc serve` shares: the options, the dataset and its caches, the
// worker pool and the registry of render sessions. Internal to the server library (Asio types are
// allowed here; nothing outside src/server includes this header).
//
// Thread safety: everything but `sessions` is set before the first connection and only read after;
// the caches are thread-safe; `sessions` is guarded by `sessionsMutex`.
#pragma once

#include "server/dataset_api.h"
#include "server/render_session.h"
#include "server/server.h"
#include "server/step_cache.h"

#include <boost/asio/thread_pool.hpp>

#include <atomic>
#include <memory>
#include <mutex>
#include <optional>
#include <string>
#include <vector>

namespace raypc::server {

struct ServerContext {
    ServerOptions options;
    std::shared_ptr<const Dataset> dataset;
    std::unique_ptr<StepCache> cache;
    std::unique_ptr<PathlineCache> pathlines;
    ApiContext api;
    RenderContext render;
    std::string token;  // empty on loopback
    std::optional<std::filesystem::path> assets;
    boost::asio::thread_pool workers{1};  // the API's Lane::Worker
    std::atomic<uint64_t> sessionCounter{0};
    // Every session's render work, so that shutdown can stop it before the io_context goes away.
    std::mutex sessionsMutex;
    std::vector<std::weak_ptr<RenderSession>> sessions;
};

}  // namespace raypc::server
