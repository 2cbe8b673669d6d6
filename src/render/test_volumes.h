// Analytic in-memory volumes for tests, golden images and benchmarks (header-only; not used by the
// renderer itself). Fields are closed-form functions of (lat, r, lon) so the truth is known.
#pragma once

#include "dataset/dataset.h"

#include <cmath>
#include <functional>
#include <memory>
#include <string>
#include <vector>

namespace raypc::render::testing {


// A centred grid: lat rows at cell centres (no pole rows), r from the CMB to the surface, lon from 0.
// `stretch` > 0 makes r and lat non-uniform (denser near the ends) to exercise the coordinate maps.
inline grid::SphericalGrid makeGrid(int nLat, int nR, int nLon, double stretch = 0.0)
{
    grid::SphericalGrid g;
    for (int i = 0; i < nLat; ++i) {
        const double u = (i + 0.5) / nLat;  // (0, 1)
        const double w = u + stretch * std::sin(2 * M_PI * u) / (2 * M_PI);
        g.latDeg.push_back(-90.0 + 180.0 * w);
    }
    for (int i = 0; i < nR; ++i) {
        const double u = double(i) / (nR - 1);
        const double w = u - stretch * std::sin(2 * M_PI * u) / (2 * M_PI);
        g.rKm.push_back(3485.0 + (6371.0 - 3485.0) * w);
    }
    for (int i = 0; i < nLon; ++i)
        g.lonDeg.push_back(360.0 * i / nLon);
    return g;
}

using FieldFn = std::function<float(double latDeg, double rKm, double lonDeg)>;

struct NamedField {
    std::string name;
    FieldFn fn;
};

inline std::shared_ptr<dataset::StepVolume> makeVolume(const grid::SphericalGrid& grid, const std::vector<NamedField>& fields,
                                              uint32_t brickSize = 8)
{
    grid::Snapshot s;
    s.grid = grid;
    for (const auto& f : fields) {
        grid::Field field;
        field.name = f.name;
        field.units = "1";
        field.values.resize(grid.cellCount());
        for (size_t a = 0; a < grid.nLat(); ++a)
            for (size_t r = 0; r < grid.nR(); ++r)
                for (size_t o = 0; o < grid.nLon(); ++o)
                    field.values[grid.index(a, r, o)] = f.fn(grid.latDeg[a], grid.rKm[r], grid.lonDeg[o]);
        s.fields.push_back(std::move(field));
    }
    return dataset::StepVolume::fromSnapshot(s, brickSize);
}

// A smooth "plume" field with both signs: blobs at fixed places plus a radial trend.
inline float plumeField(double latDeg, double rKm, double lonDeg)
{
    const double lat = latDeg * M_PI / 180, lon = lonDeg * M_PI / 180;
    const double x = rKm * std::cos(lat) * std::cos(lon), y = rKm * std::cos(lat) * std::sin(lon), z = rKm * std::sin(lat);
    auto blob = [&](double cx, double cy, double cz, double s) {
        const double d2 = (x - cx) * (x - cx) + (y - cy) * (y - cy) + (z - cz) * (z - cz);
        return std::exp(-d2 / (s * s));
    };
    return float(blob(4500, 1000, 2000, 900) - 0.8 * blob(-2000, 4000, -1500, 1100) + 0.6 * blob(0, -3000, 4500, 700) +
                 0.3 * std::sin(3 * lon) * std::cos(2 * lat) * (rKm - 3485) / 2886);
}

}  // namespace raypc::render::testing
