// Two-dimensional grids written as CF netCDF files (CF-1.8, COARDS-compatible): the depth slices
// and sections RayPC exports (render/slice_view.h; `raypc map --netcdf`, `raypc section --netcdf`),
// in the form GMT (`gmt grdinfo`, `grdimage`), Python's xarray and netCDF4, and Panoply read as they
// are: one float variable over two one-dimensional coordinate variables, missing values as
// _FillValue, units and standard names on every variable.
//
// Thread safety: netCDF-C is not thread-safe; call from one thread at a time.
#pragma once

#include <filesystem>
#include <string>
#include <utility>
#include <vector>

namespace raypc::io {

// A coordinate variable along one dimension (its name is the dimension's), or, when `dimension` is
// set, an auxiliary coordinate along another one (e.g. the latitude of every point of a section).
struct CfVariable1D {
    std::string name, units, standardName, longName;
    std::string axis;      // "X", "Y", "Z" or empty
    std::string positive;  // "down" for depth, or empty
    std::vector<double> values;
    std::string dimension;  // empty: its own dimension
};

struct CfGridFile {
    CfVariable1D rows, columns;            // the dimensions, slowest first
    std::vector<CfVariable1D> auxiliary;   // along `rows` or `columns` (by dimension name)
    std::vector<CfVariable1D> scalars;     // one value each (e.g. the slice's depth), listed in `coordinates`
    std::string name, units, longName;     // the data variable; `name` file-safe (no spaces)
    std::vector<float> values;             // rows x columns, NaN where missing
    std::vector<std::pair<std::string, std::string>> globalAttributes;  // title, source, history...
};

// Writes `grid` to `path` (64-bit offset netCDF, atomically: nothing is left on failure). Throws
// raypc::Error naming the file and what failed, or the sizes that do not match.
void writeCfGrid(const std::filesystem::path& path, const CfGridFile& grid);

// A name netCDF tools and CF take without quoting, the one rule for every file and xarray Dataset
// raypc makes (Python's raypc.cf_name calls it): '%' spelled "percent", every run of characters other
// than letters, digits and '_' one '_', none at either end, "v_" in front of a name that would not
// start with a letter ("temperature anomaly %" -> "temperature_anomaly_percent"; case kept: "dlnVs").
std::string cfName(const std::string& name);

}  // namespace raypc::io
