// Internal to raypc_io: a netCDF file's coordinates (netcdf_reader.h says how they are found and
// what their units may be): lat, r and lon read, converted to degrees north and east and km of
// radius, and put in canonical order.
#pragma once

#include "io/netcdf_file.h"
#include "io/netcdf_reader.h"

#include <array>
#include <cstdint>
#include <cstddef>
#include <vector>

namespace raypc::io::netcdf {

enum Axis { kLat = 0, kR = 1, kLon = 2 };
constexpr std::array<const char*, 3> kAxisNames = {"lat", "r", "lon"};

// The file index of a grid point a regional grid is padded with (no data: missing).
inline constexpr size_t kNoData = SIZE_MAX;

struct CoordinateAxis {
    int varId = -1;
    int dimId = -1;
    std::vector<double> fileValues;  // in file order, converted to degrees / km (of radius)
    // canonical index -> index in the file, or kNoData for a point that pads a regional grid
    std::vector<size_t> fileIndex;
    std::vector<double> canonical;
};

// The grid's three axes as a file holds them, and the grid in canonical order.
struct OpenedHeader {
    std::array<CoordinateAxis, 3> axes;
    grid::SphericalGrid grid;

    // The grid's points as the file stores them (a repeated seam included).
    size_t fileCount() const
    {
        size_t n = 1;
        for (const auto& axis : axes)
            n *= axis.fileValues.size();
        return n;
    }
};

// Finds and reads the file's coordinates (those on the dims of the requested variables first) and
// checks the grid they make. Throws raypc::Error naming the file and the coordinate.
OpenedHeader readAxes(const NcFile& file, const ReaderOptions& options);

}  // namespace raypc::io::netcdf
