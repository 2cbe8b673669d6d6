// Point sampling on the native spherical grid: the reference (scalar) trilinear interpolation
// used by `raypc probe` and the pathline tracer. The ray caster has its own vectorised sampler
// and is tested against the same rules:
//   - trilinear in index space; coordinates may be non-uniform (located by binary search);
//   - lon is periodic: between the last column and the first one (plus 360°) values blend;
//   - between the outermost lat row and its pole, values blend linearly in lat from the row
//     toward the row's ring mean at the pole (SphericalGrid::ringMean, weighted by lon width), so
//     every longitude meets the same pole value;
//   - r is clamped to the grid's radii (coarse levels' outermost radii lie inside the shell).
//
// Thread safety: immutable after construction.
#pragma once

#include "data/grid.h"

#include <optional>
#include <vector>

namespace raypc {

class GridSampler {
public:
    explicit GridSampler(const SphericalGrid& grid);

    // Where a point falls: the two bracketing indices and the weight of the upper one per axis.
    // In a pole cap, lat0 == lat1 == the outermost row and `poleWeight` > 0 blends toward the pole.
    struct Location {
        size_t lat0, lat1, r0, r1, lon0, lon1;
        double tLat, tR, tLon;
        double poleWeight;
    };

    // std::nullopt when rKm lies outside [first radius, last radius] of the grid (beyond a small
    // tolerance) or lat outside [-90, 90].
    std::optional<Location> locate(double latDeg, double lonDeg, double rKm) const;

    // Interpolated value of `values` (canonical order, grid.cellCount() entries) at `at`.
    double sample(const float* values, const Location& at) const;

    const SphericalGrid& grid() const { return m_grid; }

private:
    SphericalGrid m_grid;
    std::vector<double> m_lonWidthsDeg;
};

}  // namespace raypc
