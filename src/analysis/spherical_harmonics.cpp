// Spherical-harmonic transforms of a shell through libsharp (spherical_harmonics.h).
#include "analysis/spherical_harmonics.h"

#include "core/error.h"

#include <fmt/format.h>
#include <libsharp/sharp.h>
#include <libsharp/sharp_geomhelpers.h>
#include <libsharp/sharp_almhelpers.h>

#include <algorithm>
#include <cmath>
#include <numbers>

// The two calls of the OpenMP API used here, answered by libgomp, the runtime libsharp runs on
// (src/analysis/CMakeLists.txt): declared rather than taken from <omp.h>, which is the compiler's.
extern "C" {
int omp_get_max_threads(void);
void omp_set_num_threads(int);
}

namespace raypc::analysis {
namespace {

constexpr double kAxisToleranceDeg = 1e-4;  // coordinates stored as float in files

bool evenlySpaced(const std::vector<double>& deg, double first, double spacing)
{
    for (size_t i = 0; i < deg.size(); ++i)
        if (std::abs(deg[i] - (first + double(i) * spacing)) > kAxisToleranceDeg)
            return false;
    return true;
}

// libsharp runs an OpenMP team inside each transform; callers parallelise over shells (oneTBB), so
// each transform keeps to its calling thread. The setting is per thread (OpenMP's nthreads-var) and
// is put back afterwards.
class OneOpenMpThread {
public:
    OneOpenMpThread() : m_before(omp_get_max_threads()) { omp_set_num_threads(1); }
    ~OneOpenMpThread() { omp_set_num_threads(m_before); }

private:
    int m_before;
};

}  // namespace

struct ShellTransform::Sharp {
    sharp_geom_info* geometry = nullptr;
    sharp_alm_info* alm = nullptr;
    ~Sharp()
    {
        if (geometry)
            sharp_destroy_geom_info(geometry);
        if (alm)
            sharp_destroy_alm_info(alm);
    }
};

std::string quadratureName(SphereQuadrature quadrature)
{
    switch (quadrature) {
    case SphereQuadrature::Fejer1:
        return "Fejér's first rule";
    case SphereQuadrature::ClenshawCurtis:
        return "Clenshaw–Curtis";
    case SphereQuadrature::AreaWeights:
        break;
    }
    return "area weights";
}

SphereQuadrature quadratureOf(const grid::SphericalGrid& grid)
{
    const size_t n = grid.nLat();
    if (n >= 2 && evenlySpaced(grid.latDeg, -90.0 + 90.0 / double(n), 180.0 / double(n)))
        return SphereQuadrature::Fejer1;
    if (n >= 3 && evenlySpaced(grid.latDeg, -90.0, 180.0 / double(n - 1)))
        return SphereQuadrature::ClenshawCurtis;
    return SphereQuadrature::AreaWeights;
}

std::string transformRefusal(const grid::SphericalGrid& grid)
{
    if (grid.regional()) {
        const std::string lat =
            grid.dataLatDeg ? fmt::format("lat {:g}..{:g}°", (*grid.dataLatDeg)[0], (*grid.dataLatDeg)[1]) : "all latitudes";
        const std::string lon =
            grid.dataLonDeg ? fmt::format("lon {:g}..{:g}° east", (*grid.dataLonDeg)[0], (*grid.dataLonDeg)[1]) : "all longitudes";
        return fmt::format("the grid is regional (data within {}, {}); spherical harmonics need the whole sphere", lat, lon);
    }
    if (grid.nLat() < 3 || grid.nLon() < 3)
        return fmt::format("the grid has {} rows and {} columns; spherical harmonics need at least 3 of each", grid.nLat(),
                           grid.nLon());
    const double spacing = 360.0 / double(grid.nLon());
    if (!evenlySpaced(grid.lonDeg, grid.lonDeg.front(), spacing))
        return fmt::format("the {} longitudes are not evenly spaced over 360° ({:g}° apart); spherical harmonics on "
                           "iso-latitude rings need equal spacing",
                           grid.nLon(), spacing);
    return "";
}

int maxDegree(const grid::SphericalGrid& grid)
{
    return int(std::min((grid.nLat() - 1) / 2, (grid.nLon() - 1) / 2));
}

ShellTransform::ShellTransform(const grid::SphericalGrid& grid, int lmax, const std::string& what)
    : m_grid(grid), m_lmax(lmax), m_sharp(std::make_unique<Sharp>())
{
    if (const std::string why = transformRefusal(grid); !why.empty())
        fail("{}: {}", what, why);
    const int most = maxDegree(grid);
    if (lmax < 0 || lmax > most)
        fail("{}: degree {} is out of range 0..{} (the grid's {} rows and {} columns resolve degrees up to {})", what, lmax,
             most, grid.nLat(), grid.nLon(), most);
    m_quadrature = quadratureOf(grid);
    const int nLat = int(grid.nLat()), nLon = int(grid.nLon());
    const double phi0 = grid.lonDeg.front() * std::numbers::pi / 180.0;
    // Rings north to south, as libsharp's helpers lay them out: a shell is copied in that order.
    switch (m_quadrature) {
    case SphereQuadrature::Fejer1:
        sharp_make_fejer1_geom_info(nLat, nLon, phi0, 1, nLon, &m_sharp->geometry);
        break;
    case SphereQuadrature::ClenshawCurtis:
        sharp_make_cc_geom_info(nLat, nLon, phi0, 1, nLon, &m_sharp->geometry);
        break;
    case SphereQuadrature::AreaWeights: {
        const grid::SphericalGrid::VolumeFactors f = grid.volumeFactors();
        const size_t rings = grid.nLat();
        std::vector<int> nph(rings, nLon), stride(rings, 1);
        std::vector<ptrdiff_t> ofs(rings);
        std::vector<double> phi(rings, phi0), theta(rings), weight(rings);
        for (int ring = 0; ring < nLat; ++ring) {
            const size_t iLat = size_t(nLat - 1 - ring);
            ofs[size_t(ring)] = ptrdiff_t(ring) * nLon;
            theta[size_t(ring)] = (90.0 - grid.latDeg[iLat]) * std::numbers::pi / 180.0;
            weight[size_t(ring)] = f.lat[iLat] * 2.0 * std::numbers::pi / double(nLon);
        }
        sharp_make_geom_info(nLat, nph.data(), ofs.data(), stride.data(), phi.data(), theta.data(), weight.data(),
                             &m_sharp->geometry);
        break;
    }
    }
    sharp_make_triangular_alm_info(lmax, lmax, 1, &m_sharp->alm);
}

ShellTransform::~ShellTransform() = default;

void ShellTransform::analyse(const float* values, size_t iR, std::vector<std::complex<double>>& alm) const
{
    const size_t nLat = m_grid.nLat(), nLon = m_grid.nLon();
    std::vector<double> shell(nLat * nLon);
    for (size_t iLat = 0; iLat < nLat; ++iLat) {
        const float* row = values + m_grid.index(iLat, iR, 0);
        std::copy(row, row + nLon, shell.begin() + ptrdiff_t(iLat * nLon));
    }
    analyseShell(shell, alm);
}

void ShellTransform::analyseShell(std::span<const double> shell, std::vector<std::complex<double>>& alm) const
{
    const size_t nLat = m_grid.nLat(), nLon = m_grid.nLon();
    if (shell.size() != nLat * nLon)
        fail("spherical harmonics: a shell of {} values, expected {} x {}", shell.size(), nLat, nLon);
    // North first, as the geometry's rings.
    std::vector<double> map(nLat * nLon);
    for (size_t iLat = 0; iLat < nLat; ++iLat)
        std::copy_n(shell.begin() + ptrdiff_t(iLat * nLon), nLon, map.begin() + ptrdiff_t((nLat - 1 - iLat) * nLon));
    alm.assign(coefficientCount(), {0.0, 0.0});
    void* almPtr = alm.data();
    void* mapPtr = map.data();
    const OneOpenMpThread one;
    sharp_execute(SHARP_MAP2ALM, 0, &almPtr, &mapPtr, m_sharp->geometry, m_sharp->alm, SHARP_DP, nullptr, nullptr);
}

void ShellTransform::synthesiseShell(const std::vector<std::complex<double>>& alm, std::vector<double>& shell) const
{
    const size_t nLat = m_grid.nLat(), nLon = m_grid.nLon();
    if (alm.size() != coefficientCount())
        fail("spherical harmonics: {} coefficients, expected {} (degree {})", alm.size(), coefficientCount(), m_lmax);
    std::vector<double> map(nLat * nLon, 0.0);
    void* almPtr = const_cast<std::complex<double>*>(alm.data());
    void* mapPtr = map.data();
    {
        const OneOpenMpThread one;
        sharp_execute(SHARP_ALM2MAP, 0, &almPtr, &mapPtr, m_sharp->geometry, m_sharp->alm, SHARP_DP, nullptr, nullptr);
    }
    shell.resize(nLat * nLon);
    for (size_t iLat = 0; iLat < nLat; ++iLat)
        std::copy_n(map.begin() + ptrdiff_t((nLat - 1 - iLat) * nLon), nLon, shell.begin() + ptrdiff_t(iLat * nLon));
}

std::vector<double> ShellTransform::powerPerDegree(const std::vector<std::complex<double>>& alm) const
{
    return crossPowerPerDegree(alm, alm);
}

std::vector<double> ShellTransform::crossPowerPerDegree(const std::vector<std::complex<double>>& a,
                                                        const std::vector<std::complex<double>>& b) const
{
    if (a.size() != coefficientCount() || b.size() != coefficientCount())
        fail("spherical harmonics: {} and {} coefficients, expected {} (degree {})", a.size(), b.size(), coefficientCount(),
             m_lmax);
    std::vector<double> out(size_t(m_lmax) + 1, 0.0);
    for (int m = 0; m <= m_lmax; ++m)
        for (int l = m; l <= m_lmax; ++l) {
            const size_t i = index(l, m);
            // a_l,-m b_l,-m* = conj(a_lm) b_lm (the real field's symmetry): m > 0 counts twice.
            out[size_t(l)] += (m == 0 ? 1.0 : 2.0) * (a[i] * std::conj(b[i])).real();
        }
    for (double& s : out)
        s /= 4.0 * std::numbers::pi;
    return out;
}

size_t missingOnShell(const grid::SphericalGrid& grid, const float* values, size_t iR)
{
    size_t missing = 0;
    for (size_t iLat = 0; iLat < grid.nLat(); ++iLat)
        for (size_t iLon = 0; iLon < grid.nLon(); ++iLon)
            missing += std::isnan(values[grid.index(iLat, iR, iLon)]) && grid.holdsData(iLat, iLon);
    return missing;
}

std::vector<double> degreeCorrelation(std::span<const double> powerA, std::span<const double> powerB,
                                      std::span<const double> crossPower)
{
    if (powerA.size() != powerB.size() || powerA.size() != crossPower.size())
        fail("degree correlation: {}, {} and {} degrees", powerA.size(), powerB.size(), crossPower.size());
    const double mostA = powerA.empty() ? 0.0 : *std::max_element(powerA.begin(), powerA.end());
    const double mostB = powerB.empty() ? 0.0 : *std::max_element(powerB.begin(), powerB.end());
    std::vector<double> r(powerA.size(), NAN);
    for (size_t l = 0; l < r.size(); ++l)
        if (powerA[l] > 1e-12 * mostA && powerB[l] > 1e-12 * mostB && powerA[l] > 0 && powerB[l] > 0)
            r[l] = std::clamp(crossPower[l] / std::sqrt(powerA[l] * powerB[l]), -1.0, 1.0);
    return r;
}

}  // namespace raypc::analysis
