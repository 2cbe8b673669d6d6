#include "grid/sampler.h"

#include "core/spherical.h"

#include <algorithm>
#include <cmath>
#include <tuple>

namespace raypc::grid {

GridSampler::Axis::Axis(const std::vector<double>& c) : m_c(c)
{
    if (c.size() < 2)
        return;
    const double step = (c.back() - c.front()) / double(c.size() - 1);
    for (size_t i = 0; i < c.size(); ++i)
        if (!(std::abs(c[i] - (c.front() + step * double(i))) <= 1e-9 * std::abs(step)))
            return;
    m_first = c.front();
    m_inverseStep = 1 / step;
}

std::pair<size_t, double> GridSampler::Axis::bracket(double x) const
{
    const std::vector<double>& c = m_c;
    const size_t last = c.size() - 2;
    size_t i;
    if (m_inverseStep != 0) {
        // A guess, then the same i as the binary search's (the guess may be one off by rounding).
        const double guess = std::floor((x - m_first) * m_inverseStep);
        i = !(guess > 0) ? 0 : guess >= double(last) ? last : size_t(guess);
        while (i < last && c[i + 1] <= x)
            ++i;
        while (i > 0 && c[i] > x)
            --i;
    } else {
        const auto it = std::upper_bound(c.begin(), c.end(), x);
        i = it == c.begin() ? 0 : std::min(last, static_cast<size_t>(it - c.begin()) - 1);
    }
    const double t = (x - c[i]) / (c[i + 1] - c[i]);
    return {i, std::clamp(t, 0.0, 1.0)};
}

GridSampler::GridSampler(const SphericalGrid& grid)
    : m_grid(grid), m_lonWidthsDeg(m_grid.lonWidthsDeg()), m_lat(m_grid.latDeg), m_r(m_grid.rKm), m_lon(m_grid.lonDeg)
{
}

std::optional<GridSampler::Location> GridSampler::locate(double latDeg, double lonDeg, double rKm) const
{
    const auto radial = locateRadius(rKm);
    const auto lateral = radial ? locateLatLon(latDeg, lonDeg) : std::nullopt;
    if (!lateral)
        return std::nullopt;
    return combine(*lateral, *radial);
}

std::optional<GridSampler::RadialPart> GridSampler::locateRadius(double rKm) const
{
    const auto& g = m_grid;
    constexpr double kTolKm = 1e-6;
    if (!(rKm >= g.rKm.front() - kTolKm && rKm <= g.rKm.back() + kTolKm))
        return std::nullopt;
    // Clamped to the grid's radii.
    RadialPart at{};
    std::tie(at.r0, at.tR) = m_r.bracket(std::clamp(rKm, g.rKm.front(), g.rKm.back()));
    at.r1 = at.r0 + 1;
    return at;
}

std::optional<GridSampler::LateralPart> GridSampler::locateLatLon(double latDeg, double lonDeg) const
{
    const auto& g = m_grid;
    if (!(latDeg >= -90.0 && latDeg <= 90.0))
        return std::nullopt;
    LateralPart at{};
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
        std::tie(at.lat0, at.tLat) = m_lat.bracket(latDeg);
        at.lat1 = at.lat0 + 1;
        at.poleWeight = 0;
    }
    // lon: periodic.
    const double lon = wrapLonDeg(lonDeg);
    if (lon >= g.lonDeg.front() && lon <= g.lonDeg.back()) {
        std::tie(at.lon0, at.tLon) = m_lon.bracket(lon);
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

}  // namespace raypc::grid
