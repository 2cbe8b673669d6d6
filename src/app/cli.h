// The `raypc` command line as a function, so that the executable and Python's `python3 -m raypc`
// run the same program.
#pragma once

namespace raypc::app {

// Parses argv (argv[0] names the program in --help) and runs the subcommand it names; returns the
// exit status: 0, CLI11's code for a bad command line, 1 for a failure (one line on stderr). Catches
// every std::exception. Not reentrant: one call at a time per process (logging level, MPI).
int run(int argc, char** argv);

}  // namespace raypc::app
