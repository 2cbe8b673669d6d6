// Subcommands of the `raypc` executable register themselves here, one file each
// (cmd_<name>.cpp, a CommandRegistration named k<Name>Command: the names differ, so the files can
// share a unity build), so that adding a subcommand touches no other file.
#pragma once

#include <CLI/CLI.hpp>

#include <functional>
#include <string>

namespace raypc::app {

// Called once with the subcommand; it adds options and sets a callback that does the work.
// Callbacks throw raypc::Error for expected failures; main prints one line and exits 1.
using CommandSetup = std::function<void(CLI::App& subcommand)>;

// Under mpirun with more than one rank (core/mpi.h): a RootOnly command runs on rank 0 while the
// others wait for it; an AllRanks command runs on every rank and shares its work through core/mpi.h
// (its failures must go through mpi::together so that every rank stops with one message); a
// OneProcess command (the demo) refuses to start on several ranks (docs/scaling.md).
enum class Ranks { RootOnly, AllRanks, OneProcess };

struct CommandRegistration {
    CommandRegistration(std::string name, std::string description, CommandSetup setup, int order = 100,
                        Ranks ranks = Ranks::RootOnly);
};

}  // namespace raypc::app
