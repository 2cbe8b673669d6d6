// Reading mantle snapshots from netCDF files (netCDF-3 classic / 64-bit offset and netCDF-4).
//
// The reader reads what the file says: it finds the lat, r and lon coordinate variables
// (by name, or by CF units degrees_north / degrees_east), accepts any order of the three
// dimensions, ascending or descending coordinates, lon in [-180, 180) or [0, 360] with or
// without the repeated seam, float or double coordinates, and _FillValue / missing_value,
// and returns fields in canonical order (grid.h). netCDF-C is not thread-safe: call from
// one thread at a time.
#pragma once

#include "data/snapshot.h"

#include <array>
#include <filesystem>
#include <optional>
#include <map>
#include <string>
#include <vector>

namespace raypc {

struct ReaderOptions {
    // Canonical variable name -> name in the file, for CF outputs that name things differently
    // (e.g. "temperature" -> "T"). Unmapped variables are looked up by their canonical name.
    std::map<std::string, std::string> variableNames;
    // Names of the coordinate variables; empty: found by name (lat/latitude, lon/longitude,
    // r/radius) or by CF units.
    std::string latName, rName, lonName;
    // Variables to read (canonical names); empty: the eight contest variables.
    std::vector<std::string> variables;
    // Cells that hold the fill value / missing value (or NaN) are an error unless this is set;
    // then they are replaced by the mean of the valid values on the same radius shell.
    bool fillMissing = false;

    // VTK XML series (ASPECT's output; series_input.h):
    // the unit of a .pvd's `timestep` in Myr (ASPECT writes years unless told to write seconds);
    double myrPerTimeUnit = 1e-6;
    // the unit of the mesh's coordinates in km (ASPECT writes metres);
    double meshKmPerUnit = 1e-3;
    // the grid to resample onto: its sizes lat x r x lon (0: chosen from the mesh's finest cell),
    std::array<size_t, 3> resampleSize{};
    // or, once chosen for a series's first step, the grid itself (every step takes the same).
    std::optional<SphericalGrid> targetGrid;
};

struct FileHeader {
    SphericalGrid grid;
    struct Variable {
        std::string name, fileName, units;
    };
    std::vector<Variable> variables;  // the ones requested, all present
    std::string format;  // "classic", "64-bit offset", "netCDF-4", "VTK XML (ASPECT layout)", ...
};

// Reads coordinates and checks that every requested variable exists with the right dims.
// Throws raypc::Error naming the file and what is wrong.
FileHeader readHeader(const std::filesystem::path& path, const ReaderOptions& options = {});

// Reads the whole snapshot. Throws raypc::Error naming the file (and variable) on a missing
// or unreadable file, a non-netCDF or truncated file, a missing variable, wrong dims, or
// missing / non-finite values (unless options.fillMissing).
Snapshot readSnapshot(const std::filesystem::path& path, const ReaderOptions& options = {});

// Expands files and directories (all *.nc inside) and sorts them in natural order.
std::vector<std::filesystem::path> listSnapshotFiles(const std::vector<std::filesystem::path>& inputs);

}  // namespace raypc
