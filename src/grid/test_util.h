// Helpers for data-layer tests: temporary directories, the shared fixture, and small netCDF
// files written from CDL text by ncgen (Debian's netcdf-bin), an independent writer.
#pragma once

#include "grid/grid.h"

#include <cstddef>
#include <filesystem>
#include <functional>
#include <string>
#include <vector>

namespace raypc::testing {

// A fresh empty directory under the system temp dir, removed on destruction.
class TempDir {
public:
    explicit TempDir(const std::string& name);
    ~TempDir();
    const std::filesystem::path& path() const { return m_path; }
    std::filesystem::path operator/(const std::string& name) const { return m_path / name; }

private:
    std::filesystem::path m_path;
};

// The contest-layout fixture, written at test time by tests/data/contest-layout (ctest fixture
// test_data): three steps in the SciVis 2021 files' layout with the analytic fields of its truth.json.
std::filesystem::path contestLayoutDir();

// Writes `cdl` to a file and runs `ncgen -k <kind>` on it; kind is "nc3", "nc6" (64-bit
// offset) or "nc4". Fails the calling test (via exception) when ncgen fails.
std::filesystem::path ncgen(const std::filesystem::path& dir, const std::string& name, const std::string& cdl,
                            const std::string& kind = "nc6");

// A global grid with cell-centred lat rows (no pole rows), nR radii evenly from the core-mantle
// boundary to the surface, and lon columns at i * 360 / nLon.
grid::SphericalGrid centredGrid(size_t nLat, size_t nR, size_t nLon);

// f(iLat, iR, iLon) at every grid point, canonical order.
std::vector<float> fillGrid(const grid::SphericalGrid& g, const std::function<double(size_t, size_t, size_t)>& f);

// exp(-d² / 2σ²), d the Cartesian distance (km) from (latDeg, lonDeg, rKm): a field with one
// maximum of 1 at the centre, the same shape across the lon seam and the poles.
double gaussianBlob(const grid::SphericalGrid& g, size_t iLat, size_t iR, size_t iLon, double latDeg, double lonDeg,
                    double rKm, double sigmaKm);

// Runs a shell command; returns its exit status.
int run(const std::string& command);

}  // namespace raypc::testing
