#include "analysis/pathline_export.h"
#include "analysis/pathline_storage.h"
#include "analysis/pathlines.h"
#include "analysis/persistence.h"

#include "core/atomic_file.h"
#include "core/error.h"
#include "core/spherical.h"
#include "preprocess/preprocess.h"
#include "grid/test_util.h"

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include <cmath>
#include <fstream>
#include <functional>
#include <sstream>

namespace raypc::analysis {
namespace {

using testing::centredGrid;
using testing::TempDir;


// Velocity fields (m/s, Cartesian) of several steps from a function of (step, position in km),
// plus a fourth variable: the radius in km (to check attribute sampling).
struct Series {
    std::vector<std::vector<float>> storage;
    FieldSeries series;

    Series(const grid::SphericalGrid& g, std::vector<double> times, const std::function<Vec3d(size_t, const Vec3d&)>& v)
    {
        series.grid = g;
        series.timesMyr = times;
        storage.reserve(4 * times.size());
        for (size_t k = 0; k < times.size(); ++k) {
            std::vector<float> c[4];
            for (auto& x : c)
                x.resize(g.cellCount());
            for (size_t a = 0; a < g.nLat(); ++a)
                for (size_t b = 0; b < g.nR(); ++b)
                    for (size_t n = 0; n < g.nLon(); ++n) {
                        const Vec3d p = sphericalToCartesianKm(g.latDeg[a], g.lonDeg[n], g.rKm[b]);
                        const Vec3d u = v(k, p);
                        const size_t i = g.index(a, b, n);
                        c[0][i] = float(u.x), c[1][i] = float(u.y), c[2][i] = float(u.z), c[3][i] = float(g.rKm[b]);
                    }
            std::vector<const float*> ptrs;
            for (auto& x : c)
                ptrs.push_back(storage.emplace_back(std::move(x)).data());
            series.fields.push_back(ptrs);
        }
    }
};

double radiusOf(const Vec3d& p) { return std::sqrt(p.x * p.x + p.y * p.y + p.z * p.z); }

// Solid-body rotation about z whose rate changes from step to step, plus a uniform outward speed:
// a particle keeps its latitude, turns by the integral of the (piecewise linear in time) rate and
// rises by u0 t. It crosses the lon seam on the way.
TEST(Tracer, RotationWithTimeVaryingRateAndRadialRise)
{
    const grid::SphericalGrid g = centredGrid(36, 41, 72);
    const double omega0 = 1e-15;  // rad/s: 1.8°/Myr
    const double u0 = 5e-10;      // m/s: 15.8 km/Myr
    const std::vector<double> times = {0, 2, 4, 6};
    auto omega = [&](size_t k) { return omega0 * (1 + 0.5 * k); };
    Series s(g, times, [&](size_t k, const Vec3d& p) {
        const double r = radiusOf(p);
        return Vec3d{-omega(k) * p.y * 1000 + u0 * p.x / r, omega(k) * p.x * 1000 + u0 * p.y / r, u0 * p.z / r};
    });
    const PathlineTracer tracer(s.series, 0, 1, 2);
    const double lat0 = 32, lon0 = 350, r0 = 4400;
    const auto line = tracer.trace(sphericalToCartesianKm(lat0, lon0, r0), 0, 6);
    EXPECT_EQ(line.end, PathlineEnd::ReachedEndTime);
    ASSERT_GE(line.pointsKm.size(), 13u);  // at most 0.5 Myr apart
    for (double t : times)  // every step time is a point
        EXPECT_NE(std::find(line.timesMyr.begin(), line.timesMyr.end(), t), line.timesMyr.end()) << t;
    for (size_t i = 0; i < line.pointsKm.size(); ++i) {
        const double t = line.timesMyr[i];
        // ∫ω dt with ω linear between steps (trapezoids), in rad.
        double angle = 0;
        for (size_t k = 0; k + 1 < times.size(); ++k) {
            const double a = times[k], b = std::min(times[k + 1], t);
            if (b <= a)
                break;
            const double wa = omega(k), wb = omega(k) + (omega(k + 1) - omega(k)) * (b - a) / (times[k + 1] - a);
            angle += 0.5 * (wa + wb) * (b - a) * kSecondsPerMyr;
        }
        const SphericalPoint q = cartesianToSpherical(line.pointsKm[i]);
        // A small fraction of a cell (5°, 72 km): the trilinear interpolation of the rotation is
        // not exact between grid points (relative error ~ (5°)²/8 of the speed).
        EXPECT_NEAR(q.latDeg, lat0, 0.01) << t;
        EXPECT_LT(lonSeparationDeg(q.lonDeg, lon0 + radToDeg(angle)), 0.02) << t;
        EXPECT_NEAR(q.rKm, r0 + u0 * kMpsToKmPerMyr * t, 0.2) << t;
    }
    EXPECT_LT(cartesianToSpherical(line.pointsKm.back()).lonDeg, 90.0);  // crossed the seam
    // The polyline length: mostly the arc along the latitude circle (mean radius, total angle).
    const double totalAngle = (omega(0) + 2 * omega(1) + 2 * omega(2) + omega(3)) / 2 * 2 * kSecondsPerMyr;
    const double meanR = r0 + u0 * kMpsToKmPerMyr * 3;
    EXPECT_NEAR(line.lengthKm, meanR * std::cos(degToRad(lat0)) * totalAngle, 0.005 * line.lengthKm);
    // Attributes are sampled in space and time: variable 3 is the radius.
    EXPECT_NEAR(tracer.sample(3, line.pointsKm.back(), 6), cartesianToSpherical(line.pointsKm.back()).rKm, 1e-2);
}

// A strong outward flow carries the particle through the surface: the line ends on the boundary
// at the analytic exit time. The particle rises along a column of grid points, where the
// interpolated radial flow is exact.
TEST(Tracer, StopsWhereTheLineLeavesTheShell)
{
    const grid::SphericalGrid g = centredGrid(18, 21, 36);
    const double u0 = 1e-8;  // m/s: 315.6 km/Myr
    Series s(g, {0, 2, 4, 6, 8, 10}, [&](size_t, const Vec3d& p) {
        const double r = radiusOf(p);
        return Vec3d{u0 * p.x / r, u0 * p.y / r, u0 * p.z / r};
    });
    const PathlineTracer tracer(s.series, 0, 1, 2);
    const double r0 = 4000;
    const auto line = tracer.trace(sphericalToCartesianKm(-25, 120, r0), 0, 10);
    EXPECT_EQ(line.end, PathlineEnd::LeftShell);
    const double exitMyr = (kSurfaceRadiusKm - r0) / (u0 * kMpsToKmPerMyr);
    EXPECT_NEAR(line.timesMyr.back(), exitMyr, 1e-4);
    EXPECT_NEAR(radiusOf(line.pointsKm.back()), kSurfaceRadiusKm, 0.05);
    EXPECT_NEAR(line.lengthKm, kSurfaceRadiusKm - r0, 0.05);
    // Inward: ends on the core-mantle boundary.
    Series in(g, {0, 10}, [&](size_t, const Vec3d& p) {
        const double r = radiusOf(p);
        return Vec3d{-u0 * p.x / r, -u0 * p.y / r, -u0 * p.z / r};
    });
    const PathlineTracer down(in.series, 0, 1, 2);
    const auto sink = down.trace(sphericalToCartesianKm(5, 0, 4000), 0, 10);
    EXPECT_EQ(sink.end, PathlineEnd::LeftShell);
    EXPECT_NEAR(radiusOf(sink.pointsKm.back()), kCoreRadiusKm, 0.05);
    EXPECT_NEAR(sink.timesMyr.back(), (4000 - kCoreRadiusKm) / (u0 * kMpsToKmPerMyr), 1e-4);
}

// Rotation about the x axis carries a particle over the north pole: Cartesian integration has no
// singularity there, and the sampler's pole cap (blend toward the ring mean) keeps the velocity
// close to the true one.
TEST(Tracer, CrossesThePole)
{
    const grid::SphericalGrid g = centredGrid(36, 41, 72);
    const double omega = 2e-15;  // rad/s: 3.6°/Myr
    Series s(g, {0, 10, 20, 30, 40}, [&](size_t, const Vec3d& p) { return Vec3d{0, -omega * p.z * 1000, omega * p.y * 1000}; });
    const PathlineTracer tracer(s.series, 0, 1, 2);
    const double r = 5000;
    const auto line = tracer.trace({0, r, 0}, 0, 40);  // lat 0, lon 90, moving north
    ASSERT_EQ(line.end, PathlineEnd::ReachedEndTime);
    double maxLat = -90;
    for (size_t i = 0; i < line.pointsKm.size(); ++i) {
        const double angle = omega * line.timesMyr[i] * kSecondsPerMyr;
        const Vec3d want{0, r * std::cos(angle), r * std::sin(angle)};
        const Vec3d& p = line.pointsKm[i];
        const double err = std::sqrt((p.x - want.x) * (p.x - want.x) + (p.y - want.y) * (p.y - want.y) +
                                     (p.z - want.z) * (p.z - want.z));
        EXPECT_LT(err, 10.0) << line.timesMyr[i];  // a cell is 436 km wide at 5000 km
        maxLat = std::max(maxLat, cartesianToSpherical(p).latDeg);
    }
    EXPECT_GT(maxLat, 89.0);
}

PathlineSet smallSet()
{
    const grid::SphericalGrid g = centredGrid(18, 21, 36);
    static Series s(g, {0, 2, 4}, [](size_t, const Vec3d& p) {
        const double r = radiusOf(p);
        return Vec3d{-1e-15 * p.y * 1000 + 1e-9 * p.x / r, 1e-15 * p.x * 1000 + 1e-9 * p.y / r, 1e-9 * p.z / r};
    });
    const PathlineTracer tracer(s.series, 0, 1, 2);
    std::vector<CriticalPoint> seeds(3);
    seeds[0] = {g.index(3, 5, 7), CriticalKind::Maximum, 2.0f, 1, 0, g.latDeg[3], g.lonDeg[7], g.rKm[5]};
    seeds[1] = {g.index(9, 20, 0), CriticalKind::Minimum, -1.0f, 0, 1, g.latDeg[9], g.lonDeg[0], g.rKm[20]};
    seeds[2] = {g.index(17, 10, 35), CriticalKind::Saddle1, 0.5f, 2, 1, g.latDeg[17], g.lonDeg[35], g.rKm[10]};
    auto set = tracePathlines(s.series, tracer, seeds, 0, 2, {"vx", "vy", "vz", "r"}, {"m/s", "m/s", "m/s", "km"});
    set.seedField = "r";
    set.settingsJson = R"({"a":1})";
    return set;
}

TEST(PathlineSet, AttributesAndRoundTrip)
{
    const PathlineSet set = smallSet();
    ASSERT_EQ(set.lineCount(), 3u);
    ASSERT_EQ(set.columns.size(), kPathlineFixedColumnCount + 8);
    EXPECT_EQ(set.columns[set.column("start r")], "start r");
    // The seed on the surface leaves at once (outward flow): one point, end reason 1.
    EXPECT_EQ(set.offsets[2] - set.offsets[1], 1u);
    EXPECT_EQ(set.attribute(1, set.column("end reason")), 1.0f);
    EXPECT_EQ(set.attribute(0, set.column("end reason")), 0.0f);
    EXPECT_EQ(set.attribute(0, set.column("seed kind")), 3.0f);
    EXPECT_EQ(set.attribute(2, set.column("seed value")), 0.5f);
    EXPECT_FLOAT_EQ(set.attribute(0, set.column("duration")), 4.0f);
    EXPECT_NEAR(set.attribute(0, set.column("start r")), set.attribute(0, set.column("start radius")), 1e-3);
    EXPECT_NEAR(set.attribute(0, set.column("end r")), set.attribute(0, set.column("end radius")), 1e-2);
    EXPECT_NEAR(set.attribute(0, set.column("end radius")) - set.attribute(0, set.column("start radius")),
                4 * 1e-9 * kMpsToKmPerMyr, 0.3);  // interpolated radial flow is ~0.1 % slow between grid points

    TempDir dir("plset");
    writePathlineSet(pathlineDir(dir.path(), 4), set);
    const PathlineSet back = loadPathlineSet(dir.path(), 4);
    EXPECT_EQ(back.offsets, set.offsets);
    EXPECT_EQ(back.points, set.points);
    EXPECT_EQ(back.attributes, set.attributes);
    EXPECT_EQ(back.columns, set.columns);
    EXPECT_EQ(back.units, set.units);
    EXPECT_EQ(back.settingsJson, set.settingsJson);
    EXPECT_EQ(back.seedField, "r");
    EXPECT_THROW(loadPathlineSet(dir.path(), 3), Error);
    // A truncated array is refused.
    std::filesystem::resize_file(pathlineDir(dir.path(), 4) / "points.f32", 12);
    EXPECT_THROW(loadPathlineSet(dir.path(), 4), Error);
}

size_t countTokens(const std::string& text)
{
    std::istringstream in(text);
    std::string t;
    size_t n = 0;
    while (in >> t)
        ++n;
    return n;
}

// The text between the first `<tag ...>` whose attributes contain `attr` and its closing tag.
std::string element(const std::string& doc, const std::string& tag, const std::string& attr)
{
    size_t at = 0;
    while ((at = doc.find("<" + tag, at)) != std::string::npos) {
        const size_t close = doc.find('>', at);
        if (doc.substr(at, close - at).find(attr) != std::string::npos) {
            const size_t end = doc.find("</" + tag + ">", close);
            return doc.substr(close + 1, end - close - 1);
        }
        at = close;
    }
    ADD_FAILURE() << "no <" << tag << "> with " << attr;
    return {};
}

TEST(PathlineExport, VtkXmlStructure)
{
    const PathlineSet set = smallSet();
    TempDir dir("plvtk");
    const std::string vtp = pathlinesVtp(set);
    writeFileAtomic(dir / "lines.vtp", vtp);
    writeFileAtomic(dir / "seeds.vtp", criticalPointsVtp(set));
    // Well-formed XML by an independent parser.
    EXPECT_EQ(testing::run("xmllint --noout '" + (dir / "lines.vtp").string() + "' '" + (dir / "seeds.vtp").string() + "'"), 0);
    const size_t n = set.pointCount();
    EXPECT_NE(vtp.find(fmt::format("NumberOfPoints=\"{}\"", n)), std::string::npos);
    EXPECT_NE(vtp.find("NumberOfLines=\"3\""), std::string::npos);
    EXPECT_EQ(countTokens(element(vtp, "DataArray", "NumberOfComponents=\"3\"")), 3 * n);
    EXPECT_EQ(countTokens(element(vtp, "DataArray", "Name=\"connectivity\"")), n);
    const std::string offsets = element(vtp, "DataArray", "Name=\"offsets\"");
    EXPECT_EQ(countTokens(offsets), 3u);
    EXPECT_EQ(std::stoul(offsets.substr(offsets.find_last_not_of(" \n", offsets.size()) - 2)), n);
    EXPECT_EQ(countTokens(element(vtp, "DataArray", "Name=\"age\"")), n);
    EXPECT_EQ(countTokens(element(vtp, "DataArray", "Name=\"seed kind\"")), 3u);  // cell data
    const std::string seeds = criticalPointsVtp(set);
    EXPECT_NE(seeds.find("NumberOfVerts=\"3\""), std::string::npos);
    EXPECT_EQ(countTokens(element(seeds, "DataArray", "NumberOfComponents=\"3\"")), 9u);

    // Legacy: the declared sizes match the records.
    const std::string vtk = pathlinesLegacyVtk(set);
    EXPECT_EQ(vtk.rfind("# vtk DataFile Version 3.0\n", 0), 0u);
    EXPECT_NE(vtk.find(fmt::format("POINTS {} float\n", n)), std::string::npos);
    EXPECT_NE(vtk.find(fmt::format("LINES 3 {}\n", 3 + n)), std::string::npos);
    EXPECT_NE(vtk.find(fmt::format("FIELD FieldData {}\n", set.columns.size())), std::string::npos);
    EXPECT_NE(vtk.find("start_r 1 3 float"), std::string::npos);
    EXPECT_NE(criticalPointsLegacyVtk(set).find("VERTICES 3 6\n"), std::string::npos);

    // CSV: a header and one row per point / per seed, every row with the header's column count.
    const std::string csv = pathlinesCsv(set);
    EXPECT_EQ(std::count(csv.begin(), csv.end(), '\n'), static_cast<long>(n + 1));
    const size_t columns = 10 + set.columns.size();
    std::istringstream lines(csv);
    std::string row;
    while (std::getline(lines, row))
        ASSERT_EQ(static_cast<size_t>(std::count(row.begin(), row.end(), ',')) + 1, columns) << row;
    const std::string cp = criticalPointsCsv(set);
    EXPECT_EQ(std::count(cp.begin(), cp.end(), '\n'), 4);
    EXPECT_NE(cp.find("\nmaximum,"), std::string::npos);
}

// End to end on the contest fixture: seeds at the blobs, traced through the written steps; the
// flow is solid-body rotation about z plus a uniform outward speed (truth.json), so a particle
// keeps its latitude, turns by omega t and rises by u0 t.
TEST(PathlinePreprocess, ContestFixtureLinesFollowTheAnalyticFlow)
{
    const auto truth = nlohmann::json::parse(std::ifstream(testing::contestLayoutDir() / "truth.json"));
    const double omega = truth["omega_rad_per_s"], u0 = truth["u0_m_per_s"];
    TempDir dir("plpp");
    preprocess::PreprocessOptions o;
    o.quiet = true;
    o.sampleRows = 1000;
    const auto files = io::listSnapshotFiles({testing::contestLayoutDir()});
    const auto summary = preprocess::preprocess(files, dir / "ds", o);
    EXPECT_EQ(summary.pathlineSetsWritten, 3);
    const auto ds = dataset::Dataset::open(dir / "ds");
    const auto window = loadPathlineWindow(ds->dir(), 2);
    ASSERT_EQ(window.size(), 3u);
    EXPECT_EQ(window[0].injectionStep, 0);
    EXPECT_EQ(window[0].endStep, 2);
    EXPECT_EQ(window[2].endStep, 2);
    const PathlineSet& set = window[0];
    EXPECT_EQ(set.columns.size(), kPathlineFixedColumnCount + 2 * ds->variables().size());
    EXPECT_GE(set.lineCount(), 4u);
    EXPECT_LE(set.lineCount(), 200u);
    const int anomaly = ds->variableIndex("temperature anomaly");
    for (size_t i = 0; i < set.lineCount(); ++i) {
        const float* a = &set.points[4 * set.offsets[i]];
        const float* b = &set.points[4 * (set.offsets[i + 1] - 1)];
        const SphericalPoint sa = cartesianToSpherical({a[0], a[1], a[2]});
        const SphericalPoint sb = cartesianToSpherical({b[0], b[1], b[2]});
        const double t = (b[3] - a[3]) * kSecondsPerMyr;
        if (set.attribute(i, set.column("end reason")) != 0)
            continue;  // a seed on the surface leaves at once
        EXPECT_FLOAT_EQ(b[3], 4.0f);
        // A small fraction of a cell (5°, 72 km).
        EXPECT_NEAR(sb.latDeg, sa.latDeg, 0.01) << i;
        EXPECT_LT(lonSeparationDeg(sb.lonDeg, sa.lonDeg + radToDeg(omega * t)), 0.01) << i;
        EXPECT_NEAR(sb.rKm, sa.rKm + u0 * t / 1000, 0.02) << i;
        // The start attributes are the seed's grid values.
        EXPECT_FLOAT_EQ(set.attribute(i, set.column("start temperature anomaly")), set.attribute(i, 1));
        EXPECT_FLOAT_EQ(set.attribute(i, kPathlineFixedColumnCount + anomaly), set.attribute(i, 1));
    }

    // Resume: a finished run redoes nothing; a lost set (or one made with other settings) is redone.
    auto again = preprocess::preprocess(files, dir / "ds", o);
    EXPECT_EQ(again.pathlineSetsSkipped, 3);
    EXPECT_EQ(again.pathlineSetsWritten, 0);
    std::filesystem::remove_all(pathlineDir(dir / "ds", 1));
    std::filesystem::create_directories(dir / "ds" / "pathlines" / ".0001.tmp-9-9");
    again = preprocess::preprocess(files, dir / "ds", o);
    EXPECT_EQ(again.pathlineSetsWritten, 1);
    EXPECT_FALSE(std::filesystem::exists(dir / "ds" / "pathlines" / ".0001.tmp-9-9"));
    o.pathlines.filter.maxCount = 2;
    again = preprocess::preprocess(files, dir / "ds", o);
    EXPECT_EQ(again.pathlineSetsWritten, 3);
    EXPECT_EQ(loadPathlineSet(dir / "ds", 0).lineCount(), 2u);
    // --no-pathlines removes them; the dataset still opens.
    o.pathlines.enabled = false;
    preprocess::preprocess(files, dir / "ds", o);
    EXPECT_FALSE(std::filesystem::exists(dir / "ds" / "pathlines"));
    EXPECT_THROW(loadPathlineSet(dir / "ds", 0), Error);
    EXPECT_NO_THROW(dataset::Dataset::open(dir / "ds"));
    // Bad options are refused before anything is written.
    o.pathlines.enabled = true;
    o.pathlines.field = "no such field";
    EXPECT_THROW(preprocess::preprocess(files, dir / "other", o), Error);
    EXPECT_FALSE(std::filesystem::exists(dir / "other"));
}

// The "seed persistence" column: each line carries the persistence of its seed's pair, as
// persistencePairs finds it on the stored values (the largest pair the seed ends), and on the
// contest fixture, whose four Gaussian blobs are the only features, the seeds at the blobs carry
// the blobs' amplitudes: the 400 K maximum and the -350 K minimum form the global pair (750 K
// apart), the 300 K maximum and the -300 K minimum die at saddles in the near-zero background.
// The amplitudes are those of the grid's sample of each blob (its centre lies between grid
// points) and hold to 4 %: the fixture subtracts each shell's mean (about 1 % of an amplitude).
TEST(PathlinePreprocess, SeedPersistenceIsThePersistenceOfTheSeedsPair)
{
    const auto truth = nlohmann::json::parse(std::ifstream(testing::contestLayoutDir() / "truth.json"));
    TempDir dir("plpersist");
    preprocess::PreprocessOptions o;
    o.quiet = true;
    o.sampleRows = 1000;
    o.pathlines.steps = 1;
    const auto files = io::listSnapshotFiles({testing::contestLayoutDir()});
    preprocess::preprocess(files, dir / "ds", o);
    const auto ds = dataset::Dataset::open(dir / "ds");
    const PathlineSet set = loadPathlineSet(ds->dir(), 0);
    const int column = set.column("seed persistence");
    ASSERT_EQ(column, 2);
    ASSERT_GE(set.lineCount(), 4u);
    const auto volume = ds->load(0, 0);
    const grid::SphericalGrid& g = volume->grid();
    const std::span<const float> values(volume->values(size_t(ds->variableIndex("temperature anomaly"))), g.cellCount());
    const auto pairs = persistencePairs(g, values);
    auto nearestIndex = [&](double latDeg, double lonDeg, double rKm) {
        auto nearest = [](const std::vector<double>& axis, double x) {
            return size_t(std::min_element(axis.begin(), axis.end(), [&](double a, double b) {
                              return std::abs(a - x) < std::abs(b - x);
                          }) - axis.begin());
        };
        const double lon = std::fmod(lonDeg + 360.0, 360.0);
        return g.index(nearest(g.latDeg, latDeg), nearest(g.rKm, rKm), nearest(g.lonDeg, lon));
    };
    std::vector<size_t> seedIndex(set.lineCount());
    for (size_t i = 0; i < set.lineCount(); ++i) {
        seedIndex[i] = nearestIndex(set.attribute(i, set.column("start lat")), set.attribute(i, set.column("start lon")),
                                    set.attribute(i, set.column("start radius")));
        double expected = -1;
        for (const auto& p : pairs)  // by decreasing persistence: the first pair the seed ends
            if (p.birthIndex == seedIndex[i] || p.deathIndex == seedIndex[i]) {
                expected = p.persistence();
                break;
            }
        ASSERT_GE(expected, 0) << "line " << i << ": its seed ends no pair";
        EXPECT_NEAR(set.attribute(i, column), expected, 1e-5 * expected) << i;
        EXPECT_GT(set.attribute(i, column), set.threshold) << i;
    }
    // The blobs: the grid's largest sample of amp exp(-d²/2σ²), at the line seeded nearest each centre.
    std::vector<double> peak;
    std::vector<size_t> line;
    for (const auto& b : truth["blobs_lat_lon_rkm_amp_sigma"]) {
        const double lat = b[0], lon = b[1], r = b[2], amp = b[3], sigma = b[4];
        double factor = 0;
        for (size_t a = 0; a < g.nLat(); ++a)
            for (size_t k = 0; k < g.nR(); ++k)
                for (size_t c = 0; c < g.nLon(); ++c)
                    factor = std::max(factor, testing::gaussianBlob(g, a, k, c, lat, lon, r, sigma));
        peak.push_back(amp * factor);
        const Vec3d centre = sphericalToCartesianKm(lat, lon, r);
        size_t best = 0;
        double bestKm = 1e30;
        for (size_t i = 0; i < set.lineCount(); ++i) {
            const float* q = &set.points[4 * set.offsets[i]];
            const double km = std::hypot(q[0] - centre.x, q[1] - centre.y, q[2] - centre.z);
            if (km < bestKm) {
                bestKm = km;
                best = i;
            }
        }
        EXPECT_LT(bestKm, 400.0) << "no seed near the blob at " << lat << ", " << lon;
        line.push_back(best);
    }
    const double want[] = {peak[0] - peak[2], std::abs(peak[1]), peak[0] - peak[2], std::abs(peak[3])};
    for (size_t k = 0; k < 4; ++k)
        EXPECT_NEAR(set.attribute(line[k], column), want[k], 0.04 * want[k]) << "blob " << k;

    // A set stored before the column (lines.json version 1) reads with the columns it lists, and a
    // rerun of preprocess redoes it (the others stay).
    PathlineSet old = set;
    old.columns.erase(old.columns.begin() + column);
    old.units.erase(old.units.begin() + column);
    old.attributes.clear();
    for (size_t i = 0; i < set.lineCount(); ++i)
        for (size_t c = 0; c < set.columns.size(); ++c)
            if (int(c) != column)
                old.attributes.push_back(set.attribute(i, c));
    const auto dir0 = pathlineDir(dir / "ds", 0);
    std::filesystem::remove_all(dir0);
    writePathlineSet(dir0, old);
    auto lines = nlohmann::json::parse(std::ifstream(dir0 / "lines.json"));
    lines["version"] = 1;
    std::ofstream(dir0 / "lines.json") << lines.dump();
    const PathlineSet read = loadPathlineSet(dir / "ds", 0);
    EXPECT_EQ(read.column("seed persistence"), -1);
    EXPECT_EQ(read.columns.size(), set.columns.size() - 1);
    EXPECT_EQ(read.attribute(1, read.column("length")), set.attribute(1, set.column("length")));
    lines["version"] = kPathlineSetVersion + 1;
    std::ofstream(dir0 / "lines.json") << lines.dump();
    EXPECT_THROW(loadPathlineSet(dir / "ds", 0), Error);
    lines["version"] = 1;
    std::ofstream(dir0 / "lines.json") << lines.dump();
    const auto again = preprocess::preprocess(files, dir / "ds", o);
    EXPECT_EQ(again.pathlineSetsWritten, 1);
    EXPECT_EQ(loadPathlineSet(dir / "ds", 0).column("seed persistence"), column);
}

}  // namespace
}  // namespace raypc::analysis
