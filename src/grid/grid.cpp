#include "grid/grid.h"

#include "core/error.h"
#include "core/spherical.h"

#include <algorithm>
#include <cmath>

#include <tbb/parallel_for.h>

namespace raypc::grid {
namespace {

// Midpoints between neighbours; the two ends extend by half the end spacing.
std::vector<double> midpointEdges(const std::vector<double>& c)
{
    const size_t n = c.size();
    std::vector<double> e(n + 1);
    if (n == 1) {
        e[0] = c[0];
        e[1] = c[0];
        return e;
    }
    for (size_t i = 1; i < n; ++i)
        e[i] = 0.5 * (c[i - 1] + c[i]);
    e[0] = c[0] - 0.5 * (c[1] - c[0]);
    e[n] = c[n - 1] + 0.5 * (c[n - 1] - c[n - 2]);
    return e;
}

// Mean of pairs (2i, 2i+1); an odd last value stays alone.
std::vector<double> pairMeans(const std::vector<double>& c)
{
    std::vector<double> out((c.size() + 1) / 2);
    for (size_t i = 0; i < out.size(); ++i)
        out[i] = 2 * i + 1 < c.size() ? 0.5 * (c[2 * i] + c[2 * i + 1]) : c[2 * i];
    return out;
}

bool strictlyAscending(const std::vector<double>& c)
{
    for (size_t i = 1; i < c.size(); ++i)
        if (!(c[i] > c[i - 1]))
            return false;
    return true;
}

}  // namespace

std::vector<double> SphericalGrid::latEdgesDeg() const
{
    auto e = midpointEdges(latDeg);
    e.front() = std::max(e.front(), -90.0);
    e.back() = std::min(e.back(), 90.0);
    return e;
}

std::vector<double> SphericalGrid::rEdgesKm() const
{
    auto e = midpointEdges(rKm);
    e.front() = rKm.front();
    e.back() = rKm.back();
    return e;
}

std::vector<double> SphericalGrid::lonEdgesDeg() const
{
    const size_t n = lonDeg.size();
    std::vector<double> e(n + 1);
    if (n == 1) {
        e[0] = lonDeg[0] - 180.0;
        e[1] = lonDeg[0] + 180.0;
        return e;
    }
    for (size_t i = 1; i < n; ++i)
        e[i] = 0.5 * (lonDeg[i - 1] + lonDeg[i]);
    // The seam: the gap between the last column and the first one plus 360°.
    const double seamMid = 0.5 * (lonDeg[n - 1] + lonDeg[0] + 360.0);
    e[0] = seamMid - 360.0;
    e[n] = seamMid;
    return e;
}

std::vector<double> SphericalGrid::lonWidthsDeg() const
{
    const auto e = lonEdgesDeg();
    std::vector<double> w(nLon());
    for (size_t i = 0; i < nLon(); ++i)
        w[i] = e[i + 1] - e[i];
    return w;
}

double SphericalGrid::ringMean(const float* values, size_t iLat, size_t iR, const std::vector<double>& lonWidthsDeg) const
{
    const float* row = values + index(iLat, iR, 0);
    double sum = 0;
    for (size_t i = 0; i < nLon(); ++i)
        sum += double(row[i]) * lonWidthsDeg[i];
    return sum / 360.0;
}

NodeGradient nodeGradient(const SphericalGrid& grid, const float* values)
{
    const size_t nLat = grid.nLat(), nR = grid.nR(), nLon = grid.nLon();
    RAYPC_CHECK(nLat >= 2 && nR >= 2 && nLon >= 2);
    NodeGradient out;
    out.count = grid.cellCount();
    // Not zeroed: the threads write it (a spare block is faulted in already, a fresh one on first touch).
    out.values = makeSpareArray<float>(3 * out.count);
    // Neighbours i - 1 and i + 1 (clamped) and the inverse of the coordinate difference between them.
    struct Stencil {
        size_t lo, hi;
        float inv;
    };
    auto stencils = [](const std::vector<double>& c, bool periodic) {
        const size_t n = c.size();
        std::vector<Stencil> s(n);
        for (size_t i = 0; i < n; ++i) {
            size_t lo = i == 0 ? (periodic ? n - 1 : 0) : i - 1;
            size_t hi = i + 1 == n ? (periodic ? 0 : n - 1) : i + 1;
            double span = c[hi] - c[lo];
            if (periodic && span <= 0.0)
                span += 360.0;
            s[i] = {lo, hi, float(1.0 / span)};
        }
        return s;
    };
    const std::vector<Stencil> sLat = stencils(grid.latDeg, false), sR = stencils(grid.rKm, false),
                               sLon = stencils(grid.lonDeg, true);
    tbb::parallel_for(tbb::blocked_range<size_t>(0, nLat * nR), [&](const tbb::blocked_range<size_t>& rows) {
        for (size_t row = rows.begin(); row != rows.end(); ++row) {
            const size_t iLat = row / nR, iR = row % nR;
            const float* v = values + row * nLon;
            const float* vLatLo = values + grid.index(sLat[iLat].lo, iR, 0);
            const float* vLatHi = values + grid.index(sLat[iLat].hi, iR, 0);
            const float* vRLo = values + grid.index(iLat, sR[iR].lo, 0);
            const float* vRHi = values + grid.index(iLat, sR[iR].hi, 0);
            float* gLat = out.values.get() + row * nLon;
            float* gR = gLat + out.count;
            float* gLon = gR + out.count;
            for (size_t i = 0; i < nLon; ++i) {
                gLat[i] = (vLatHi[i] - vLatLo[i]) * sLat[iLat].inv;
                gR[i] = (vRHi[i] - vRLo[i]) * sR[iR].inv;
                gLon[i] = (v[sLon[i].hi] - v[sLon[i].lo]) * sLon[i].inv;
            }
        }
    });
    return out;
}

SphericalGrid::VolumeFactors SphericalGrid::volumeFactors() const
{
    VolumeFactors f;
    const auto le = latEdgesDeg(), re = rEdgesKm(), oe = lonEdgesDeg();
    f.lat.resize(nLat());
    for (size_t i = 0; i < nLat(); ++i)
        f.lat[i] = latHoldsData(latDeg[i]) ? std::sin(degToRad(le[i + 1])) - std::sin(degToRad(le[i])) : 0.0;
    f.r.resize(nR());
    for (size_t i = 0; i < nR(); ++i)
        f.r[i] = (re[i + 1] * re[i + 1] * re[i + 1] - re[i] * re[i] * re[i]) / 3.0;
    f.lon.resize(nLon());
    for (size_t i = 0; i < nLon(); ++i)
        f.lon[i] = lonHoldsData(lonDeg[i]) ? degToRad(oe[i + 1] - oe[i]) : 0.0;
    return f;
}

// A coarser level's row or column that merges a point of data with one of padding lies between
// them, outside the data's extent: it has no volume, as its value (the mean, with a NaN) has none.
// The tolerance admits the float rounding of the extent as a file writes it.
bool SphericalGrid::latHoldsData(double lat) const
{
    constexpr double kTolDeg = 1e-6;
    return !dataLatDeg || (lat >= (*dataLatDeg)[0] - kTolDeg && lat <= (*dataLatDeg)[1] + kTolDeg);
}

bool SphericalGrid::lonHoldsData(double lon) const
{
    constexpr double kTolDeg = 1e-6;
    if (!dataLonDeg)
        return true;
    const double west = (*dataLonDeg)[0], east = (*dataLonDeg)[1];
    // Degrees east of the western edge, in [0, 360).
    const double fromWest = std::fmod(std::fmod(lon - west, 360.0) + 360.0 + kTolDeg, 360.0) - kTolDeg;
    const double width = std::fmod(std::fmod(east - west, 360.0) + 360.0, 360.0);
    return fromWest <= width + kTolDeg;
}

double SphericalGrid::totalVolumeKm3() const
{
    const auto f = volumeFactors();
    double a = 0, b = 0, c = 0;
    for (double v : f.lat)
        a += v;
    for (double v : f.r)
        b += v;
    for (double v : f.lon)
        c += v;
    return a * b * c;
}

SphericalGrid SphericalGrid::coarsened() const
{
    SphericalGrid g;
    g.latDeg = pairMeans(latDeg);
    g.rKm = pairMeans(rKm);
    // Lon pairs never straddle the seam (pairs start at column 0), so a plain mean is the
    // circular mean; an odd last column stays alone.
    g.lonDeg = pairMeans(lonDeg);
    g.dataLatDeg = dataLatDeg;
    g.dataLonDeg = dataLonDeg;
    return g;
}

void SphericalGrid::validate(const std::string& what) const
{
    if (nLat() < 2 || nR() < 2 || nLon() < 3)
        fail("{}: grid {}x{}x{} (lat x r x lon) is too small, expected at least 2x2x3", what, nLat(), nR(),
             nLon());
    if (!strictlyAscending(latDeg) || latDeg.front() < -90.0 || latDeg.back() > 90.0)
        fail("{}: lat coordinates are not strictly monotonic within [-90, 90] degrees", what);
    if (!strictlyAscending(rKm) || rKm.front() <= 0.0)
        fail("{}: the radii (from the radius or depth coordinate) are not strictly monotonic and positive", what);
    if (!strictlyAscending(lonDeg) || lonDeg.front() < 0.0 || lonDeg.back() >= 360.0)
        fail("{}: lon coordinates are not strictly monotonic within [0, 360) degrees", what);
    // A regional grid is made global by its reader with points that hold no data (io/netcdf_coordinates.cpp):
    // wide gaps between the points of a grid are allowed here, and hold what the reader put there.
}

namespace {

double medianSpacing(const std::vector<double>& ascending)
{
    std::vector<double> gaps;
    for (size_t i = 1; i < ascending.size(); ++i)
        gaps.push_back(ascending[i] - ascending[i - 1]);
    if (gaps.empty())
        return 0;
    std::nth_element(gaps.begin(), gaps.begin() + gaps.size() / 2, gaps.end());
    return gaps[gaps.size() / 2];
}

// Points from `from` toward `to` (exclusive) with spacings step, 2 step, 4 step...: few points, however
// far, and a first one a regular spacing beyond the data. Stops where the next spacing would leave
// less than itself before `to`.
std::vector<double> growingSteps(double from, double to, double step)
{
    std::vector<double> points;
    const double sign = to > from ? 1.0 : -1.0;
    double x = from;
    for (double s = step; std::abs(to - x) > 2.0 * s; s *= 2.0) {
        x += sign * s;
        points.push_back(x);
    }
    return points;
}

}  // namespace

PaddedAxis padToGlobe(const std::vector<double>& ascendingDeg, bool latitude)
{
    PaddedAxis out;
    out.deg = ascendingDeg;
    for (size_t i = 0; i < ascendingDeg.size(); ++i)
        out.source.push_back(i);
    const double d = medianSpacing(ascendingDeg);
    if (d <= 0)
        return out;
    constexpr size_t kNoData = PaddedAxis::kPadding;
    std::vector<std::pair<double, size_t>> points;
    for (size_t i = 0; i < ascendingDeg.size(); ++i)
        points.emplace_back(ascendingDeg[i], i);
    std::optional<std::array<double, 2>>& extent = out.extent;
    const std::vector<double>& canonical = ascendingDeg;
    if (latitude) {
        const double south = canonical.front(), north = canonical.back();
        if (south + 90.0 <= 2.0 * d + 1e-9 && 90.0 - north <= 2.0 * d + 1e-9)
            return out;
        extent = std::array<double, 2>{south, north};
        if (south + 90.0 > 2.0 * d + 1e-9) {
            for (double x : growingSteps(south, -90.0, d))
                points.emplace_back(x, kNoData);
            points.emplace_back(-90.0, kNoData);
        }
        if (90.0 - north > 2.0 * d + 1e-9) {
            for (double x : growingSteps(north, 90.0, d))
                points.emplace_back(x, kNoData);
            points.emplace_back(90.0, kNoData);
        }
    } else {
        // The widest gap between neighbours on the circle (the seam's included).
        const size_t n = canonical.size();
        size_t widest = n - 1;
        double widestGap = canonical.front() + 360.0 - canonical.back();
        for (size_t i = 0; i + 1 < n; ++i)
            if (canonical[i + 1] - canonical[i] > widestGap) {
                widestGap = canonical[i + 1] - canonical[i];
                widest = i;
            }
        if (widestGap <= 2.0 * d + 1e-9)
            return out;
        const double west = canonical[(widest + 1) % n], east = canonical[widest];
        extent = std::array<double, 2>{west, east};
        // From both sides toward the middle of the gap, then the middle itself.
        const double mid = east + 0.5 * widestGap;
        for (double x : growingSteps(east, mid, d))
            points.emplace_back(wrapLonDeg(x), kNoData);
        for (double x : growingSteps(east + widestGap, mid, d))
            points.emplace_back(wrapLonDeg(x), kNoData);
        points.emplace_back(wrapLonDeg(mid), kNoData);
    }
    std::stable_sort(points.begin(), points.end(), [](const auto& p, const auto& q) { return p.first < q.first; });
    out.deg.clear();
    out.source.clear();
    for (const auto& [x, i] : points) {
        out.deg.push_back(x);
        out.source.push_back(i);
    }
    return out;
}


bool SphericalGrid::sameAs(const SphericalGrid& other, double tolerance) const
{
    auto same = [tolerance](const std::vector<double>& a, const std::vector<double>& b) {
        if (a.size() != b.size())
            return false;
        for (size_t i = 0; i < a.size(); ++i)
            if (std::abs(a[i] - b[i]) > tolerance)
                return false;
        return true;
    };
    return same(latDeg, other.latDeg) && same(rKm, other.rKm) && same(lonDeg, other.lonDeg) &&
           dataLatDeg.has_value() == other.dataLatDeg.has_value() && dataLonDeg.has_value() == other.dataLonDeg.has_value() &&
           (!dataLatDeg || same({(*dataLatDeg)[0], (*dataLatDeg)[1]}, {(*other.dataLatDeg)[0], (*other.dataLatDeg)[1]})) &&
           (!dataLonDeg || same({(*dataLonDeg)[0], (*dataLonDeg)[1]}, {(*other.dataLonDeg)[0], (*other.dataLonDeg)[1]}));
}

BrickLayout BrickLayout::forGrid(const SphericalGrid& grid, uint32_t size)
{
    RAYPC_CHECK(size > 0);
    BrickLayout b;
    b.size = size;
    auto bricks = [size](size_t n) { return static_cast<uint32_t>((n + size - 1) / size); };
    b.count = {bricks(grid.nLat()), bricks(grid.nR()), bricks(grid.nLon())};
    return b;
}

}  // namespace raypc::grid
