#include "grid/test_util.h"

#include "core/atomic_file.h"
#include "core/error.h"
#include "core/spherical.h"

#include <unistd.h>

#include <cmath>
#include <cstdlib>
#include <sys/wait.h>

namespace raypc::testing {

TempDir::TempDir(const std::string& name)
    : m_path(std::filesystem::temp_directory_path() / ("raypc_" + name + "_" + std::to_string(::getpid())))
{
    std::filesystem::remove_all(m_path);
    std::filesystem::create_directories(m_path);
}

TempDir::~TempDir()
{
    std::error_code ec;
    std::filesystem::remove_all(m_path, ec);
}

std::filesystem::path contestLayoutDir() { return std::filesystem::path(RAYPC_TEST_DATA_DIR) / "contest-layout"; }

grid::SphericalGrid centredGrid(size_t nLat, size_t nR, size_t nLon)
{
    grid::SphericalGrid g;
    for (size_t i = 0; i < nLat; ++i)
        g.latDeg.push_back(-90.0 + (i + 0.5) * 180.0 / nLat);
    for (size_t i = 0; i < nR; ++i)
        g.rKm.push_back(kCoreRadiusKm + i * (kSurfaceRadiusKm - kCoreRadiusKm) / (nR - 1));
    for (size_t i = 0; i < nLon; ++i)
        g.lonDeg.push_back(i * 360.0 / nLon);
    return g;
}

std::vector<float> fillGrid(const grid::SphericalGrid& g, const std::function<double(size_t, size_t, size_t)>& f)
{
    std::vector<float> v(g.cellCount());
    for (size_t a = 0; a < g.nLat(); ++a)
        for (size_t b = 0; b < g.nR(); ++b)
            for (size_t c = 0; c < g.nLon(); ++c)
                v[g.index(a, b, c)] = static_cast<float>(f(a, b, c));
    return v;
}

double gaussianBlob(const grid::SphericalGrid& g, size_t iLat, size_t iR, size_t iLon, double latDeg, double lonDeg,
                    double rKm, double sigmaKm)
{
    const Vec3d c = sphericalToCartesianKm(latDeg, lonDeg, rKm);
    const Vec3d p = sphericalToCartesianKm(g.latDeg[iLat], g.lonDeg[iLon], g.rKm[iR]);
    const double d2 = (p.x - c.x) * (p.x - c.x) + (p.y - c.y) * (p.y - c.y) + (p.z - c.z) * (p.z - c.z);
    return std::exp(-d2 / (2 * sigmaKm * sigmaKm));
}

int run(const std::string& command)
{
    const int status = std::system(command.c_str());
    return WIFEXITED(status) ? WEXITSTATUS(status) : -1;
}

std::filesystem::path ncgen(const std::filesystem::path& dir, const std::string& name, const std::string& cdl,
                            const std::string& kind)
{
    const auto cdlPath = dir / (name + ".cdl");
    const auto ncPath = dir / (name + ".nc");
    writeFileAtomic(cdlPath, cdl);
    const std::string cmd = "ncgen -k " + kind + " -o '" + ncPath.string() + "' '" + cdlPath.string() + "'";
    if (run(cmd) != 0)
        fail("ncgen failed: {}", cmd);
    return ncPath;
}

}  // namespace raypc::testing
