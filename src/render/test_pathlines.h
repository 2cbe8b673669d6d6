// Synthetic pathline sets for tests and golden images (header-only; not used by the renderer).
// Lines are given as polylines with times; the attribute columns are those of the stored format
// (kPathlineFixedColumns, then "start <v>"/"end <v>" for the given variables), computed from the
// points so that filters have known truth.
#pragma once

#include "core/spherical.h"
#include "analysis/pathlines.h"

#include <cmath>
#include <functional>
#include <string>
#include <vector>

namespace raypc::render::testing {

struct TestLine {
    std::vector<Vec3d> pointsKm;
    std::vector<double> timesMyr;
};

// `values(name, point)` gives a variable's value at a point (for the start/end columns).
inline analysis::PathlineSet makePathlineSet(int injectionStep, double injectionTimeMyr, int endStep,
                                   const std::vector<TestLine>& lines, const std::vector<std::string>& variables = {},
                                   const std::function<double(const std::string&, const Vec3d&)>& values = {})
{
    analysis::PathlineSet set;
    set.injectionStep = injectionStep;
    set.injectionTimeMyr = injectionTimeMyr;
    set.endStep = endStep;
    set.seedField = "temperature anomaly";
    set.columns = analysis::pathlineColumns(variables);
    set.units.assign(set.columns.size(), "");
    set.offsets.push_back(0);
    for (const TestLine& line : lines) {
        double lengthKm = 0;
        for (size_t i = 0; i < line.pointsKm.size(); ++i) {
            const Vec3d& p = line.pointsKm[i];
            set.points.insert(set.points.end(), {float(p.x), float(p.y), float(p.z), float(line.timesMyr[i])});
            if (i > 0) {
                const Vec3d& q = line.pointsKm[i - 1];
                lengthKm += std::sqrt((p.x - q.x) * (p.x - q.x) + (p.y - q.y) * (p.y - q.y) + (p.z - q.z) * (p.z - q.z));
            }
        }
        set.offsets.push_back(uint32_t(set.points.size() / 4));
        const SphericalPoint a = cartesianToSpherical(line.pointsKm.front());
        const SphericalPoint b = cartesianToSpherical(line.pointsKm.back());
        std::vector<float> row = {3.0f, 100.0f, 50.0f, float(injectionTimeMyr),
                                  float(line.timesMyr.back() - line.timesMyr.front()), float(lengthKm), 0.0f,
                                  float(a.latDeg), float(a.lonDeg), float(a.rKm), float(b.latDeg), float(b.lonDeg),
                                  float(b.rKm)};
        for (const Vec3d* p : {&line.pointsKm.front(), &line.pointsKm.back()})
            for (const auto& v : variables)
                row.push_back(values ? float(values(v, *p)) : 0.0f);
        set.attributes.insert(set.attributes.end(), row.begin(), row.end());
    }
    return set;
}

// A straight line from a to b with n points, times from t0 to t1.
inline TestLine straightLine(Vec3d a, Vec3d b, int n, double t0Myr, double t1Myr)
{
    TestLine line;
    for (int i = 0; i < n; ++i) {
        const double u = double(i) / double(n - 1);
        line.pointsKm.push_back({a.x + u * (b.x - a.x), a.y + u * (b.y - a.y), a.z + u * (b.z - a.z)});
        line.timesMyr.push_back(t0Myr + u * (t1Myr - t0Myr));
    }
    return line;
}

// A rising helix around the radial direction at (latDeg, lonDeg): from radius r0 to r1, `turns`
// turns of radius `helixKm`, n points, times from t0 to t1.
inline TestLine helixLine(double latDeg, double lonDeg, double r0, double r1, double helixKm, double turns, int n,
                          double t0Myr, double t1Myr)
{
    const Vec3d axis = sphericalToCartesianKm(latDeg, lonDeg, 1.0);
    const Vec3d e1 = sphericalToCartesianKm(latDeg, lonDeg + 90.0, 1.0);
    const Vec3d e2{axis.y * e1.z - axis.z * e1.y, axis.z * e1.x - axis.x * e1.z, axis.x * e1.y - axis.y * e1.x};
    TestLine line;
    for (int i = 0; i < n; ++i) {
        const double u = double(i) / double(n - 1);
        const double r = r0 + u * (r1 - r0), phi = 2 * M_PI * turns * u;
        const double c = helixKm * std::cos(phi), s = helixKm * std::sin(phi);
        line.pointsKm.push_back({axis.x * r + e1.x * c + e2.x * s, axis.y * r + e1.y * c + e2.y * s,
                                 axis.z * r + e1.z * c + e2.z * s});
        line.timesMyr.push_back(t0Myr + u * (t1Myr - t0Myr));
    }
    return line;
}

}  // namespace raypc::render::testing
