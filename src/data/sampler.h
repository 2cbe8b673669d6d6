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
#include <type_traits>
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
    double sample(const float* values, const Location& at) const
    {
        return sample([&](size_t iLat, size_t iR, size_t iLon) { return values[m_grid.index(iLat, iR, iLon)]; }, at);
    }
    // The same with the grid values given by `valueAt(iLat, iR, iLon)` (a float).
    template <typename ValueAt>
        requires std::is_invocable_r_v<float, ValueAt, size_t, size_t, size_t>
    double sample(const ValueAt& valueAt, const Location& at) const
    {
        const auto& g = m_grid;
        auto v = [&](size_t iLat, size_t iR, size_t iLon) { return static_cast<double>(valueAt(iLat, iR, iLon)); };
        auto lerp = [](double a, double b, double t) { return a + (b - a) * t; };
        auto atLat = [&](size_t iLat, size_t iR) { return lerp(v(iLat, iR, at.lon0), v(iLat, iR, at.lon1), at.tLon); };
        auto atR = [&](size_t iR) {
            double value = lerp(atLat(at.lat0, iR), atLat(at.lat1, iR), at.tLat);
            if (at.poleWeight > 0) {
                // The row's ring mean (SphericalGrid::ringMean), weighted by lon width.
                double sum = 0;
                for (size_t i = 0; i < g.nLon(); ++i)
                    sum += v(at.lat0, iR, i) * m_lonWidthsDeg[i];
                value = lerp(value, sum / 360.0, at.poleWeight);
            }
            return value;
        };
        return lerp(atR(at.r0), atR(at.r1), at.tR);
    }

    const SphericalGrid& grid() const { return m_grid; }

private:
    SphericalGrid m_grid;
    std::vector<double> m_lonWidthsDeg;
};

}  // namespace raypc
