// raypc: interactive visual analysis of mantle convection simulations.
#include "app/command.h"
#include "core/error.h"

#include <spdlog/spdlog.h>

#include <algorithm>
#include <cstdio>
#include <exception>
#include <vector>

namespace raypc::app {
namespace {

struct Entry {
    std::string name, description;
    CommandSetup setup;
    int order;
};

std::vector<Entry>& registry()
{
    static std::vector<Entry> entries;
    return entries;
}

}  // namespace

CommandRegistration::CommandRegistration(std::string name, std::string description, CommandSetup setup,
                                         int order)
{
    registry().push_back({std::move(name), std::move(description), std::move(setup), order});
}

}  // namespace raypc::app

int main(int argc, char** argv)
{
    using namespace raypc::app;
    CLI::App app{"RayPC: interactive visual analysis of mantle convection simulations"};
    app.require_subcommand(1);
    app.set_version_flag("--version", "raypc 0.1.0");
    bool verbose = false;
    app.add_flag("-v,--verbose", verbose, "Log more detail");
    auto entries = registry();
    std::stable_sort(entries.begin(), entries.end(),
                     [](const Entry& a, const Entry& b) { return a.order < b.order; });
    for (auto& entry : entries)
        entry.setup(*app.add_subcommand(entry.name, entry.description));
    app.parse_complete_callback([&] { spdlog::set_level(verbose ? spdlog::level::debug : spdlog::level::info); });
    try {
        app.parse(argc, argv);
    } catch (const CLI::ParseError& e) {
        return app.exit(e);
    } catch (const raypc::Error& e) {
        std::fprintf(stderr, "raypc: error: %s\n", e.what());
        return 1;
    } catch (const std::exception& e) {
        std::fprintf(stderr, "raypc: error: %s\n", e.what());
        return 1;
    }
    return 0;
}
