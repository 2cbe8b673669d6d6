// Internal to raypc_io: which variables of a netCDF file are read, and where their values lie in it
// (netcdf_reader.h, ReaderOptions::variables and variableNames).
#pragma once

#include "io/netcdf_coordinates.h"

#include <array>
#include <cstddef>
#include <string>
#include <vector>

namespace raypc::io::netcdf {

// The name a variable has in the file: the one ReaderOptions::variableNames maps it to, else its own.
std::string fileNameOf(const ReaderOptions& options, const std::string& canonicalName);

// The variables to read (canonical names): those given (ReaderOptions::variables); else the
// contest's eight when the file holds them all (in their order); else every numeric variable of
// three or more dims, in the file's order, whatever a model or a tomography file calls them (one
// `vs`, a CF output's own names). With `h` (the axes found), only those on the grid's three dims:
// a file's surface maps or other grids are not the model's fields.
std::vector<std::string> requestedVariables(const NcFile& file, const ReaderOptions& options,
                                            const OpenedHeader* h = nullptr);

// Where a variable's values are: its id and, for each grid axis, the distance in elements between
// neighbours along it in the file.
struct VariableLayout {
    int id = -1;
    std::array<size_t, 3> stride{};
    // The hyperslab of one step, in the file's dim order: the whole grid, `timeIndex` of the time dim.
    std::vector<size_t> start, count;
    size_t steps = 1;  // the time dim's length (1 without one)
};

// Checks that the variable exists, is numeric and has the three grid dims in any order, and besides
// them dims of length 1 and at most one longer (CF's time, (time, lat, r, lon): a series in one file,
// of which step `timeIndex` is read).
VariableLayout checkVariable(const NcFile& file, const OpenedHeader& h, const std::string& canonicalName,
                             const std::string& fileName, size_t timeIndex);

}  // namespace raypc::io::netcdf
