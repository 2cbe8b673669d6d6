// The resampling of ASPECT-layout meshes onto the spherical grid (mesh_resample.h, series_input.h)
// against the analytic truth of the deal.II-written series in tests/data/aspect-layout: an adaptive
// mesh of hexahedra with hanging nodes in three pieces, and Lagrange hexahedra of degree 2. ResampleErrors
// are measured at every grid point, and separately at the poles' rows, the lon seam and the inner
// and outer shells.
#include "io/mesh_resample.h"
#include "io/series_input.h"

#include "core/atomic_file.h"
#include "core/error.h"
#include "core/spherical.h"

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <functional>
#include <set>

#include <unistd.h>

namespace raypc::io {
namespace {

namespace fs = std::filesystem;

fs::path aspectSetDir(const std::string& set) { return fs::path(RAYPC_SOURCE_DIR) / "tests/data/aspect-layout" / set; }

// The analytic fields of truth.json: Gaussian blobs of temperature moving with a solid-body
// rotation (omega about z) and a uniform outward flow (u0).
struct ShellTruth {
    explicit ShellTruth(const fs::path& file)
    {
        const auto j = nlohmann::json::parse(readFile(file));
        omega = j.at("omega_rad_per_year");
        u0 = j.at("u0_m_per_year");
        for (const auto& b : j.at("blobs_lat_lon_rkm_amp_sigma"))
            blobs.push_back({b[0], b[1], b[2], b[3], b[4]});
    }
    // blob_sum_K at a point (km) at time t (years).
    double blobSum(const double p[3], double years) const
    {
        double sum = 0;
        for (const auto& b : blobs) {
            const double lat = b[0] * M_PI / 180, lon = (b[1] * M_PI / 180) + omega * years, r = b[2] + u0 * years / 1000;
            const double c[3] = {r * std::cos(lat) * std::cos(lon), r * std::cos(lat) * std::sin(lon), r * std::sin(lat)};
            const double d2 = (p[0] - c[0]) * (p[0] - c[0]) + (p[1] - c[1]) * (p[1] - c[1]) + (p[2] - c[2]) * (p[2] - c[2]);
            sum += b[3] * std::exp(-d2 / (2 * b[4] * b[4]));
        }
        return sum;
    }
    double temperature(const double p[3], double years) const
    {
        const double r = std::sqrt(p[0] * p[0] + p[1] * p[1] + p[2] * p[2]);
        return 1600 + 2000 * (6371 - r) / 2886 + blobSum(p, years);
    }
    double omega = 0, u0 = 0;
    std::vector<std::array<double, 5>> blobs;
};

// Absolute errors of a field at the grid's points, with the median and maximum of chosen subsets.
struct ResampleErrors {
    std::vector<double> all, poles, seam, boundaries;
    static double median(std::vector<double> v)
    {
        std::nth_element(v.begin(), v.begin() + ptrdiff_t(v.size() / 2), v.end());
        return v[v.size() / 2];
    }
    static double max(const std::vector<double>& v) { return *std::max_element(v.begin(), v.end()); }
};

// T and the velocity of `snap` (step at `years`) against the truth at every grid point.
void compareWithTruth(const grid::Snapshot& snap, const ShellTruth& truth, double years, ResampleErrors& t, double& worstVelocityMps)
{
    const grid::SphericalGrid& g = snap.grid;
    const grid::Field* T = snap.find("T");
    const grid::Field* v[3] = {snap.find("vx"), snap.find("vy"), snap.find("vz")};
    ASSERT_TRUE(T && v[0] && v[1] && v[2]);
    EXPECT_EQ(T->units, "K");
    EXPECT_EQ(v[0]->units, "m/s");
    constexpr double kSecondsPerYear = 365.25 * 86400;
    for (size_t iLat = 0; iLat < g.nLat(); ++iLat)
        for (size_t iR = 0; iR < g.nR(); ++iR)
            for (size_t iLon = 0; iLon < g.nLon(); ++iLon) {
                const double lat = degToRad(g.latDeg[iLat]), lon = degToRad(g.lonDeg[iLon]), r = g.rKm[iR];
                const double p[3] = {r * std::cos(lat) * std::cos(lon), r * std::cos(lat) * std::sin(lon), r * std::sin(lat)};
                const size_t i = g.index(iLat, iR, iLon);
                const double e = std::abs(T->values[i] - truth.temperature(p, years));
                t.all.push_back(e);
                if (iLat == 0 || iLat + 1 == g.nLat())
                    t.poles.push_back(e);
                if (iLon == 0 || iLon + 1 == g.nLon())
                    t.seam.push_back(e);
                if (iR == 0 || iR + 1 == g.nR())
                    t.boundaries.push_back(e);
                // omega (-y, x, 0) + u0 p / |p| in m/year, the dataset's in m/s.
                const double expected[3] = {-truth.omega * p[1] * 1e3 + truth.u0 * p[0] / r,
                                            truth.omega * p[0] * 1e3 + truth.u0 * p[1] / r, truth.u0 * p[2] / r};
                for (int c = 0; c < 3; ++c)
                    worstVelocityMps = std::max(worstVelocityMps,
                                                std::abs(v[c]->values[i] - expected[c] / kSecondsPerYear));
            }
}

// Point array "f" of a piece of one cell (km × 1e3, as metres), resampled onto a 180x12x360 grid over
// the cell's radii (returned in `grid`).
std::vector<std::vector<float>> resampleOneCell(vtk::Piece piece, grid::SphericalGrid& grid, ResampleCounts& counts)
{
    std::vector<vtk::Piece> pieces;
    pieces.push_back(std::move(piece));
    const ShellMesh mesh = makeShellMesh(std::move(pieces), 1e-3, "one cell");
    grid = resampleGrid(mesh, 180, 12, 360);
    return resampleOntoGrid(mesh, grid, {{"f", -1}}, "one cell", &counts);
}

TEST(LagrangeHex, VtkNumberingIsABijectionWithTheVerticesFirst)
{
    for (int p = 1; p <= 5; ++p) {
        std::set<int> seen;
        for (int k = 0; k <= p; ++k)
            for (int j = 0; j <= p; ++j)
                for (int i = 0; i <= p; ++i)
                    seen.insert(lagrangeHexPointIndex(i, j, k, p));
        EXPECT_EQ(seen.size(), size_t((p + 1) * (p + 1) * (p + 1))) << "degree " << p;
        EXPECT_EQ(*seen.begin(), 0);
        EXPECT_EQ(*seen.rbegin(), (p + 1) * (p + 1) * (p + 1) - 1);
    }
    // The vertices in the linear hexahedron's order: (0,0,0) (1,0,0) (1,1,0) (0,1,0), then z = 1.
    EXPECT_EQ(lagrangeHexPointIndex(0, 0, 0, 2), 0);
    EXPECT_EQ(lagrangeHexPointIndex(2, 0, 0, 2), 1);
    EXPECT_EQ(lagrangeHexPointIndex(2, 2, 0, 2), 2);
    EXPECT_EQ(lagrangeHexPointIndex(0, 2, 0, 2), 3);
    EXPECT_EQ(lagrangeHexPointIndex(0, 2, 2, 2), 7);
    EXPECT_EQ(lagrangeHexPointIndex(1, 1, 1, 2), 26);  // the one interior point is last
}

// Every step of both deal.II series, at the default grid (as fine as the finest cell): T within
// a few kelvin of the truth (the blobs' curvature over a cell, and float32 values), everywhere
// including the poles' rows, the seam and the boundary shells; no grid point left out.
TEST(Resample, DealIiSeriesMatchTheTruthEverywhere)
{
    struct Case {
        std::string set;
        double medianK, maxK;
    };
    // The errors are the meshes' own: the fields are interpolated at the nodes and linear (AMR:
    // patch cells up to 2.8° by 360 km) or quadratic (Lagrange: cells of 11.25°) between them, for
    // blobs of 500-650 km width; measured 2.3 K median, 25.7 K at most (AMR), 0.03 K and 65.4 K
    // (Lagrange). The velocity is linear in position, which both cell kinds reproduce exactly.
    for (const Case& c : {Case{"shell-amr", 3.0, 32.0}, Case{"shell-lagrange", 0.1, 80.0}}) {
        SCOPED_TRACE(c.set);
        const ShellTruth truth(aspectSetDir(c.set) / "truth.json");
        const SeriesListing listing = listSeries({aspectSetDir(c.set)}, {});
        ASSERT_TRUE(listing.vtk);
        ASSERT_EQ(listing.timesMyr.size(), listing.steps.size());
        ReaderOptions options;
        const FileHeader header = readStepHeader(listing.steps.front(), options);
        options.targetGrid = header.grid;
        ResampleErrors t;
        double worstVelocity = 0;
        for (size_t s = 0; s < listing.steps.size(); ++s) {
            EXPECT_DOUBLE_EQ(listing.timesMyr[s], 2.0 * double(s));
            const grid::Snapshot snap = readStep(listing.steps[s], options);
            ASSERT_TRUE(snap.grid.sameAs(header.grid));
            EXPECT_EQ(snap.origin.at("missing").get<size_t>(), 0u);
            // Snapped: points between the nodes of the curved boundary shells (2 of 9 to 34 shells).
            EXPECT_GT(snap.origin.at("inside").get<double>(), 0.8 * snap.grid.cellCount());
            compareWithTruth(snap, truth, listing.timesMyr[s] * 1e6, t, worstVelocity);
        }
        std::printf("%s: grid %zux%zux%zu, T error median %.3f K, max %.3f K; poles %.3f, seam %.3f, "
                    "inner/outer shells %.3f K; velocity max %.3g m/s\n",
                    c.set.c_str(), header.grid.nLat(), header.grid.nR(), header.grid.nLon(), ResampleErrors::median(t.all),
                    ResampleErrors::max(t.all), ResampleErrors::max(t.poles), ResampleErrors::max(t.seam), ResampleErrors::max(t.boundaries),
                    worstVelocity);
        EXPECT_LT(ResampleErrors::median(t.all), c.medianK);
        EXPECT_LT(ResampleErrors::max(t.all), c.maxK);
        // |v| is up to 0.1 m/yr = 3.2e-9 m/s and linear in position: exact inside the cells, off by the
        // flat faces' sag (a few km) at the snapped points of the boundary shells.
        EXPECT_LT(worstVelocity, 3.2e-9 * 0.002);
    }
}

// One Lagrange hexahedron of degree p on a regular lattice (an affine map), its points in VTK's
// order, carrying f = x² + y z - 3 x z (km², quadratic, so exactly represented for p ≥ 2): every grid
// point well inside takes f at its position. A wrong point order makes the map non-affine and the
// values wrong.
TEST(Resample, LagrangeCellsReproduceTheirPolynomialsExactly)
{
    for (int p : {2, 3}) {
        SCOPED_TRACE(p);
        vtk::Piece piece;
        const int n = (p + 1) * (p + 1) * (p + 1);
        piece.points.resize(3 * size_t(n));
        vtk::PointArray f{"f", 1, std::vector<float>(size_t(n))};
        const double origin[3] = {5000, -300, -300}, size[3] = {600, 600, 600};  // km
        const auto fOf = [](double x, double y, double z) { return x * x / 1e3 + y * z / 1e3 - 3 * x * z / 1e3; };
        for (int k = 0; k <= p; ++k)
            for (int j = 0; j <= p; ++j)
                for (int i = 0; i <= p; ++i) {
                    const size_t a = size_t(lagrangeHexPointIndex(i, j, k, p));
                    const double x = origin[0] + size[0] * i / p, y = origin[1] + size[1] * j / p,
                                 z = origin[2] + size[2] * k / p;
                    piece.points[3 * a] = x * 1e3, piece.points[3 * a + 1] = y * 1e3, piece.points[3 * a + 2] = z * 1e3;
                    f.values[a] = float(fOf(x, y, z));
                }
        for (int a = 0; a < n; ++a)
            piece.connectivity.push_back(a);
        piece.offsets.push_back(n);
        piece.types.push_back(vtk::CellType::LagrangeHexahedron);
        piece.pointData.push_back(f);
        grid::SphericalGrid grid;
        ResampleCounts counts;
        const auto values = resampleOneCell(std::move(piece), grid, counts);
        size_t checked = 0;
        double worst = 0;
        for (size_t iLat = 0; iLat < grid.nLat(); ++iLat)
            for (size_t iR = 0; iR < grid.nR(); ++iR)
                for (size_t iLon = 0; iLon < grid.nLon(); ++iLon) {
                    const double lat = degToRad(grid.latDeg[iLat]), lon = degToRad(grid.lonDeg[iLon]), r = grid.rKm[iR];
                    const double x = r * std::cos(lat) * std::cos(lon), y = r * std::cos(lat) * std::sin(lon),
                                 z = r * std::sin(lat);
                    const bool inside = x > origin[0] + 1 && x < origin[0] + size[0] - 1 && std::abs(y) < 299 &&
                                        std::abs(z) < 299;
                    const float v = values[0][grid.index(iLat, iR, iLon)];
                    if (!inside)
                        continue;
                    ++checked;
                    worst = std::max(worst, std::abs(v - fOf(x, y, z)) / 1e3);
                }
        EXPECT_GT(checked, 50u);
        // Inside: those checked, and the few within 1 km of a face that the check leaves out.
        EXPECT_GE(counts.inside, checked);
        EXPECT_LT(counts.inside, checked + checked / 10);
        EXPECT_LT(worst, 1e-4) << "relative to |f| ~ 1e3 km²";
    }
}

// A tetrahedron and a wedge (VTK types 10 and 13, which ASPECT does not write but other deal.II
// and VTK writers do) carrying a linear field f = 2x - y + 3z (km): every grid point inside takes f
// exactly (the points snapped to their faces from outside take it at the face).
TEST(Resample, TetrahedraAndWedgesReproduceLinearFieldsExactly)
{
    const auto fOf = [](double x, double y, double z) { return 2 * x - y + 3 * z; };
    const std::vector<std::array<double, 3>> tet = {{5000, -300, -300}, {5600, -300, -300}, {5000, 300, -300}, {5000, -300, 300}};
    const std::vector<std::array<double, 3>> wedge = {{5000, -300, -300}, {5600, -300, -300}, {5000, 300, -300},
                                                      {5000, -300, 300},  {5600, -300, 300},  {5000, 300, 300}};
    for (const auto& [type, nodes] : {std::pair{vtk::CellType::Tetra, tet}, std::pair{vtk::CellType::Wedge, wedge}}) {
        SCOPED_TRACE(int(type));
        vtk::Piece piece;
        vtk::PointArray f{"f", 1, {}};
        for (size_t n = 0; n < nodes.size(); ++n) {
            for (int a = 0; a < 3; ++a)
                piece.points.push_back(nodes[n][size_t(a)] * 1e3);
            f.values.push_back(float(fOf(nodes[n][0], nodes[n][1], nodes[n][2])));
            piece.connectivity.push_back(int64_t(n));
        }
        piece.offsets.push_back(int64_t(nodes.size()));
        piece.types.push_back(type);
        piece.pointData.push_back(f);
        grid::SphericalGrid grid;
        ResampleCounts counts;
        const auto values = resampleOneCell(std::move(piece), grid, counts);
        size_t exact = 0;
        for (size_t iLat = 0; iLat < grid.nLat(); ++iLat)
            for (size_t iR = 0; iR < grid.nR(); ++iR)
                for (size_t iLon = 0; iLon < grid.nLon(); ++iLon) {
                    const float v = values[0][grid.index(iLat, iR, iLon)];
                    if (std::isnan(v))
                        continue;
                    const double lat = degToRad(grid.latDeg[iLat]), lon = degToRad(grid.lonDeg[iLon]), r = grid.rKm[iR];
                    const double expected = fOf(r * std::cos(lat) * std::cos(lon), r * std::cos(lat) * std::sin(lon),
                                                r * std::sin(lat));
                    exact += std::abs(v - expected) < 1e-6 * 1e4;
                }
        EXPECT_GT(counts.inside, 20u);
        EXPECT_GE(exact, counts.inside) << "a point inside the cell took another value than f";
    }
}

// A grid chosen by --grid: any sizes; a coarse one samples the same fields.
TEST(Resample, AChosenGridIsUsed)
{
    ReaderOptions options;
    options.resampleSize = {18, 5, 36};
    const SeriesListing listing = listSeries({aspectSetDir("shell-amr") / "solution.pvd"}, options);
    const FileHeader header = readStepHeader(listing.steps.front(), options);
    EXPECT_EQ(header.grid.nLat(), 18u);
    EXPECT_EQ(header.grid.nR(), 5u);
    EXPECT_EQ(header.grid.nLon(), 36u);
    EXPECT_NEAR(header.grid.rKm.front(), 3485, 1e-3);
    EXPECT_NEAR(header.grid.rKm.back(), 6371, 1e-3);
    EXPECT_DOUBLE_EQ(header.grid.latDeg.front(), -85);
    EXPECT_DOUBLE_EQ(header.grid.lonDeg.front(), 0);
    EXPECT_NO_THROW(header.grid.validate("the chosen grid"));
}

std::string resampleErrorOf(const std::function<void()>& f)
{
    try {
        f();
    } catch (const Error& e) {
        return e.what();
    }
    return "(no error)";
}

// Bad series: one line naming the file and what is wrong.
TEST(Resample, BadSeriesAreOneClearError)
{
    const fs::path dir = fs::temp_directory_path() / ("raypc-resample-test-" + std::to_string(::getpid()));
    fs::create_directories(dir);
    writeFileAtomic(dir / "missing.pvd",
                        "<VTKFile type=\"Collection\"><Collection><DataSet timestep=\"0\" file=\"nowhere.pvtu\"/>"
                        "</Collection></VTKFile>");
    EXPECT_NE(resampleErrorOf([&] { listSeries({dir / "missing.pvd"}, {}); }).find("names " + (dir / "nowhere.pvtu").string() + ", which does not exist"),
              std::string::npos);
    // A mesh that is not a mantle shell (a unit cube in metres, a non-dimensional model).
    writeFileAtomic(dir / "cube.vtu", R"(<VTKFile type="UnstructuredGrid" version="1.0" byte_order="LittleEndian">
<UnstructuredGrid><Piece NumberOfPoints="8" NumberOfCells="1"><PointData><DataArray type="Float32" Name="T" format="ascii">1 2 3 4 5 6 7 8</DataArray></PointData>
<Points><DataArray type="Float32" NumberOfComponents="3" format="ascii">0 0 0 1 0 0 1 1 0 0 1 0 0 0 1 1 0 1 1 1 1 0 1 1</DataArray></Points>
<Cells><DataArray type="Int32" Name="connectivity" format="ascii">0 1 2 3 4 5 6 7</DataArray>
<DataArray type="Int32" Name="offsets" format="ascii">8</DataArray><DataArray type="UInt8" Name="types" format="ascii">12</DataArray></Cells>
</Piece></UnstructuredGrid></VTKFile>)");
    const std::string cube = resampleErrorOf([&] { readStepHeader(dir / "cube.vtu", {}); });
    EXPECT_NE(cube.find("cube.vtu: the mesh's points lie at radii 0 to 0.00173205 km"), std::string::npos) << cube;
    EXPECT_NE(cube.find("not a mantle shell"), std::string::npos) << cube;
    // netCDF and VTK inputs together.
    const std::string mixed = resampleErrorOf([&] { listSeries({dir / "cube.vtu", dir / "a.nc"}, {}); });
    EXPECT_NE(mixed.find("cannot make one series"), std::string::npos) << mixed;
    fs::remove_all(dir);
}

}  // namespace
}  // namespace raypc::io
