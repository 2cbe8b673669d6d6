// Subcommands of the `raypc` executable register themselves here, one file each
// (cmd_<name>.cpp), so that adding a subcommand touches no other file.
#pragma once

#include <CLI/CLI.hpp>

#include <functional>
#include <string>

namespace raypc::app {

// Called once with the subcommand; it adds options and sets a callback that does the work.
// Callbacks throw raypc::Error for expected failures; main prints one line and exits 1.
using CommandSetup = std::function<void(CLI::App& subcommand)>;

struct CommandRegistration {
    CommandRegistration(std::string name, std::string description, CommandSetup setup, int order = 100);
};

}  // namespace raypc::app
