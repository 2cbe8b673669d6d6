// How `raypc serve` and `raypc demo` start the server: the same options (--port, --host, --assets,
// --examples, --allow-origin and the limits of docs/reliability.md) with the same defaults, so the demo serves exactly what `raypc serve` would.
#pragma once

#include "server/limits.h"

#include <CLI/CLI.hpp>

#include <filesystem>
#include <string>
#include <vector>

namespace raypc::app {

struct ServeFlags {
    std::string host = "127.0.0.1", assets, examples;
    int port = 8080;
    std::vector<std::string> allowOrigins;
    server::ServerLimits limits;
    size_t sessionMemoryMiB = server::ServerLimits{}.sessionFrameBytes >> 20;

    void add(CLI::App& cmd);
};

// Serves `dataset` until SIGINT/SIGTERM. Prints one parseable line "raypc: serving URL" (tests and
// scripts read the port and token from it). Throws raypc::Error when the dataset cannot be opened,
// the address cannot be bound, or --assets/--examples is not a directory.
void serveDataset(const std::filesystem::path& dataset, const ServeFlags& flags);

}  // namespace raypc::app
