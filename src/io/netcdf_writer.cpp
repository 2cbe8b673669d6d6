// Writing netCDF files: snapshots in the layout of the SciVis 2021 contest files (io/netcdf_writer.h),
// and two-dimensional CF grids (io/cf_grid.h).
//
// The file has dims (lat, r, lon) with lon fastest and lat descending (north first), while
// snapshots in memory are lat ascending, so rows are written in reverse order. netCDF-C is
// not thread-safe: call from one thread at a time.
#include "io/netcdf_writer.h"
#include "io/cf_grid.h"

#include "core/atomic_file.h"
#include "core/error.h"

#include <netcdf.h>

#include <algorithm>
#include <array>
#include <cctype>
#include <cmath>
#include <string>
#include <vector>

namespace raypc::io {
namespace {

// Owns an open netCDF file under its temporary name: on any failure the file is closed and
// removed, so no half-written output remains.
class TemporaryNcFile {
public:
    TemporaryNcFile(std::filesystem::path finalPath, int mode)
        : m_final(regularOutputPath(finalPath, "a netCDF file")), m_temporary(temporarySibling(m_final))
    {
        check(nc_create(m_temporary.c_str(), mode | NC_CLOBBER, &m_id), "cannot create");
        m_open = true;
    }
    ~TemporaryNcFile()
    {
        if (m_open)
            nc_close(m_id);
        if (!m_committed) {
            std::error_code ignored;
            std::filesystem::remove(m_temporary, ignored);
        }
    }
    TemporaryNcFile(const TemporaryNcFile&) = delete;
    TemporaryNcFile& operator=(const TemporaryNcFile&) = delete;

    int id() const { return m_id; }

    void check(int status, const std::string& what) const
    {
        if (status != NC_NOERR)
            fail("{}: {}: {}", m_final.string(), what, nc_strerror(status));
    }

