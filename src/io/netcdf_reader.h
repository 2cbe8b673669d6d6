// Reading mantle snapshots from netCDF files (netCDF-3 classic / 64-bit offset and netCDF-4).
//
// The reader reads what the file says, by its CF attributes (CF conventions 1.x) where it has them:
// - Coordinates: lat, lon and the vertical coordinate are found by name given in the options, by CF
//   attributes (standard_name latitude / longitude / depth, axis Y / X / Z, units degrees_north /
//   degrees_east and their spellings, positive; of several, those on the variables' dims, then
//   coordinate variables, then customary names), or by customary names (lat/latitude, lon/longitude,
//   r/radius/depth).
// - Units: lat and lon in degrees or radians; degrees_south and degrees_west are negated. The
//   vertical coordinate is a radius, or a depth (positive = "down"; without positive, standard_name
//   or name depth) turned into radius = 6371 km - depth; its numbers are km or m as its units say, or
//   as ReaderOptions::radiusUnits says. Without units, numbers that cannot be what they would be taken
//   for (radii outside 3000..7000 km; lat within ±π/2, lon within ±2π: radians?) are refused.
// - Dims: the three grid dims in any order, and other dims of length 1 (one time step per file);
//   coordinates ascending or descending, lon in [-180, 180) or [0, 360] with or without the
//   repeated seam, float or double. A regional grid (latitudes more than two spacings short of a
//   pole, or a gap of more than two spacings in longitude) is padded to the globe with points of no
//   data (SphericalGrid::dataLatDeg, dataLonDeg: the data's extent).
// - Values: any numeric type (doubles and integers wider than 16 bits are read as double);
//   _FillValue (or netCDF's default fill value), missing_value, NaN and Inf are missing, and stay
//   missing (NaN) unless ReaderOptions::fillMissing; a variable missing everywhere is an error;
//   scale_factor / add_offset and _Unsigned are applied; a value beyond float32 is an error.
//   Text attributes may be NC_CHAR or NC_STRING.
// Fields are returned in canonical order (grid.h): lat ascending (degrees north), r ascending (km),
// lon ascending in [0, 360) (degrees east). netCDF-C is not thread-safe: call from one thread at a time.
#pragma once

#include "grid/snapshot.h"

#include <array>
#include <filesystem>
#include <optional>
#include <map>
#include <string>
#include <vector>

namespace raypc::io {

struct ReaderOptions {
    // Canonical variable name -> name in the file, for CF outputs that name things differently
    // (e.g. "temperature" -> "T"). Unmapped variables are looked up by their canonical name.
    std::map<std::string, std::string> variableNames;
    // The velocity's components vx, vy, vz (variableNames may name them in the file: --velocity)
    // are Cartesian, or spherical: radial (up), north, east (--velocity-frame spherical), or
    // colatitude (southward), longitude (eastward), radial as CitcomS orders them (--velocity-frame
    // colatitude), turned into Cartesian ones at each grid point when read. Either way they are
    // converted into m/s from the units they have (m/s, cm/yr, mm/yr, m/yr and their CF spellings;
    // none: m/s).
    enum class VelocityFrame { Cartesian, Spherical, Colatitude };
    VelocityFrame velocityFrame = VelocityFrame::Cartesian;
    // Names of the coordinate variables (rName: the radius or depth); empty: found by CF attributes
    // or customary names (above).
    std::string latName, rName, lonName;
    // Variables to read (canonical names); empty: the eight contest variables when a file holds
    // them all, else every variable on the grid's three dims (a tomography model's one `vs`).
    std::vector<std::string> variables;
    // Cells that hold the fill value / missing value (or NaN) are missing (NaN) unless this is set;
    // then they are replaced by the mean of the valid values on the same radius shell (the points
    // that pad a regional grid stay missing).
    bool fillMissing = false;
    // What the numbers of the radius (or depth) coordinate are. FromFile: its units attribute
    // (km or m); without one, km when the radii lie within a mantle (3000..7000 km), else an error.
    // The others override the attribute; Nondimensional: fractions of Earth's radius (6371 km).
    enum class RadiusUnits { FromFile, Km, M, Nondimensional };
    RadiusUnits radiusUnits = RadiusUnits::FromFile;
    // The step to read of a file holding several (a dimension besides the grid's longer than 1,
    // CF's time): 0 .. FileHeader::steps - 1.
    size_t timeIndex = 0;

    // VTK XML series (ASPECT's output; series_input.h), whose coordinates are metres unless
    // radiusUnits says otherwise:
    // the unit of a .pvd's `timestep` in Myr (ASPECT writes years unless told to write seconds);
    double myrPerTimeUnit = 1e-6;
    // the grid to resample onto: its sizes lat x r x lon (0: chosen from the mesh's finest cell),
    std::array<size_t, 3> resampleSize{};
    // or, once chosen for a series's first step, the grid itself (every step takes the same).
    std::optional<grid::SphericalGrid> targetGrid;

    // CitcomS output (citcoms.h), nondimensional: ΔT in K that temperatures are multiplied by (0:
    // kept as written), and the radius R (km) and thermal diffusivity κ (m²/s) that scale radii,
    // velocities (κ/R) and times (R²/κ); without them the run's own (HDF5 `/input`), else 6371 km
    // and 1e-6 m²/s.
    double temperatureScaleK = 0;
    std::optional<double> planetRadiusKm, diffusivityM2s;
};

struct FileHeader {
    grid::SphericalGrid grid;
    struct Variable {
        std::string name, fileName, units;
        std::string longName;  // CF's long_name (e.g. "Shear-wave velocity"), or empty
    };
    std::vector<Variable> variables;  // the ones requested, all present
    std::string format;  // "classic", "64-bit offset", "netCDF-4", "VTK XML (ASPECT layout)", ...
    size_t steps = 1;    // steps in the file: the length of its time dimension (1 without one)
};

// Reads coordinates and checks that every requested variable exists with the right dims.
// Throws raypc::Error naming the file and what is wrong (as readSnapshot, values aside).
FileHeader readHeader(const std::filesystem::path& path, const ReaderOptions& options = {});

// Reads the whole snapshot. Throws raypc::Error naming the file (and variable) on a missing
// or unreadable file, a non-netCDF or truncated file, a missing variable, wrong dims (a time
// dimension longer than 1), coordinates whose units are unknown or missing where the numbers do not
// fit, a variable whose every value is missing, or a value beyond float32.
grid::Snapshot readSnapshot(const std::filesystem::path& path, const ReaderOptions& options = {});

// The velocity's components vx, vy, vz of `snapshot`, when it has all three, into Cartesian m/s:
// their units converted, and spherical ones (radial, north, east) turned at each grid point. Throws
// raypc::Error naming `what` and the component for units that are not a velocity's.
void normaliseVelocity(grid::Snapshot& snapshot, ReaderOptions::VelocityFrame frame, const std::string& what);

// Expands files and directories (all *.nc inside) and sorts them in natural order.
std::vector<std::filesystem::path> listSnapshotFiles(const std::vector<std::filesystem::path>& inputs);

}  // namespace raypc::io
