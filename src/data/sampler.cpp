#include "data/sampler.h"

#include "core/spherical.h"

#include <algorithm>
#include <cmath>
#include <tuple>

namespace raypc {
namespace {

// Index i with c[i] <= x <= c[i+1] and the weight of c[i+1]; x is within [c.front(), c.back()].
std::pair<size_t, double> bracket(const std::vector<double>& c, double x)
{
    const auto it = std::upper_bound(c.begin(), c.end(), x);
    size_t i = it == c.begin() ? 0 : static_cast<size_t>(it - c.begin()) - 1;
    i = std::min(i, c.size() - 2);
    const double t = (x - c[i]) / (c[i + 1] - c[i]);
    return {i, std::clamp(t, 0.0, 1.0)};
}

}  // namespace

GridSampler::GridSampler(const SphericalGrid& grid) : m_grid(grid), m_lonWidthsDeg(grid.lonWidthsDeg()) {}

std::optional<GridSampler::Location> GridSampler::locate(double latDeg, double lonDeg, double rKm) const
{
    const auto& g = m_grid;
    constexpr double kTolKm = 1e-6;
    if (!(rKm >= g.rKm.front() - kTolKm && rKm <= g.rKm.back() + kTolKm) || !(latDeg >= -90.0 && latDeg <= 90.0))
        return std::nullopt;
    Location at{};
    // r: clamped to the grid's radii.
    const double r = std::clamp(rKm, g.rKm.front(), g.rKm.back());
    std::tie(at.r0, at.tR) = bracket(g.rKm, r);
    at.r1 = at.r0 + 1;
    // lat: inside the rows, or in a pole cap.
    if (latDeg < g.latDeg.front()) {
        at.lat0 = at.lat1 = 0;
        at.tLat = 0;
        at.poleWeight = (g.latDeg.front() - latDeg) / (g.latDeg.front() + 90.0);
    } else if (latDeg > g.latDeg.back()) {
        at.lat0 = at.lat1 = g.nLat() - 1;
        at.tLat = 0;
        at.poleWeight = (latDeg - g.latDeg.back()) / (90.0 - g.latDeg.back());
    } else {
        std::tie(at.lat0, at.tLat) = bracket(g.latDeg, latDeg);
        at.lat1 = at.lat0 + 1;
        at.poleWeight = 0;
    }
    // lon: periodic.
    const double lon = wrapLonDeg(lonDeg);
    if (lon >= g.lonDeg.front() && lon <= g.lonDeg.back()) {
        std::tie(at.lon0, at.tLon) = bracket(g.lonDeg, lon);
        at.lon1 = at.lon0 + 1;
    } else {
        // In the seam gap between the last column and the first one (+360°).
        const double last = g.lonDeg.back(), first = g.lonDeg.front() + 360.0;
        const double x = lon < g.lonDeg.front() ? lon + 360.0 : lon;
        at.lon0 = g.nLon() - 1;
        at.lon1 = 0;
        at.tLon = std::clamp((x - last) / (first - last), 0.0, 1.0);
    }
    return at;
}

}  // namespace raypc
