// The velocity's units and frame (netcdf_reader.h, normaliseVelocity): a snapshot's components vx,
// vy, vz turned into Cartesian m/s.
#include "io/netcdf_reader.h"

#include "core/error.h"
#include "core/spherical.h"
#include "grid/variable_names.h"
#include "io/netcdf_file.h"

#include <array>
#include <map>
#include <optional>
#include <string>

namespace raypc::io {
namespace {

// Metres per second in one unit of a velocity as CF and models spell it; nullopt when unknown.
std::optional<double> metresPerSecondIn(std::string units)
{
    std::erase_if(units, [](char c) { return c == ' ' || c == '.' || c == '*'; });
    units = netcdf::lowerCase(units);
    constexpr double kYear = 3.15576e7;  // Julian year, s
    static const std::map<std::string, double> known = {
        {"", 1.0},           {"m/s", 1.0},          {"ms-1", 1.0},          {"ms^-1", 1.0},
        {"m/sec", 1.0},      {"meter/second", 1.0}, {"meters/second", 1.0}, {"metre/second", 1.0},
        {"cm/yr", 0.01 / kYear}, {"cm/year", 0.01 / kYear}, {"cm/a", 0.01 / kYear}, {"cmyr-1", 0.01 / kYear},
        {"cma-1", 0.01 / kYear}, {"mm/yr", 1e-3 / kYear},  {"mm/year", 1e-3 / kYear}, {"mm/a", 1e-3 / kYear},
        {"mmyr-1", 1e-3 / kYear}, {"m/yr", 1.0 / kYear},   {"m/year", 1.0 / kYear},   {"m/a", 1.0 / kYear},
        {"myr-1", 1.0 / kYear}};
    const auto it = known.find(units);
    return it == known.end() ? std::nullopt : std::optional<double>(it->second);
}

}  // namespace

void normaliseVelocity(grid::Snapshot& snapshot, ReaderOptions::VelocityFrame frame, const std::string& what)
{
    std::array<grid::Field*, 3> v{};
    for (size_t c = 0; c < 3; ++c)
        for (grid::Field& f : snapshot.fields)
            if (f.name == varname::kVelocity[c])
                v[c] = &f;
    if (!v[0] || !v[1] || !v[2])
        return;
    for (grid::Field* f : v) {
        const auto scale = metresPerSecondIn(f->units);
        if (!scale)
            fail("{}: {}: velocity units '{}', expected m/s, cm/yr, mm/yr or m/yr (or their CF spellings)", what, f->name,
                 f->units);
        if (*scale != 1.0)
            for (float& x : f->values)
                x = float(double(x) * *scale);
        f->units = "m/s";
    }
    if (frame == ReaderOptions::VelocityFrame::Cartesian)
        return;
    // (radial, north, east) at each point into (x, y, z): v = v_r e_r + v_n e_n + v_e e_e; CitcomS'
    // (colatitude, longitude, radial) is (v_r, v_n, v_e) = (third, -first, second).
    const bool colatitude = frame == ReaderOptions::VelocityFrame::Colatitude;
    const std::array<size_t, 3> from = colatitude ? std::array<size_t, 3>{2, 0, 1} : std::array<size_t, 3>{0, 1, 2};
    const double northSign = colatitude ? -1.0 : 1.0;
    const grid::SphericalGrid& g = snapshot.grid;
    for (size_t iLat = 0; iLat < g.nLat(); ++iLat)
        for (size_t iLon = 0; iLon < g.nLon(); ++iLon) {
            const Vec3d up = sphericalToCartesianKm(g.latDeg[iLat], g.lonDeg[iLon], 1.0);
            const EastNorth en = eastNorthAt(g.latDeg[iLat], g.lonDeg[iLon]);
            for (size_t iR = 0; iR < g.nR(); ++iR) {
                const size_t i = g.index(iLat, iR, iLon);
                const Vec3d c = double(v[from[0]]->values[i]) * up +
                                northSign * double(v[from[1]]->values[i]) * en.north +
                                double(v[from[2]]->values[i]) * en.east;
                v[0]->values[i] = float(c.x), v[1]->values[i] = float(c.y), v[2]->values[i] = float(c.z);
            }
        }
}

}  // namespace raypc::io
