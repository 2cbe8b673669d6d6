// How `raypc serve` and `raypc demo` start the server: the same options (--port, --host, --assets,
// --examples, --allow-origin and the limits of docs/reliability.md) with the same defaults, so the demo serves exactly what `raypc serve` would.
#pragma once

#include "app/series_inputs.h"
#include "server/limits.h"

#include <CLI/CLI.hpp>

#include <filesystem>
#include <optional>
#include <string>
#include <vector>

namespace raypc::app {

struct ServeFlags {
    std::string host = "127.0.0.1", assets, examples;
    int port = 8080;
    std::vector<std::string> allowOrigins;
    server::ServerLimits limits;
    size_t sessionMemoryMiB = server::ServerLimits{}.sessionFrameBytes >> 20;
    // --step-cache and --frame-cache as given (parseMemorySize); empty: the defaults
    // (StepCache::defaultBytes, ServerLimits::frameCacheBytes).
    std::string stepCache, frameCache;

    void add(CLI::App& cmd);
};

// Serves `dataset` until SIGINT/SIGTERM. Prints one parseable line "raypc: serving URL" (tests and
// scripts read the port and token from it). Throws raypc::Error when the dataset cannot be opened,
// the address cannot be bound, or --assets/--examples is not a directory.
// `second`: a pair's second dataset (`raypc serve A B`, docs/compare.md), served by one process
// (under mpirun: raypc::Error).
void serveDataset(const std::filesystem::path& dataset, const ServeFlags& flags,
                  const std::optional<std::filesystem::path>& second = std::nullopt);

// `raypc serve INPUT…`: a dataset as serveDataset; netCDF files (series_inputs.h) as the dataset made
// from them: when it is not complete yet, the first file is preprocessed alone and served at once
// while the rest of the series is preprocessed in the background (one thread, lower priority; GET
// /api/progress says where it is), then the server of the whole series replaces it on the same port.
// SIGINT/SIGTERM stop the background run between steps (a later run resumes). One process only.
void serveSeries(const SeriesInputs& inputs, const preprocess::PreprocessOptions& preprocessOptions, const ServeFlags& flags);

}  // namespace raypc::app
