#include "io/mesh_resample.h"

#include "core/clock.h"
#include "core/error.h"
#include "core/spherical.h"

#include <fmt/format.h>
#include <spdlog/spdlog.h>

#include <tbb/blocked_range.h>
#include <tbb/combinable.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <array>
#include <chrono>
#include <cmath>
#include <limits>
#include <mutex>

namespace raypc::io {
namespace {

constexpr double kRadPerDeg = M_PI / 180.0;
// A point is inside a cell when its reference coordinates are within this of the cell's domain.
constexpr double kInsideTolerance = 1e-6;
// The candidate box of a cell is its nodes' (lat, r, lon) extent widened by this share of itself
// on each side: a cell's faces bulge beyond its nodes' extent by far less for cells of a few
// degrees (a chord of 20° of arc sags by 1.5 % of the radius).
constexpr double kBoxPadding = 0.25;

using vtk::CellType;

// ---- VTK's Lagrange hexahedron numbering and the shape functions ---------------------------

// The lattice position (i, j, k) of each of the (p+1)³ points of a Lagrange hexahedron of degree
// p, by the point's index in the cell; for p = 1 the linear hexahedron's vertices.
struct LatticeTable {
    std::vector<std::array<int, 3>> ijk;
};

const LatticeTable& latticeTable(int p)
{
    static std::once_flag once;
    static std::vector<LatticeTable> tables;
    std::call_once(once, [] {
        tables.resize(11);
        for (int q = 1; q <= 10; ++q) {
            tables[size_t(q)].ijk.resize(size_t((q + 1) * (q + 1) * (q + 1)));
            for (int k = 0; k <= q; ++k)
                for (int j = 0; j <= q; ++j)
                    for (int i = 0; i <= q; ++i)
                        tables[size_t(q)].ijk[size_t(lagrangeHexPointIndex(i, j, k, q))] = {i, j, k};
        }
    });
    RAYPC_CHECK(p >= 1 && p <= 10);
    return tables[size_t(p)];
}

// The p + 1 Lagrange polynomials on equally spaced nodes a / p of [0, 1] at t, and their derivatives.
void lagrangeBasis(int p, double t, double* value, double* derivative)
{
    for (int a = 0; a <= p; ++a) {
        const double ta = double(a) / p;
        double v = 1, d = 0;
        for (int b = 0; b <= p; ++b) {
            if (b == a)
                continue;
            const double tb = double(b) / p, f = (t - tb) / (ta - tb);
            d = d * f + v / (ta - tb);  // product rule, accumulated factor by factor
            v *= f;
        }
        value[a] = v;
        derivative[a] = d;
    }
}

// One cell being resampled: its type, degree and nodes (km), gathered from its piece.
struct Cell {
    CellType type = CellType::Hexahedron;
    int degree = 1;
    int nodeCount = 0;
    const vtk::Piece* piece = nullptr;
    int64_t begin = 0;  // in piece->connectivity
    std::vector<std::array<double, 3>> nodes;

