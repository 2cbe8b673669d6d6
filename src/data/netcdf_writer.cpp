// Writing snapshots in the layout of the SciVis 2021 contest files (see synth.h).
//
// The file has dims (lat, r, lon) with lon fastest and lat descending (north first), while
// snapshots in memory are lat ascending, so rows are written in reverse order. netCDF-C is
// not thread-safe: call from one thread at a time.
#include "data/synth.h"

#include "core/atomic_file.h"
#include "core/error.h"

#include <netcdf.h>

#include <array>
#include <string>
#include <vector>

namespace raypc {
namespace {

// Owns an open netCDF file under its temporary name: on any failure the file is closed and
// removed, so no half-written output remains.
class TemporaryNcFile {
public:
    TemporaryNcFile(std::filesystem::path finalPath, int mode)
        : m_final(std::move(finalPath)), m_temporary(temporarySibling(m_final))
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

void writeContestFile(const std::filesystem::path& path, const Snapshot& snapshot, NetcdfFlavour flavour)
{
    const SphericalGrid& grid = snapshot.grid;
    const size_t nLat = grid.nLat(), nR = grid.nR(), nLon = grid.nLon();
    if (nLat == 0 || nR == 0 || nLon == 0)
        fail("{}: cannot write an empty grid ({}x{}x{})", path.string(), nLat, nR, nLon);
    for (const Field& field : snapshot.fields)
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
        const Field& field = snapshot.fields[v];
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

}  // namespace raypc
