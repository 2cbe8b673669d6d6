// Point sampling on the native spherical grid: the reference (scalar) trilinear interpolation
// used by `raypc probe` and the pathline tracer. The ray caster has its own vectorised sampler
// and is tested against the same rules:
//   - trilinear in index space; coordinates may be non-uniform (located by binary search; an
//     evenly spaced axis in constant time);
//   - lon is periodic: between the last column and the first one (plus 360°) values blend;
//   - between the outermost lat row and its pole, values blend linearly in lat from the row
//     toward the row's ring mean at the pole (SphericalGrid::ringMean, weighted by lon width), so
//     every longitude meets the same pole value;
//   - r is clamped to the grid's radii (coarse levels' outermost radii lie inside the shell).
//
// Thread safety: immutable after construction.
#pragma once

#include "grid/grid.h"

#include <cmath>
#include <limits>
#include <optional>
#include <type_traits>
#include <utility>
#include <vector>

namespace raypc::grid {

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

    // The same in two parts, for samples on a shell (one radius, many points) or on a section
    // (points along a line by radii): locate(lat, lon, r) == combine(locateLatLon(lat, lon),
    // locateRadius(r)), each part found once.
    struct RadialPart {
        size_t r0, r1;
        double tR;
    };
    struct LateralPart {
        size_t lat0, lat1, lon0, lon1;
        double tLat, tLon, poleWeight;
    };
    std::optional<RadialPart> locateRadius(double rKm) const;
    std::optional<LateralPart> locateLatLon(double latDeg, double lonDeg) const;
    static Location combine(const LateralPart& lateral, const RadialPart& radial)
    {
        return {lateral.lat0, lateral.lat1, radial.r0, radial.r1, lateral.lon0, lateral.lon1,
                lateral.tLat, radial.tR, lateral.tLon, lateral.poleWeight};
    }

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
        const LateralPart lateral{at.lat0, at.lat1, at.lon0, at.lon1, at.tLat, at.tLon, at.poleWeight};
        auto atR = [&](size_t iR) {
            return sampleLateral([&](size_t iLat, size_t iLon) { return valueAt(iLat, iR, iLon); }, lateral);
        };
        return lerpMissing(atR(at.r0), atR(at.r1), at.tR);
    }

    // a + (b - a) t, or where a or b is missing (NaN) the other at the weight that takes it alone,
    // NaN between: a point of data at the edge of a missing region keeps its value.
    static double lerpMissing(double a, double b, double t)
    {
        if (std::isnan(a) || std::isnan(b))
            return t == 0 ? a : t == 1 ? b : std::numeric_limits<double>::quiet_NaN();
        return a + (b - a) * t;
    }

    // The value on one shell (a radius's values, given by `valueAt(iLat, iLon)`, a float) at a
    // lateral location: the rules above in lat and lon.
    template <typename ValueAt>
        requires std::is_invocable_r_v<float, ValueAt, size_t, size_t>
    double sampleLateral(const ValueAt& valueAt, const LateralPart& at) const
    {
        auto v = [&](size_t iLat, size_t iLon) { return static_cast<double>(valueAt(iLat, iLon)); };
        auto lerp = [](double a, double b, double t) { return lerpMissing(a, b, t); };
        auto atLat = [&](size_t iLat) { return lerp(v(iLat, at.lon0), v(iLat, at.lon1), at.tLon); };
        double value = lerp(atLat(at.lat0), atLat(at.lat1), at.tLat);
        if (at.poleWeight > 0) {
            // The row's ring mean (SphericalGrid::ringMean), weighted by lon width.
            double sum = 0;
            for (size_t i = 0; i < m_grid.nLon(); ++i)
                sum += v(at.lat0, i) * m_lonWidthsDeg[i];
            value = lerp(value, sum / 360.0, at.poleWeight);
        }
        return value;
    }

    const SphericalGrid& grid() const { return m_grid; }

    // Finds i with c[i] <= x < c[i+1] (i at most c.size() - 2) in a coordinate axis, in constant
    // time on an evenly spaced axis (the usual grid), by binary search otherwise.
    class Axis {
    public:
        explicit Axis(const std::vector<double>& c);
        std::pair<size_t, double> bracket(double x) const;  // the index and the weight of c[i+1]

    private:
        std::vector<double> m_c;
        double m_first = 0, m_inverseStep = 0;  // m_inverseStep 0: not evenly spaced
    };

private:
    SphericalGrid m_grid;
    std::vector<double> m_lonWidthsDeg;
    Axis m_lat, m_r, m_lon;  // m_grid's coordinates
};

}  // namespace raypc::grid
