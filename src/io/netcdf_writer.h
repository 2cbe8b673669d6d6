// Writing a snapshot as a netCDF file in the layout of the SciVis 2021 contest files (the
// synthetic generator's output, synth/synth.h). The two-dimensional CF grids of maps and sections
// are written by the same file's code: io/cf_grid.h.
//
// Thread safety: netCDF-C is not thread-safe; call from one thread at a time.
#pragma once

#include "grid/snapshot.h"

#include <filesystem>

namespace raypc::io {

// netCDF's 64-bit offset format (CDF-2, readable by every netCDF library) or netCDF-4 (HDF5).
enum class NetcdfFlavour { Classic64, Netcdf4 };

// Writes one snapshot in the contest layout: dims (lat, r, lon) with lat descending,
// float32 variables with `units` attributes, double coordinates lat/r/lon. Atomic.
void writeContestFile(const std::filesystem::path& path, const grid::Snapshot& snapshot,
                      NetcdfFlavour flavour = NetcdfFlavour::Classic64);

}  // namespace raypc::io