    void commit()
    {
        m_open = false;
        check(nc_close(m_id), "cannot close");
        renameAtomic(m_temporary, m_final);
        m_committed = true;
    }

private:
    std::filesystem::path m_final, m_temporary;
    int m_id = -1;
    bool m_open = false, m_committed = false;
};

void putText(const TemporaryNcFile& file, int var, const char* name, const std::string& value,
             const std::string& owner)
{
    file.check(nc_put_att_text(file.id(), var, name, value.size(), value.c_str()),
               fmt::format("cannot write attribute {} of {}", name, owner));
}

std::string longNameOf(const std::string& variable)
{
    if (variable == "vx" || variable == "vy" || variable == "vz")
        return fmt::format("velocity, Cartesian {} component", variable.substr(1));
    return variable;
}

}  // namespace

void writeContestFile(const std::filesystem::path& path, const grid::Snapshot& snapshot, NetcdfFlavour flavour)
{
    const grid::SphericalGrid& grid = snapshot.grid;
    const size_t nLat = grid.nLat(), nR = grid.nR(), nLon = grid.nLon();
    if (nLat == 0 || nR == 0 || nLon == 0)
        fail("{}: cannot write an empty grid ({}x{}x{})", path.string(), nLat, nR, nLon);
    for (const grid::Field& field : snapshot.fields)
        if (field.values.size() != grid.cellCount())
            fail("{}: variable '{}' has {} values, expected {} for a {}x{}x{} grid", path.string(), field.name,
                 field.values.size(), grid.cellCount(), nLat, nR, nLon);

    TemporaryNcFile file(path, flavour == NetcdfFlavour::Netcdf4 ? NC_NETCDF4 : NC_64BIT_OFFSET);
    const int nc = file.id();

    // Define mode: dims in the contest's order, then coordinates, then data variables.
    std::array<int, 3> dims{};
    file.check(nc_def_dim(nc, "lat", nLat, &dims[0]), "cannot define dim lat");
    file.check(nc_def_dim(nc, "r", nR, &dims[1]), "cannot define dim r");
    file.check(nc_def_dim(nc, "lon", nLon, &dims[2]), "cannot define dim lon");

    struct Coordinate {
        const char* name;
        int dim;
        const char* units;
        const char* longName;
        int var = -1;
    };
    std::array<Coordinate, 3> coords = {{{"lat", dims[0], "degrees_north", "latitude"},
                                         {"lon", dims[2], "degrees_east", "longitude"},
                                         {"r", dims[1], "km", "radius"}}};
    for (Coordinate& c : coords) {
        file.check(nc_def_var(nc, c.name, NC_DOUBLE, 1, &c.dim, &c.var), fmt::format("cannot define variable {}", c.name));
        putText(file, c.var, "units", c.units, c.name);
        putText(file, c.var, "long_name", c.longName, c.name);
    }
    std::vector<int> vars(snapshot.fields.size());
    for (size_t v = 0; v < snapshot.fields.size(); ++v) {
        const grid::Field& field = snapshot.fields[v];
        file.check(nc_def_var(nc, field.name.c_str(), NC_FLOAT, 3, dims.data(), &vars[v]),
                   fmt::format("cannot define variable '{}'", field.name));
        putText(file, vars[v], "units", field.units, field.name);
        putText(file, vars[v], "long_name", longNameOf(field.name), field.name);
    }
    putText(file, NC_GLOBAL, "Conventions", "CF-1.6", "the file");
    file.check(nc_enddef(nc), "cannot leave define mode");

    // Data mode: coordinates (lat reversed), then each variable one lat row at a time.
    std::vector<double> latDescending(grid.latDeg.rbegin(), grid.latDeg.rend());
    file.check(nc_put_var_double(nc, coords[0].var, latDescending.data()), "cannot write lat");
    file.check(nc_put_var_double(nc, coords[1].var, grid.lonDeg.data()), "cannot write lon");
    file.check(nc_put_var_double(nc, coords[2].var, grid.rKm.data()), "cannot write r");
    for (size_t v = 0; v < snapshot.fields.size(); ++v) {
        const float* values = snapshot.fields[v].values.data();
        for (size_t fileRow = 0; fileRow < nLat; ++fileRow) {
            const size_t memoryRow = nLat - 1 - fileRow;
            const std::array<size_t, 3> start = {fileRow, 0, 0};
            const std::array<size_t, 3> count = {1, nR, nLon};
            file.check(nc_put_vara_float(nc, vars[v], start.data(), count.data(), values + grid.index(memoryRow, 0, 0)),
                       fmt::format("cannot write variable '{}'", snapshot.fields[v].name));
        }
    }
    file.commit();
}

}  // namespace raypc::io

