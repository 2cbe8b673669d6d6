// Option parsing shared by several subcommands.
#pragma once

#include "data/dataset.h"
#include "data/netcdf_reader.h"

#include <CLI/CLI.hpp>

#include <string>
#include <vector>

namespace raypc::app {

// Options that tell the netCDF reader how the input names things.
struct ReaderFlags {
    std::vector<std::string> variableMap;  // NAME=FILE_NAME
    std::string latName, rName, lonName;
    bool fillMissing = false;

    void add(CLI::App& app);
    // Throws raypc::Error for a malformed --map.
    ReaderOptions toOptions() const;
};

// A step given as an index ("12") or a time ("24Myr"); throws raypc::Error naming the option
// and the dataset's valid steps when it is out of range or malformed.
int parseStep(const Dataset& dataset, const std::string& text, const std::string& option = "--time");

}  // namespace raypc::app