    void gather(const vtk::Piece& p, size_t c)
    {
        piece = &p;
        type = p.types[c];
        begin = p.cellBegin(c);
        nodeCount = int(p.offsets[c] - begin);
        degree = vtk::cellDegree(type, nodeCount);
        nodes.resize(size_t(nodeCount));
        for (int n = 0; n < nodeCount; ++n) {
            const size_t pt = size_t(p.connectivity[size_t(begin + n)]);
            nodes[size_t(n)] = {p.points[3 * pt], p.points[3 * pt + 1], p.points[3 * pt + 2]};
        }
    }
    size_t pointIndex(int n) const { return size_t(piece->connectivity[size_t(begin + n)]); }
};

// Shape function values of every node of `cell` at reference coordinates `ref`, and with `grad`
// their derivatives (3 per node).
void shapeFunctions(const Cell& cell, const double ref[3], double* value, double* grad)
{
    const double x = ref[0], y = ref[1], z = ref[2];
    switch (cell.type) {
    case CellType::Tetra:
        value[0] = 1 - x - y - z, value[1] = x, value[2] = y, value[3] = z;
        if (grad) {
            const double g[12] = {-1, -1, -1, 1, 0, 0, 0, 1, 0, 0, 0, 1};
            std::copy(g, g + 12, grad);
        }
        return;
    case CellType::Wedge: {
        const double t = 1 - x - y;
        value[0] = t * (1 - z), value[1] = x * (1 - z), value[2] = y * (1 - z);
        value[3] = t * z, value[4] = x * z, value[5] = y * z;
        if (grad) {
            const double g[18] = {-(1 - z), -(1 - z), -t, (1 - z), 0, -x, 0, (1 - z), -y,
                                  -z,       -z,       t,  z,       0, x,  0, z,       y};
            std::copy(g, g + 18, grad);
        }
        return;
    }
    case CellType::Hexahedron:
        if (cell.degree == 1) {
            // The trilinear hexahedron, VTK's vertex order: (0,0,0) (1,0,0) (1,1,0) (0,1,0), then z = 1.
            const double X[2] = {1 - x, x}, Y[2] = {1 - y, y}, Z[2] = {1 - z, z};
            constexpr int corner[8][3] = {{0, 0, 0}, {1, 0, 0}, {1, 1, 0}, {0, 1, 0},
                                          {0, 0, 1}, {1, 0, 1}, {1, 1, 1}, {0, 1, 1}};
            for (int n = 0; n < 8; ++n) {
                const int i = corner[n][0], j = corner[n][1], k = corner[n][2];
                value[n] = X[i] * Y[j] * Z[k];
                if (grad) {
                    const double si = i ? 1 : -1, sj = j ? 1 : -1, sk = k ? 1 : -1;
                    grad[3 * n] = si * Y[j] * Z[k];
                    grad[3 * n + 1] = X[i] * sj * Z[k];
                    grad[3 * n + 2] = X[i] * Y[j] * sk;
                }
            }
            return;
        }
        [[fallthrough]];
    case CellType::LagrangeHexahedron: {
        const int p = cell.degree;
        double l[3][11], d[3][11];
        for (int a = 0; a < 3; ++a)
            lagrangeBasis(p, ref[a], l[a], d[a]);
        const auto& ijk = latticeTable(p).ijk;
        for (int n = 0; n < cell.nodeCount; ++n) {
            const auto [i, j, k] = ijk[size_t(n)];
            value[n] = l[0][i] * l[1][j] * l[2][k];
            if (grad) {
                grad[3 * n] = d[0][i] * l[1][j] * l[2][k];
                grad[3 * n + 1] = l[0][i] * d[1][j] * l[2][k];
                grad[3 * n + 2] = l[0][i] * l[1][j] * d[2][k];
            }
        }
        return;
    }
    }
}

// How far `ref` lies outside the cell's reference domain (0 inside), in reference units.
double outsideBy(CellType type, const double ref[3])
{
    const double x = ref[0], y = ref[1], z = ref[2];
    switch (type) {
    case CellType::Tetra: return std::max({0.0, -x, -y, -z, x + y + z - 1});
    case CellType::Wedge: return std::max({0.0, -x, -y, x + y - 1, -z, z - 1});
    default: return std::max({0.0, -x, x - 1, -y, y - 1, -z, z - 1});
    }
}

// The nearest point of the reference domain (for a simplex face, the point scaled back onto it).
void clampToCell(CellType type, double ref[3])
{
    for (int a = 0; a < 3; ++a)
        ref[a] = std::clamp(ref[a], 0.0, 1.0);
    if (type == CellType::Tetra || type == CellType::Wedge) {
        const int n = type == CellType::Tetra ? 3 : 2;  // the simplex's coordinates
        double sum = 0;
        for (int a = 0; a < n; ++a)
            sum += ref[a];
        if (sum > 1)
            for (int a = 0; a < n; ++a)
                ref[a] /= sum;
    }
}

// Newton's method for the reference coordinates of `target` in `cell`, from `ref` when `warm` (a
// neighbouring point's), else from the cell's centre. Returns false when the iteration does not
// converge (a point far outside a strongly curved cell, a degenerate cell), or, for a linear cell
// (nearly affine: the second estimate is close), when after two steps the point lies farther
// outside than any point that could be snapped.
bool invertMap(const Cell& cell, const double target[3], double ref[3], bool warm, std::vector<double>& value,
               std::vector<double>& grad)
{
    if (warm)
        ;
    else if (cell.type == CellType::Wedge)
        ref[0] = ref[1] = 1.0 / 3, ref[2] = 0.5;
    else if (cell.type == CellType::Tetra)
        ref[0] = ref[1] = ref[2] = 0.25;
    else
        ref[0] = ref[1] = ref[2] = 0.5;
    value.resize(size_t(cell.nodeCount));
    grad.resize(3 * size_t(cell.nodeCount));
    for (int iteration = 0; iteration < 24; ++iteration) {
        shapeFunctions(cell, ref, value.data(), grad.data());
        double x[3] = {0, 0, 0}, J[3][3] = {};
        for (int n = 0; n < cell.nodeCount; ++n) {
            const auto& X = cell.nodes[size_t(n)];
            for (int r = 0; r < 3; ++r) {
                x[r] += value[size_t(n)] * X[size_t(r)];
                for (int c = 0; c < 3; ++c)
                    J[r][c] += X[size_t(r)] * grad[3 * size_t(n) + size_t(c)];
            }
        }
        const double f[3] = {x[0] - target[0], x[1] - target[1], x[2] - target[2]};
        // Solve J d = f by Cramer's rule.
        const double det = J[0][0] * (J[1][1] * J[2][2] - J[1][2] * J[2][1]) -
                           J[0][1] * (J[1][0] * J[2][2] - J[1][2] * J[2][0]) +
                           J[0][2] * (J[1][0] * J[2][1] - J[1][1] * J[2][0]);
        if (!(std::abs(det) > 0) || !std::isfinite(det))
            return false;
        double dRef[3];
        for (int c = 0; c < 3; ++c) {
            double M[3][3];
            for (int r = 0; r < 3; ++r)
                for (int k = 0; k < 3; ++k)
                    M[r][k] = k == c ? f[r] : J[r][k];
            dRef[c] = (M[0][0] * (M[1][1] * M[2][2] - M[1][2] * M[2][1]) -
                       M[0][1] * (M[1][0] * M[2][2] - M[1][2] * M[2][0]) +
                       M[0][2] * (M[1][0] * M[2][1] - M[1][1] * M[2][0])) /
                      det;
        }
        double step = 0;
        for (int c = 0; c < 3; ++c) {
            ref[c] -= dRef[c];
            step = std::max(step, std::abs(dRef[c]));
        }
        if (!(std::abs(ref[0]) < 8 && std::abs(ref[1]) < 8 && std::abs(ref[2]) < 8))
            return false;
        if (step < 1e-10)
            return true;
        if (iteration == 1 && cell.degree == 1 && outsideBy(cell.type, ref) > 2 * kSnapReference)
            return false;
        if (cell.type == CellType::Tetra)
            return true;  // linear: one step is exact
    }
    return false;
}

// ---- where a cell's candidates are ----------------------------------------------------------

struct Spherical {
    double latDeg, lonDeg, rKm;
};

Spherical toSpherical(const std::array<double, 3>& p)
{
    const double r = std::sqrt(p[0] * p[0] + p[1] * p[1] + p[2] * p[2]);
    double lon = std::atan2(p[1], p[0]) / kRadPerDeg;
    if (lon < 0)
        lon += 360;
    return {r > 0 ? std::asin(std::clamp(p[2] / r, -1.0, 1.0)) / kRadPerDeg : 0.0, lon, r};
}

// Index range [first, last) of the ascending `axis` values within [lo, hi].
std::pair<size_t, size_t> indexRange(const std::vector<double>& axis, double lo, double hi)
{
    const auto first = std::lower_bound(axis.begin(), axis.end(), lo);
    const auto last = std::upper_bound(first, axis.end(), hi);
    return {size_t(first - axis.begin()), size_t(last - axis.begin())};
}

// A cell's candidate grid points: rows [lat0, lat1), radii [r0, r1), and up to two lon index ranges
// (a cell across the seam has one on each side of it).
struct CellBox {
    uint32_t lat0 = 0, lat1 = 0, r0 = 0, r1 = 0;
    std::array<std::pair<uint32_t, uint32_t>, 2> lon{};
    std::array<double, 3> lo{}, hi{};  // Cartesian box of the nodes, widened (km)
};

CellBox boxOf(const Cell& cell, const grid::SphericalGrid& grid, std::vector<double>& lons)
{
    double latLo = 90, latHi = -90, rLo = INFINITY, rHi = 0;
    std::array<double, 3> lo{INFINITY, INFINITY, INFINITY}, hi{-INFINITY, -INFINITY, -INFINITY};
    lons.resize(size_t(cell.nodeCount));
    for (int n = 0; n < cell.nodeCount; ++n) {
        const auto& X = cell.nodes[size_t(n)];
        const Spherical s = toSpherical(X);
        latLo = std::min(latLo, s.latDeg), latHi = std::max(latHi, s.latDeg);
        rLo = std::min(rLo, s.rKm), rHi = std::max(rHi, s.rKm);
        lons[size_t(n)] = s.lonDeg;
        for (int a = 0; a < 3; ++a)
            lo[size_t(a)] = std::min(lo[size_t(a)], X[size_t(a)]), hi[size_t(a)] = std::max(hi[size_t(a)], X[size_t(a)]);
    }
    // A linear cell lies within its nodes' convex hull, so within their Cartesian box; widened by how
    // far a grid point on the curved boundary shell may lie outside a flat face between nodes (the
    // chord's sag, r θ² / 8 for an arc of θ) to be snapped. A Lagrange cell bulges: by a share of itself.
    const double diagonal = std::sqrt((hi[0] - lo[0]) * (hi[0] - lo[0]) + (hi[1] - lo[1]) * (hi[1] - lo[1]) +
                                      (hi[2] - lo[2]) * (hi[2] - lo[2]));
    const double theta = diagonal / std::max(rLo, 1.0), sag = rHi * theta * theta / 8;
    for (int a = 0; a < 3; ++a) {
        const double extent = hi[size_t(a)] - lo[size_t(a)];
        const double pad = cell.degree == 1 ? 0.01 * extent + 2 * sag + 1e-6 : kBoxPadding * extent + 1e-6;
        lo[size_t(a)] -= pad, hi[size_t(a)] += pad;
    }
    // Longitudes: the shorter way round; a cell across the seam is taken from below 360° to above it.
    auto [lonLoIt, lonHiIt] = std::minmax_element(lons.begin(), lons.end());
    double lonLo = *lonLoIt, lonHi = *lonHiIt;
    if (lonHi - lonLo > 180) {
        for (double& l : lons)
            if (l < 180)
                l += 360;
        const auto [a, b] = std::minmax_element(lons.begin(), lons.end());
        lonLo = *a, lonHi = *b;
    }
    // Still more than half the circle: the cell surrounds the polar axis; it takes every longitude
    // and reaches the pole on its side.
    const bool aroundAxis = lonHi - lonLo > 180;
    // A linear cell's (lat, r, lon) extent beyond its nodes': its edges are great-circle arcs seen from
    // the centre, which keep within their ends' longitudes and exceed their latitudes by about
    // θ² tan|lat| / 8 (at most θ / 2); its flat faces sag below the nodes' radii by r θ² / 8. A
    // Lagrange cell bulges: a share of its extent.
    double latPad, lonShare, rPadBelow, rPadAbove;
    if (cell.degree == 1) {
        const double tanLat = std::tan(std::min(std::max(std::abs(latLo), std::abs(latHi)), 89.9) * kRadPerDeg);
        latPad = 0.02 * (latHi - latLo) + std::min(theta / 2, theta * theta * tanLat / 8) / kRadPerDeg + 1e-9;
        lonShare = 0.02;
        rPadBelow = 0.02 * (rHi - rLo) + 2 * sag + 1e-9, rPadAbove = 0.02 * (rHi - rLo) + 1e-9;
    } else {
        latPad = kBoxPadding * (latHi - latLo) + 1e-9;
        lonShare = kBoxPadding;
        rPadBelow = rPadAbove = kBoxPadding * (rHi - rLo) + 1e-9;
    }
    latLo -= latPad, latHi += latPad;
    if (aroundAxis) {
        if (latHi + latLo > 0)
            latHi = 90;
        else
            latLo = -90;
    }
    CellBox box;
    box.lo = lo, box.hi = hi;
    const auto [lat0, lat1] = indexRange(grid.latDeg, latLo, latHi);
    const auto [r0, r1] = indexRange(grid.rKm, rLo - rPadBelow, rHi + rPadAbove);
    box.lat0 = uint32_t(lat0), box.lat1 = uint32_t(lat1), box.r0 = uint32_t(r0), box.r1 = uint32_t(r1);
    if (aroundAxis || lonHi - lonLo >= 360) {
        box.lon[0] = {0, uint32_t(grid.nLon())};
        return box;
    }
    const double lonPad = lonShare * (lonHi - lonLo) + 1e-9;
    lonLo -= lonPad, lonHi += lonPad;
    // [lonLo, lonHi] may reach below 0 or above 360: split at the seam.
    const auto part = [&](double a, double b) {
        const auto [i0, i1] = indexRange(grid.lonDeg, a, b);
        return std::pair<uint32_t, uint32_t>{uint32_t(i0), uint32_t(i1)};
    };
    if (lonLo < 0) {
        box.lon[0] = part(0, lonHi);
        box.lon[1] = part(lonLo + 360, 360);
    } else if (lonHi >= 360) {
        box.lon[0] = part(lonLo, 360);
        box.lon[1] = part(0, lonHi - 360);
    } else {
        box.lon[0] = part(lonLo, lonHi);
    }
    return box;
}

}  // namespace

int lagrangeHexPointIndex(int i, int j, int k, int p)
{
    // VTK's order: the 8 vertices as in a linear hexahedron; the inner points of the 12 edges
    // (4 at k = 0: along i at j = 0, along j at i = p, along i at j = p, along j at i = 0; the
    // same 4 at k = p; then the 4 along k, at (i, j) = (0, 0), (p, 0), (0, p), (p, p) in that
    // order, as VTK numbers them); the inner points of the faces i = 0, i = p, j = 0, j = p,
    // k = 0, k = p (each row-major in its two other indices, the lower one fastest); the interior
    // (i fastest, then j, then k).
    const bool onI = i == 0 || i == p, onJ = j == 0 || j == p, onK = k == 0 || k == p;
    const int boundaries = int(onI) + int(onJ) + int(onK);
    const int e = p - 1;  // inner points per edge
    if (boundaries == 3)
        return (i ? (j ? 2 : 1) : (j ? 3 : 0)) + (k ? 4 : 0);
    int offset = 8;
    if (boundaries == 2) {
        const int layer = k ? 4 * e : 0;  // the k = p edges follow the k = 0 ones
        if (!onI)
            return offset + layer + (j ? 2 * e : 0) + (i - 1);
        if (!onJ)
            return offset + layer + (i ? e : 3 * e) + (j - 1);
        offset += 8 * e;
        const int corner = i ? (j ? 3 : 1) : (j ? 2 : 0);
        return offset + corner * e + (k - 1);
    }
    offset += 12 * e;
    if (boundaries == 1) {
        if (onI)
            return offset + (i ? e * e : 0) + (k - 1) * e + (j - 1);
        offset += 2 * e * e;
        if (onJ)
            return offset + (j ? e * e : 0) + (k - 1) * e + (i - 1);
        offset += 2 * e * e;
        return offset + (k ? e * e : 0) + (j - 1) * e + (i - 1);
    }
    offset += 6 * e * e;
    return offset + ((k - 1) * e + (j - 1)) * e + (i - 1);
}

namespace {

// A mesh's extent when it is regional (ShellMesh::latExtentDeg, lonExtentDeg): its nodes' latitudes,
// and the widest gap between its nodes' longitudes (on a tenth-of-a-degree circle of bins).
void findRegion(ShellMesh& mesh, const std::vector<vtk::Piece>& pieces)
{
    constexpr int kBinsPerDeg = 10;
    struct Partial {
        double south = 90, north = -90;
        // Per bin the least and the largest longitude of a node in it (+inf, -inf: none).
        std::vector<double> lonLo = std::vector<double>(360 * kBinsPerDeg, INFINITY);
        std::vector<double> lonHi = std::vector<double>(360 * kBinsPerDeg, -INFINITY);
    };
    tbb::combinable<Partial> partial;
    for (const auto& piece : pieces)
        tbb::parallel_for(tbb::blocked_range<size_t>(0, piece.points.size() / 3, 1 << 14), [&](const auto& range) {
            Partial& p = partial.local();
            for (size_t i = range.begin(); i != range.end(); ++i) {
                const SphericalPoint s = cartesianToSpherical(
                    Vec3d{piece.points[3 * i], piece.points[3 * i + 1], piece.points[3 * i + 2]});
                p.south = std::min(p.south, s.latDeg), p.north = std::max(p.north, s.latDeg);
                const double lon = wrapLonDeg(s.lonDeg);
                const size_t b = std::min(size_t(lon * kBinsPerDeg), size_t(360 * kBinsPerDeg - 1));
                p.lonLo[b] = std::min(p.lonLo[b], lon), p.lonHi[b] = std::max(p.lonHi[b], lon);
            }
        });
    Partial all;
    partial.combine_each([&](const Partial& p) {
        all.south = std::min(all.south, p.south), all.north = std::max(all.north, p.north);
        for (size_t b = 0; b < all.lonLo.size(); ++b)
            all.lonLo[b] = std::min(all.lonLo[b], p.lonLo[b]), all.lonHi[b] = std::max(all.lonHi[b], p.lonHi[b]);
    });
    const auto occupied = [&](int b) { return all.lonLo[size_t(b)] <= all.lonHi[size_t(b)]; };
    // Nodes of a mesh that covers the globe lie within a cell of every pole and every meridian: gaps
    // are measured against its coarsest cell (the arc between a cell's farthest nodes).
    const double margin = 2 * mesh.coarsestArcDeg;
    if (all.south > -90 + margin || all.north < 90 - margin)
        mesh.latExtentDeg = std::array<double, 2>{all.south, all.north};
    // The widest run of empty bins on the circle; a gap wider than two cells is outside the mesh (a
    // mesh that reaches a pole has nodes at every longitude near it).
    const int n = int(all.lonLo.size());
    int first = -1;
    for (int b = 0; b < n && first < 0; ++b)
        if (occupied(b))
            first = b;
    if (first < 0)
        return;
    int bestStart = 0, bestLength = 0;
    for (int k = 1, run = 0; k <= n; ++k) {
        const int b = (first + k) % n;
        if (!occupied(b)) {
            ++run;
            continue;
        }
        if (run > bestLength)
            bestLength = run, bestStart = (b - run + n) % n;
        run = 0;
    }
    if (double(bestLength) / kBinsPerDeg > margin) {
        // The nodes on either side of the gap: the easternmost before it, the westernmost after it.
        const double east = all.lonHi[size_t((bestStart - 1 + n) % n)];
        const double west = all.lonLo[size_t((bestStart + bestLength) % n)];
        mesh.lonExtentDeg = std::array<double, 2>{west, east};
    }
}

}  // namespace

ShellMesh makeShellMesh(std::vector<vtk::Piece> pieces, double kmPerUnit, const std::string& what)
{
    ShellMesh mesh;
    mesh.kmPerUnit = kmPerUnit;
    mesh.rMinKm = INFINITY;
    mesh.finestArcDeg = INFINITY, mesh.finestRadialKm = INFINITY;
    // The shell's radii and the finest cell, over every cell's nodes, in parallel.
    struct Extent {
        double rMin = INFINITY, rMax = 0, arcDeg = INFINITY, radialKm = INFINITY, coarsestArcDeg = 0;
    };
    tbb::combinable<Extent> partial;
    for (auto& piece : pieces) {
        tbb::parallel_for(tbb::blocked_range<size_t>(0, piece.points.size(), 1 << 16),
                          [&](const tbb::blocked_range<size_t>& range) {
                              for (size_t i = range.begin(); i != range.end(); ++i)
                                  piece.points[i] *= kmPerUnit;
                          });
        mesh.cellCount += piece.cellCount();
        mesh.pointCount += piece.pointCount();
        tbb::parallel_for(tbb::blocked_range<size_t>(0, piece.cellCount(), 4096), [&](const tbb::blocked_range<size_t>& range) {
            Extent& e = partial.local();
            Cell cell;
            for (size_t c = range.begin(); c != range.end(); ++c) {
                cell.gather(piece, c);
                const auto& first = cell.nodes[0];
                const double rFirst = std::sqrt(first[0] * first[0] + first[1] * first[1] + first[2] * first[2]);
                double rLo = INFINITY, rHi = 0, arc = 0;
                for (const auto& X : cell.nodes) {
                    const double r = std::sqrt(X[0] * X[0] + X[1] * X[1] + X[2] * X[2]);
                    rLo = std::min(rLo, r), rHi = std::max(rHi, r);
                    // The angle between this node's direction and the first node's.
                    const double dot = (X[0] * first[0] + X[1] * first[1] + X[2] * first[2]) / (r * rFirst);
                    arc = std::max(arc, std::acos(std::clamp(dot, -1.0, 1.0)) / kRadPerDeg);
                }
                e.rMin = std::min(e.rMin, rLo), e.rMax = std::max(e.rMax, rHi);
                // A cell's arc between its farthest nodes is about √2 (a face's diagonal) to √3 times
                // its edge; the radial extent is one edge when the cell's radial edges are radial.
                if (arc > 0)
                    e.arcDeg = std::min(e.arcDeg, arc / std::sqrt(2.0) / cell.degree);
                e.coarsestArcDeg = std::max(e.coarsestArcDeg, arc);
                if (rHi > rLo)
                    e.radialKm = std::min(e.radialKm, (rHi - rLo) / cell.degree);
            }
        });
    }
    partial.combine_each([&](const Extent& e) {
        mesh.rMinKm = std::min(mesh.rMinKm, e.rMin), mesh.rMaxKm = std::max(mesh.rMaxKm, e.rMax);
        mesh.finestArcDeg = std::min(mesh.finestArcDeg, e.arcDeg);
        mesh.finestRadialKm = std::min(mesh.finestRadialKm, e.radialKm);
        mesh.coarsestArcDeg = std::max(mesh.coarsestArcDeg, e.coarsestArcDeg);
    });
    if (mesh.cellCount == 0)
        fail("{}: the mesh has no cells", what);
    if (!(mesh.rMinKm >= 3000 && mesh.rMaxKm <= 7000 && mesh.rMaxKm > mesh.rMinKm))
        fail("{}: the mesh's points lie at radii {:.6g} to {:.6g} km (coordinates taken as {}), not a mantle shell "
             "within 3000 to 7000 km; give their unit with --radius-units km|m|nondimensional",
             what, mesh.rMinKm, mesh.rMaxKm, kmPerUnit == 1e-3 ? std::string("metres") : fmt::format("{:g} km each", kmPerUnit));
    // The shell's radii to the metre: float32 coordinates put 3485 km at 3484.99985.
    mesh.rMinKm = std::round(mesh.rMinKm * 1e3) / 1e3, mesh.rMaxKm = std::round(mesh.rMaxKm * 1e3) / 1e3;
    if (!std::isfinite(mesh.finestArcDeg) || !std::isfinite(mesh.finestRadialKm))
        fail("{}: every cell of the mesh is flat (no extent along a shell or across radii)", what);
    findRegion(mesh, pieces);
    mesh.pieces = std::move(pieces);
    return mesh;
}

grid::SphericalGrid resampleGrid(const ShellMesh& mesh, size_t nLat, size_t nR, size_t nLon)
{
    RAYPC_CHECK(nLat >= 2 && nR >= 2 && nLon >= 4);
    grid::SphericalGrid g;
    for (size_t i = 0; i < nR; ++i)
        g.rKm.push_back(mesh.rMinKm + (mesh.rMaxKm - mesh.rMinKm) * double(i) / double(nR - 1));
    if (mesh.latExtentDeg) {
        const auto [south, north] = *mesh.latExtentDeg;
        for (size_t i = 0; i < nLat; ++i)
            g.latDeg.push_back(south + (north - south) * double(i) / double(nLat - 1));
        const grid::PaddedAxis padded = grid::padToGlobe(g.latDeg, true);
        g.latDeg = padded.deg;
        g.dataLatDeg = padded.extent;
    } else {
        for (size_t i = 0; i < nLat; ++i)
            g.latDeg.push_back(-90 + (double(i) + 0.5) * 180.0 / double(nLat));
    }
    if (mesh.lonExtentDeg) {
        const auto [west, east] = *mesh.lonExtentDeg;
        const double width = wrapLonDeg(east - west);
        for (size_t i = 0; i < nLon; ++i)
            g.lonDeg.push_back(wrapLonDeg(west + width * double(i) / double(nLon - 1)));
        std::sort(g.lonDeg.begin(), g.lonDeg.end());
        const grid::PaddedAxis padded = grid::padToGlobe(g.lonDeg, false);
        g.lonDeg = padded.deg;
        g.dataLonDeg = padded.extent;
    } else {
        for (size_t i = 0; i < nLon; ++i)
            g.lonDeg.push_back(360.0 * double(i) / double(nLon));
    }
    return g;
}

grid::SphericalGrid defaultResampleGrid(const ShellMesh& mesh, uint64_t maxPoints)
{
    // A spacing that divides the extent (to rounding) gives that many intervals, not one more.
    const auto intervals = [](double extent, double spacing) { return std::ceil(extent / spacing * (1 - 1e-9)); };
    double nLat = intervals(180, mesh.finestArcDeg), nLon = 2 * nLat;
    // A regional mesh: points on its extent's edges, as far apart as its finest cell.
    if (mesh.latExtentDeg)
        nLat = intervals((*mesh.latExtentDeg)[1] - (*mesh.latExtentDeg)[0], mesh.finestArcDeg) + 1;
    if (mesh.lonExtentDeg)
        nLon = intervals(wrapLonDeg((*mesh.lonExtentDeg)[1] - (*mesh.lonExtentDeg)[0]), mesh.finestArcDeg) + 1;
    double nR = intervals(mesh.rMaxKm - mesh.rMinKm, mesh.finestRadialKm) + 1;
    const double points = nLat * nR * nLon;
    if (points > double(maxPoints)) {
        const double s = std::cbrt(double(maxPoints) / points);
        nLat = std::floor(nLat * s), nR = std::floor(nR * s), nLon = mesh.lonExtentDeg ? std::floor(nLon * s) : 2 * nLat;
    }
    return resampleGrid(mesh, size_t(std::max(nLat, 2.0)), size_t(std::max(nR, 2.0)), size_t(std::max(nLon, 4.0)));
}

namespace {

// Each piece's point arrays named in `arrays`, checked: present, with the component asked for.
std::vector<std::vector<const vtk::PointArray*>> arraySources(const ShellMesh& mesh,
                                                              const std::vector<ArrayComponent>& arrays,
                                                              const std::string& what)
{
    std::vector<std::vector<const vtk::PointArray*>> sources(mesh.pieces.size());
    for (size_t p = 0; p < mesh.pieces.size(); ++p) {
        for (const auto& a : arrays) {
            const vtk::PointArray* found = mesh.pieces[p].find(a.name);
            if (!found)
                fail("{}: piece {} has no point array \"{}\"", what, p, a.name);
            if ((a.component < 0 && found->components != 1) || a.component >= found->components)
                fail("{}: piece {}: point array \"{}\" has {} components, expected {}", what, p, a.name,
                     found->components, a.component < 0 ? 1 : a.component + 1);
            sources[p].push_back(found);
        }
    }
    return sources;
}

// The mesh's cells found by lat row: every cell's candidate box, and the cells whose box reaches
// each lat row of the grid (rowCells[rowStart[row]] up to rowCells[rowStart[row + 1]], indices into
// cells and boxes).
struct CellsByRow {
    struct CellRef {
        uint32_t piece;
        uint32_t cell;
    };
    std::vector<CellRef> cells;
    std::vector<CellBox> boxes;
    std::vector<size_t> rowStart;
    std::vector<uint32_t> rowCells;
};

CellsByRow cellsByRow(const ShellMesh& mesh, const grid::SphericalGrid& grid)
{
    CellsByRow byRow;
    // Plain references, not a structured binding: the lambda below captures them (clang 14 cannot
    // capture bindings).
    std::vector<CellsByRow::CellRef>& cells = byRow.cells;
    std::vector<CellBox>& boxes = byRow.boxes;
    std::vector<size_t>& rowStart = byRow.rowStart;
    std::vector<uint32_t>& rowCells = byRow.rowCells;
    cells.reserve(mesh.cellCount);
    for (size_t p = 0; p < mesh.pieces.size(); ++p)
        for (size_t c = 0; c < mesh.pieces[p].cellCount(); ++c)
            cells.push_back({uint32_t(p), uint32_t(c)});
    boxes.resize(cells.size());
    tbb::parallel_for(tbb::blocked_range<size_t>(0, cells.size(), 4096), [&](const tbb::blocked_range<size_t>& range) {
        Cell cell;
        std::vector<double> lons;
        for (size_t i = range.begin(); i != range.end(); ++i) {
            cell.gather(mesh.pieces[cells[i].piece], cells[i].cell);
            boxes[i] = boxOf(cell, grid, lons);
        }
    });
    rowStart.assign(grid.nLat() + 1, 0);
    for (const CellBox& b : boxes)
        for (uint32_t row = b.lat0; row < b.lat1; ++row)
            ++rowStart[row + 1];
    for (size_t row = 0; row < grid.nLat(); ++row)
        rowStart[row + 1] += rowStart[row];
    rowCells.resize(rowStart.back());
    {
        std::vector<size_t> fill(rowStart.begin(), rowStart.end() - 1);
        for (size_t i = 0; i < boxes.size(); ++i)
            for (uint32_t row = boxes[i].lat0; row < boxes[i].lat1; ++row)
                rowCells[fill[row]++] = uint32_t(i);
    }
    return byRow;
}

// The cell's values of every array (`sources`: its piece's), node by node: nodeValues[a * nodeCount + n]
// is array a at node n.
void gatherNodeValues(const Cell& cell, const std::vector<const vtk::PointArray*>& sources,
                      const std::vector<ArrayComponent>& arrays, std::vector<double>& nodeValues)
{
    nodeValues.resize(arrays.size() * size_t(cell.nodeCount));
    for (size_t a = 0; a < arrays.size(); ++a) {
        const vtk::PointArray& src = *sources[a];
        const size_t stride = size_t(src.components), component = size_t(std::max(arrays[a].component, 0));
        for (int n = 0; n < cell.nodeCount; ++n)
            nodeValues[a * size_t(cell.nodeCount) + size_t(n)] = src.values[cell.pointIndex(n) * stride + component];
    }
}

// Resamples the grid's lat row `row` into `out` (arrays x grid points): a point takes the values of the
// first cell it lies in, else of the cell it lies nearest to within kSnapReference (its values at
// the nearest boundary), else stays NaN. Returns the row's counts (points left 0).
ResampleCounts resampleRow(size_t row, const ShellMesh& mesh, const grid::SphericalGrid& grid, const CellsByRow& byRow,
                           const std::vector<std::vector<const vtk::PointArray*>>& sources,
                           const std::vector<ArrayComponent>& arrays, const std::vector<double>& cosLon,
                           const std::vector<double>& sinLon, std::vector<std::vector<float>>& out)
{
    const auto& [cells, boxes, rowStart, rowCells] = byRow;
    const size_t rowPoints = grid.nR() * grid.nLon();
    std::vector<float> best(rowPoints, INFINITY);  // how far outside the best cell so far (0: inside)
    Cell cell;
    std::vector<double> value, grad, nodeValues;
    const double cosLat = std::cos(grid.latDeg[row] * kRadPerDeg), sinLat = std::sin(grid.latDeg[row] * kRadPerDeg);
    for (size_t k = rowStart[row]; k < rowStart[row + 1]; ++k) {
        const size_t i = rowCells[k];
        const CellBox& box = boxes[i];
        const vtk::Piece& piece = mesh.pieces[cells[i].piece];
        bool gathered = false, warm = false;
        double warmRef[3] = {0, 0, 0};
        for (uint32_t iR = box.r0; iR < box.r1; ++iR) {
            const double r = grid.rKm[iR];
            for (const auto& [lon0, lon1] : box.lon)
                for (uint32_t iLon = lon0; iLon < lon1; ++iLon) {
                    const size_t local = size_t(iR) * grid.nLon() + iLon;
                    if (best[local] == 0)
                        continue;  // already inside an earlier cell
                    const double target[3] = {r * cosLat * cosLon[iLon], r * cosLat * sinLon[iLon], r * sinLat};
                    if (target[0] < box.lo[0] || target[0] > box.hi[0] || target[1] < box.lo[1] ||
                        target[1] > box.hi[1] || target[2] < box.lo[2] || target[2] > box.hi[2])
                        continue;
                    if (!gathered) {
                        cell.gather(piece, cells[i].cell);
                        // The cell's values of every array, node by node, gathered once.
                        gatherNodeValues(cell, sources[cells[i].piece], arrays, nodeValues);
                        gathered = true;
                    }
                    double ref[3] = {warmRef[0], warmRef[1], warmRef[2]};
                    if (!invertMap(cell, target, ref, warm, value, grad))
                        continue;
                    if (outsideBy(cell.type, ref) <= kSnapReference) {
                        std::copy(ref, ref + 3, warmRef);
                        warm = true;
                    }
                    double outside = outsideBy(cell.type, ref);
                    if (outside <= kInsideTolerance)
                        outside = 0;
                    if (outside > kSnapReference || !(outside < best[local]))
                        continue;
                    best[local] = float(outside);
                    if (outside > 0)
                        clampToCell(cell.type, ref);
                    shapeFunctions(cell, ref, value.data(), nullptr);
                    const size_t index = grid.index(row, iR, iLon);
                    for (size_t a = 0; a < arrays.size(); ++a) {
                        const double* v = &nodeValues[a * size_t(cell.nodeCount)];
                        double sum = 0;
                        for (int n = 0; n < cell.nodeCount; ++n)
                            sum += value[size_t(n)] * v[n];
                        out[a][index] = float(sum);
                    }
                }
        }
    }
    // A point in no cell outside a regional grid's extent pads the grid; within it, it is missing.
    ResampleCounts local;
    const bool rowHoldsData = grid.latHoldsData(grid.latDeg[row]);
    for (size_t p = 0; p < rowPoints; ++p) {
        const float b = best[p];
        (b == 0                                                           ? local.inside
         : std::isfinite(b)                                               ? local.snapped
         : rowHoldsData && grid.lonHoldsData(grid.lonDeg[p % grid.nLon()]) ? local.missing
                                                                          : local.outside) += 1;
    }
    return local;
}

}  // namespace

std::vector<std::vector<float>> resampleOntoGrid(const ShellMesh& mesh, const grid::SphericalGrid& grid,
                                                 const std::vector<ArrayComponent>& arrays, const std::string& what,
                                                 ResampleCounts* counts)
{
    const auto sources = arraySources(mesh, arrays, what);
    const auto start = std::chrono::steady_clock::now();
    // Every cell's candidate box, then the cells of each lat row.
    const CellsByRow byRow = cellsByRow(mesh, grid);
    const double boxSeconds = secondsSince(start);
    std::vector<std::vector<float>> out(arrays.size(), std::vector<float>(grid.cellCount(), NAN));
    std::vector<double> cosLon(grid.nLon()), sinLon(grid.nLon());
    for (size_t i = 0; i < grid.nLon(); ++i)
        cosLon[i] = std::cos(grid.lonDeg[i] * kRadPerDeg), sinLon[i] = std::sin(grid.lonDeg[i] * kRadPerDeg);
    std::mutex countMutex;
    ResampleCounts total;
    total.points = grid.cellCount();
    tbb::parallel_for(size_t(0), grid.nLat(), [&](size_t row) {
        const ResampleCounts local = resampleRow(row, mesh, grid, byRow, sources, arrays, cosLon, sinLon, out);
        std::lock_guard lock(countMutex);
        total.inside += local.inside, total.snapped += local.snapped, total.missing += local.missing;
        total.outside += local.outside;
    });
    spdlog::debug("{}: {} candidate boxes in {:.2f} s ({} cell rows), points located in {:.2f} s", what,
                  byRow.cells.size(), boxSeconds, byRow.rowCells.size(), secondsSince(start) - boxSeconds);
    if (counts)
        *counts = total;
    return out;
}

}  // namespace raypc::io