namespace raypc::io {

std::string cfName(const std::string& name)
{
    std::string out;
    bool gap = false;  // a run of characters netCDF tools would need quoted, written as one '_'
    auto put = [&](const std::string& part) {
        if (gap && !out.empty())
            out += '_';
        gap = false;
        out += part;
    };
    for (const char c : name) {
        if (c == '%') {
            gap = true;
            put("percent");
            gap = true;
        } else if (std::isalnum(static_cast<unsigned char>(c)) || c == '_') {
            put(std::string(1, c));
        } else {
            gap = true;
        }
    }
    const size_t first = out.find_first_not_of('_'), last = out.find_last_not_of('_');
    out = first == std::string::npos ? std::string() : out.substr(first, last - first + 1);
    if (out.empty() || !std::isalpha(static_cast<unsigned char>(out[0])))
        out = "v_" + out;
    return out;
}

void writeCfGrid(const std::filesystem::path& path, const CfGridFile& grid)
{
    const size_t nRows = grid.rows.values.size(), nColumns = grid.columns.values.size();
    if (nRows == 0 || nColumns == 0 || grid.values.size() != nRows * nColumns)
        fail("{}: a grid of {} values over {} x {} points", path.string(), grid.values.size(), nRows, nColumns);
    TemporaryNcFile file(path, NC_64BIT_OFFSET);
    const int nc = file.id();
    int rowDim = -1, columnDim = -1;
    file.check(nc_def_dim(nc, grid.rows.name.c_str(), nRows, &rowDim), "cannot define dim " + grid.rows.name);
    file.check(nc_def_dim(nc, grid.columns.name.c_str(), nColumns, &columnDim), "cannot define dim " + grid.columns.name);
    auto define = [&](const CfVariable1D& v, int ndims, const int* dims) {
        int id = -1;
        file.check(nc_def_var(nc, v.name.c_str(), NC_DOUBLE, ndims, dims, &id), "cannot define variable " + v.name);
        putText(file, id, "units", v.units, v.name);
        if (!v.standardName.empty())
            putText(file, id, "standard_name", v.standardName, v.name);
        putText(file, id, "long_name", v.longName, v.name);
        if (!v.axis.empty())
            putText(file, id, "axis", v.axis, v.name);
        if (!v.positive.empty())
            putText(file, id, "positive", v.positive, v.name);
        return id;
    };
    std::vector<std::pair<int, const CfVariable1D*>> written;
    written.emplace_back(define(grid.rows, 1, &rowDim), &grid.rows);
    written.emplace_back(define(grid.columns, 1, &columnDim), &grid.columns);
    std::string coordinates;
    for (const CfVariable1D& a : grid.auxiliary) {
        const int dim = a.dimension == grid.rows.name ? rowDim : a.dimension == grid.columns.name ? columnDim : -1;
        if (dim < 0 || a.values.size() != (dim == rowDim ? nRows : nColumns))
            fail("{}: auxiliary coordinate {} along '{}' has {} values", path.string(), a.name, a.dimension,
                 a.values.size());
        written.emplace_back(define(a, 1, &dim), &a);
        coordinates += (coordinates.empty() ? "" : " ") + a.name;
    }
    for (const CfVariable1D& s : grid.scalars) {
        if (s.values.size() != 1)
            fail("{}: scalar coordinate {} has {} values", path.string(), s.name, s.values.size());
        written.emplace_back(define(s, 0, nullptr), &s);
        coordinates += (coordinates.empty() ? "" : " ") + s.name;
    }
    const int dims[2] = {rowDim, columnDim};
    int var = -1;
    file.check(nc_def_var(nc, grid.name.c_str(), NC_FLOAT, 2, dims, &var), "cannot define variable " + grid.name);
    putText(file, var, "units", grid.units, grid.name);
    putText(file, var, "long_name", grid.longName, grid.name);
    const float fill = NC_FILL_FLOAT;
    file.check(nc_put_att_float(nc, var, "_FillValue", NC_FLOAT, 1, &fill), "cannot write _FillValue");
    if (!coordinates.empty())
        putText(file, var, "coordinates", coordinates, grid.name);
    // The values' range (what GMT's grdinfo shows from the header).
    float range[2] = {INFINITY, -INFINITY};
    for (const float x : grid.values)
        if (!std::isnan(x)) {
            range[0] = std::min(range[0], x);
            range[1] = std::max(range[1], x);
        }
    if (range[0] <= range[1])
        file.check(nc_put_att_float(nc, var, "actual_range", NC_FLOAT, 2, range), "cannot write actual_range");
    putText(file, NC_GLOBAL, "Conventions", "CF-1.8", "the file");
    for (const auto& [key, value] : grid.globalAttributes)
        putText(file, NC_GLOBAL, key.c_str(), value, "the file");
    file.check(nc_enddef(nc), "cannot leave define mode");
    for (const auto& [id, v] : written)
        file.check(nc_put_var_double(nc, id, v->values.data()), "cannot write " + v->name);
    std::vector<float> values(grid.values);
    for (float& x : values)
        if (std::isnan(x))
            x = fill;
    file.check(nc_put_var_float(nc, var, values.data()), "cannot write " + grid.name);
    file.commit();
}

}  // namespace raypc::io
