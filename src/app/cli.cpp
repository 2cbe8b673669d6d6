// The `raypc` command line: the subcommands' registry and the one entry that parses and runs them,
// shared by the executable (main.cpp) and Python's `python3 -m raypc` (src/python/module.cpp).
#include "app/cli.h"
#include "app/command.h"
#include "app/options.h"
#include "core/error.h"
#include "core/mpi.h"

#include <spdlog/spdlog.h>

#include <algorithm>
#include <cstdio>
#include <exception>
#include <optional>
#include <vector>

namespace raypc::app {
namespace {

struct Entry {
    std::string name, description;
    CommandSetup setup;
    int order;
    Ranks ranks;
};

std::vector<Entry>& registry()
{
    static std::vector<Entry> entries;
    return entries;
}

}  // namespace

CommandRegistration::CommandRegistration(std::string name, std::string description, CommandSetup setup,
                                         int order, Ranks ranks)
{
    registry().push_back({std::move(name), std::move(description), std::move(setup), order, ranks});
}

namespace {

// The subcommand named on the command line (the first argument that is one), before parsing: under
// mpirun, ranks other than 0 must know whether to parse (and run) it at all.
const Entry* selectedEntry(int argc, char** argv, const std::vector<Entry>& entries)
{
    for (int i = 1; i < argc; ++i)
        for (const auto& entry : entries)
            if (entry.name == argv[i])
                return &entry;
    return nullptr;
}

int parseAndRun(CLI::App& app, int argc, char** argv)
{
    try {
        app.parse(argc, argv);
    } catch (const CLI::ParseError& e) {
        // Every rank parses the same arguments: one of them prints. Help and --version print as
        // CLI11 does; an error is one line, as every other error of raypc.
        if (!raypc::mpi::isRoot())
            return e.get_exit_code();
        if (e.get_exit_code() == 0)
            return app.exit(e);
        std::fprintf(stderr, "raypc: error: %s (see --help)\n", e.what());
        return e.get_exit_code();
    }
    return 0;
}

}  // namespace

int run(int argc, char** argv)
{
    namespace mpi = raypc::mpi;
    CLI::App app{"RayPC: interactive visual analysis of mantle convection simulations"};
    app.require_subcommand(1);
    app.set_version_flag("--version", "raypc " RAYPC_VERSION);  // project(VERSION) in CMakeLists.txt
    bool verbose = false;
    app.add_flag("-v,--verbose", verbose, "Log more detail");
    auto entries = registry();
    std::stable_sort(entries.begin(), entries.end(),
                     [](const Entry& a, const Entry& b) { return a.order < b.order; });
    for (auto& entry : entries)
        entry.setup(*app.add_subcommand(entry.name, entry.description));
    requireFiniteNumbers(app);
    app.parse_complete_callback([&] { spdlog::set_level(verbose ? spdlog::level::debug : spdlog::level::info); });
    // Alone (no MPI launcher) this initialises nothing: one process, as without MPI. It outlives the
    // catch below, so that a failing rank reports (and, if need be, aborts the job) before finalising.
    std::optional<mpi::Environment> environment;
    try {
        environment.emplace(argc, argv);
    } catch (const std::exception& e) {
        std::fprintf(stderr, "raypc: error: %s\n", e.what());
        return 1;
    }
    try {
        const Entry* selected = selectedEntry(argc, argv, entries);
        if (!mpi::distributed() || !selected || selected->ranks == Ranks::AllRanks)
            return parseAndRun(app, argc, argv);
        // A command that is not shared out runs once, on rank 0; the others wait for its outcome.
        int status = 0;
        mpi::together([&] {
            if (selected->ranks == Ranks::OneProcess)
                raypc::fail("{}: runs in one process (docs/scaling.md): start it without mpirun, or make a dataset "
                            "and run `mpirun raypc serve DATASET`",
                            selected->name);
            if (mpi::isRoot())
                status = parseAndRun(app, argc, argv);
        });
        return status;
    } catch (const std::exception& e) {
        return mpi::reportFailure(e);
    }
}

}  // namespace raypc::app
