#include "preprocess/preprocess.h"

#include "core/atomic_file.h"
#include "core/error.h"
#include "core/spherical.h"
#include "dataset/dataset_format.h"
#include "analysis/pathline_storage.h"
#include "analysis/persistence.h"
#include "io/series_input.h"
#include "synth/synth.h"
#include "grid/test_util.h"

#include <fmt/format.h>
#include <gtest/gtest.h>
#include <tbb/task_arena.h>
#include <sys/resource.h>
#include <unistd.h>
#include <nlohmann/json.hpp>

#include <atomic>
#include <bit>
#include <chrono>
#include <cmath>
#include <limits>
#include <map>
#include <mutex>
#include <numbers>
#include <random>
#include <thread>

namespace raypc::preprocess {
namespace {

using testing::centredGrid;

using testing::contestLayoutDir;
using testing::TempDir;


// Volume of one grid point's dual cell, from first principles (not SphericalGrid's factors).
double dualVolume(const grid::SphericalGrid& g, size_t a, size_t b, size_t c)
{
    auto mid = [](const std::vector<double>& v, size_t i, bool upper, double lo, double hi) {
        if (upper)
            return i + 1 < v.size() ? 0.5 * (v[i] + v[i + 1]) : hi;
        return i > 0 ? 0.5 * (v[i - 1] + v[i]) : lo;
    };
    const double la0 = mid(g.latDeg, a, false, -90, 90), la1 = mid(g.latDeg, a, true, -90, 90);
    const double r0 = mid(g.rKm, b, false, g.rKm.front(), 0), r1 = mid(g.rKm, b, true, 0, g.rKm.back());
    const double dLon = 360.0 / g.nLon();  // uniform lon in these tests
    return (std::sin(degToRad(la1)) - std::sin(degToRad(la0))) * (r1 * r1 * r1 - r0 * r0 * r0) / 3 * degToRad(dLon);
}

std::vector<float> randomValues(const grid::SphericalGrid& grid, unsigned seed, float lo, float hi)
{
    std::mt19937 rng(seed);
    std::uniform_real_distribution<float> u(lo, hi);
    std::vector<float> values(grid.cellCount());
    for (auto& v : values)
        v = u(rng);
    return values;
}

TEST(Lod, CoarseValuesAreVolumeWeightedMeansAtOddSizes)
{
    const grid::SphericalGrid fine = centredGrid(7, 5, 9);
    const std::vector<float> values = randomValues(fine, 3, -1, 1);
    const auto coarse = coarsenField(fine, values);
    const grid::SphericalGrid cg = fine.coarsened();
    ASSERT_EQ(coarse.size(), cg.cellCount());
    for (size_t a = 0; a < cg.nLat(); ++a)
        for (size_t b = 0; b < cg.nR(); ++b)
            for (size_t c = 0; c < cg.nLon(); ++c) {
                double sum = 0, weight = 0;
                for (size_t i = 2 * a; i < std::min(2 * a + 2, fine.nLat()); ++i)
                    for (size_t j = 2 * b; j < std::min(2 * b + 2, fine.nR()); ++j)
                        for (size_t k = 2 * c; k < std::min(2 * c + 2, fine.nLon()); ++k) {
                            const double w = dualVolume(fine, i, j, k);
                            sum += w * values[fine.index(i, j, k)];
                            weight += w;
                        }
                ASSERT_NEAR(coarse[cg.index(a, b, c)], sum / weight, 1e-5) << a << " " << b << " " << c;
            }
    // A constant stays constant, also in the pole rows and the odd last column.
    const auto constant = coarsenField(fine, std::vector<float>(fine.cellCount(), 2.5f));
    for (float v : constant)
        ASSERT_FLOAT_EQ(v, 2.5f);
}

TEST(Stats, VolumeWeightedMeanAndHistogram)
{
    const grid::SphericalGrid g = centredGrid(36, 81, 72);
    std::vector<float> lat(g.cellCount()), r(g.cellCount());
    for (size_t a = 0; a < g.nLat(); ++a)
        for (size_t b = 0; b < g.nR(); ++b)
            for (size_t c = 0; c < g.nLon(); ++c) {
                lat[g.index(a, b, c)] = static_cast<float>(g.latDeg[a]);
                r[g.index(a, b, c)] = static_cast<float>(g.rKm[b]);
            }
    const auto sLat = computeStats(g, lat);
    EXPECT_NEAR(sLat.mean, 0.0, 1e-9);
    double total = 0;
    for (double h : sLat.histogram)
        total += h;
    EXPECT_NEAR(total, 1.0, 1e-12);
    // Volume with lat above 60°: the rows at 62.5..87.5 fill exactly (1 - sin 60°) / 2.
    double north = 0;
    for (int b = 0; b < dataset::kHistogramBins; ++b)
        if (sLat.range.min + (b + 0.5) * (sLat.range.max - sLat.range.min) / dataset::kHistogramBins > 60)
            north += sLat.histogram[b];
    EXPECT_NEAR(north, (1 - std::sin(degToRad(60.0))) / 2, 1e-9);
    // The mean radius of a shell's volume is 3/4 (R⁴ - r⁴) / (R³ - r³), up to the discretisation.
    const double R = kSurfaceRadiusKm, c = kCoreRadiusKm;
    const double expected = 0.75 * (std::pow(R, 4) - std::pow(c, 4)) / (std::pow(R, 3) - std::pow(c, 3));
    EXPECT_NEAR(computeStats(g, r).mean, expected, 2.0);
    EXPECT_FLOAT_EQ(computeStats(g, r).range.min, 3485.0f);
}

// The sample must show volume fractions: as many samples above the radius that halves the
// shell's volume as below, and 13.4 % beyond ±60° latitude; an index-uniform sample gives
// other fractions, which the tolerance rejects.
TEST(Sample, DrawsGridPointsInProportionToVolume)
{
    const grid::SphericalGrid g = centredGrid(36, 41, 72);
    const size_t n = 100000;
    const auto cells = drawVolumeWeightedSample(g, n, 42);
    ASSERT_EQ(cells.size(), n);
    ASSERT_TRUE(std::is_sorted(cells.begin(), cells.end()));
    // Exact volume fraction of the dual cells above r = 5200 km and poleward of 60°.
    double above = 0, polar = 0, total = 0;
    for (size_t a = 0; a < g.nLat(); ++a)
        for (size_t b = 0; b < g.nR(); ++b) {
            const double v = dualVolume(g, a, b, 0);
            total += v;
            above += g.rKm[b] > 5200 ? v : 0;
            polar += std::abs(g.latDeg[a]) > 60 ? v : 0;
        }
    above /= total;
    polar /= total;
    size_t nAbove = 0, nPolar = 0, gridAbove = 0;
    for (uint32_t c : cells) {
        const size_t b = (c / g.nLon()) % g.nR(), a = c / (g.nLon() * g.nR());
        nAbove += g.rKm[b] > 5200;
        nPolar += std::abs(g.latDeg[a]) > 60;
    }
    for (double r : g.rKm)
        gridAbove += r > 5200;
    const double sigma = std::sqrt(0.25 / n);
    EXPECT_NEAR(double(nAbove) / n, above, 5 * sigma);
    EXPECT_NEAR(double(nPolar) / n, polar, 5 * sigma);
    EXPECT_NEAR(polar, 1 - std::sin(degToRad(60.0)), 1e-9);
    // Sanity of the test itself: counting grid points would be far off.
    EXPECT_GT(std::abs(double(gridAbove) / g.nR() - above), 20 * sigma);
    EXPECT_EQ(drawVolumeWeightedSample(g, 1000, 42), drawVolumeWeightedSample(g, 1000, 42));
    EXPECT_NE(drawVolumeWeightedSample(g, 1000, 42), drawVolumeWeightedSample(g, 1000, 43));
}

TEST(Rebin, KeepsMassAndPlacesIt)
{
    dataset::VariableStats s;
    s.range = {0, 10};
    s.histogram.assign(10, 0.0);
    s.histogram[2] = 0.5;  // [2, 3)
    s.histogram[9] = 0.5;  // [9, 10]
    std::vector<double> out(5, 0.0);  // over [0, 20): bins of 4
    rebinHistogram(s, {0, 20}, out);
    EXPECT_NEAR(out[0], 0.5, 1e-12);
    EXPECT_NEAR(out[2], 0.5, 1e-12);  // [8, 12) holds [9, 10]
    std::vector<double> split(2, 0.0);
    s.histogram.assign(10, 0.0);
    s.histogram[4] = 1.0;  // [4, 5) over two output bins [0, 4.5) and [4.5, 9)
    rebinHistogram(s, {0, 9}, split);
    EXPECT_NEAR(split[0], 0.5, 1e-12);
    EXPECT_NEAR(split[1], 0.5, 1e-12);
}

std::vector<std::filesystem::path> fixtureFiles()
{
    return io::listSnapshotFiles({contestLayoutDir()});
}

PreprocessOptions quiet()
{
    PreprocessOptions o;
    o.quiet = true;
    o.sampleRows = 5000;
    return o;
}

// Float32's extremes in one field: the histogram's bin arithmetic overflowed float (the
// difference of the two is beyond float32) and indexed the histogram at INT_MIN.
TEST(Stats, FiniteExtremesOfFloat32)
{
    const grid::SphericalGrid g = centredGrid(6, 5, 8);
    std::vector<float> values(g.cellCount(), 0.0f);
    values.front() = -3.4e38f;
    values.back() = 3.4e38f;
    const auto s = computeStats(g, values);
    EXPECT_EQ(s.range.min, -3.4e38f);
    EXPECT_EQ(s.range.max, 3.4e38f);
    double total = 0;
    for (double h : s.histogram)
        total += h;
    EXPECT_NEAR(total, 1.0, 1e-12);
    EXPECT_GT(s.histogram.front(), 0);
    EXPECT_GT(s.histogram.back(), 0);
    EXPECT_GT(s.histogram[dataset::kHistogramBins / 2 - 1] + s.histogram[dataset::kHistogramBins / 2], 0.9);  // the zeros, mid-range
}

// The statistics must not depend on how many threads share the work: dataset.json is the same
// bytes on every run. Thread-local partial sums gave other last digits.
TEST(Stats, SameBitsWithAnyNumberOfThreads)
{
    const grid::SphericalGrid g = centredGrid(90, 41, 180);
    const std::vector<float> values = randomValues(g, 7, -1000, 3000);
    dataset::VariableStats reference;
    tbb::task_arena(1).execute([&] { reference = computeStats(g, values); });
    for (int threads : {2, 3, 4, 8})
        for (int repeat = 0; repeat < 3; ++repeat) {
            dataset::VariableStats s;
            tbb::task_arena(threads).execute([&] { s = computeStats(g, values); });
            ASSERT_EQ(std::bit_cast<uint64_t>(s.mean), std::bit_cast<uint64_t>(reference.mean)) << threads;
            ASSERT_EQ(s.histogram, reference.histogram) << threads;
        }
}

TEST(Derived, ValuesBeyondFloat32BecomeInfiniteAndAreRefusedWithTheirPlace)
{
    EXPECT_EQ(toFloat32(1e39), std::numeric_limits<float>::infinity());
    EXPECT_EQ(toFloat32(-1e39), -std::numeric_limits<float>::infinity());
    EXPECT_EQ(toFloat32(3.4e38), 3.4e38f);
    grid::Snapshot snap;
    snap.grid = centredGrid(2, 2, 4);
    for (const char* name : {"vx", "vy", "vz"})
        snap.fields.push_back({name, "m/s", std::vector<float>(snap.grid.cellCount(), 0.01f)});
    snap.fields[0].values[snap.grid.index(1, 0, 2)] = 1e30f;
    addDerivedVariables(snap);
    const grid::Field* magnitude = snap.find("velocity magnitude");
    ASSERT_NE(magnitude, nullptr);
    EXPECT_TRUE(std::isinf(magnitude->values[snap.grid.index(1, 0, 2)]));
    for (const char* stored : {"vx", "vy", "vz"})
        EXPECT_NO_THROW(grid::checkFinite(snap, *snap.find(stored), "in.nc"));
    try {
        grid::checkFinite(snap, *magnitude, "in.nc");
        FAIL() << "an infinite magnitude passed";
    } catch (const Error& e) {
        const std::string m = e.what();
        for (const char* fragment :
             {"in.nc: velocity magnitude: inf", "lat 45°, r 3485 km, lon 180° (point 1, 0, 2 of lat, r, lon ascending)",
              "vx = 1e+30 m/s, vy = 0.01 m/s, vz = 0.01 m/s"})
            EXPECT_NE(m.find(fragment), std::string::npos) << m << " lacks " << fragment;
    }
}

// checkFinite passes over chunks of finite values: an infinity, and a NaN computed from inputs that
// all have values, far into a large field are still found at their place; a NaN where an input has
// none passes.
TEST(Derived, CheckFiniteFindsTheFirstBadValueAnywhere)
{
    grid::Snapshot snap;
    snap.grid = centredGrid(20, 30, 40);
    snap.fields.push_back({"vx", "m/s", std::vector<float>(snap.grid.cellCount(), 0.01f)});
    snap.fields.push_back({"derived", "m/s", std::vector<float>(snap.grid.cellCount(), 1.0f), {"vx"}});
    const size_t input = snap.grid.index(11, 3, 5), nan = snap.grid.index(13, 7, 9), inf = snap.grid.index(17, 2, 3);
    snap.fields[0].values[input] = std::numeric_limits<float>::quiet_NaN();
    snap.fields[1].values[input] = std::numeric_limits<float>::quiet_NaN();  // missing where its input is
    EXPECT_NO_THROW(grid::checkFinite(snap, snap.fields[1], "in.nc"));
    snap.fields[1].values[inf] = std::numeric_limits<float>::infinity();
    snap.fields[1].values[nan] = std::numeric_limits<float>::quiet_NaN();
    for (const size_t expected : {nan, inf}) {
        try {
            grid::checkFinite(snap, snap.fields[1], "in.nc");
            FAIL() << "a bad value passed";
        } catch (const Error& e) {
            const std::string m = e.what();
            const size_t iLon = expected % 40, iR = expected / 40 % 30, iLat = expected / 1200;
            const std::string point = fmt::format("point {}, {}, {} of", iLat, iR, iLon);
            EXPECT_NE(m.find(point), std::string::npos) << m << " lacks " << point;
        }
        snap.fields[1].values[nan] = 1.0f;  // next: the infinity
    }
}

// The range's extremes are found four at a time; a zero among them keeps the sign of one
// std::min/std::max after another (the first zero met).
TEST(Stats, ARangeEndingAtZeroKeepsTheSignOfTheFirstZero)
{
    const grid::SphericalGrid g = centredGrid(10, 9, 16);
    for (const float first : {-0.0f, 0.0f}) {
        std::vector<float> v(g.cellCount(), 2.0f);
        v[37] = first;
        v[38] = -first;
        v[101] = -first;
        v[555] = 7.5f;
        const dataset::VariableStats st = computeStats(g, v);
        EXPECT_EQ(std::bit_cast<uint32_t>(st.range.min), std::bit_cast<uint32_t>(first));
        EXPECT_EQ(st.range.max, 7.5f);
        for (float& x : v)
            x = -x;
        const dataset::VariableStats negated = computeStats(g, v);
        EXPECT_EQ(std::bit_cast<uint32_t>(negated.range.max), std::bit_cast<uint32_t>(-first));
        EXPECT_EQ(negated.range.min, -7.5f);
    }
}

TEST(Memory, AGridTooLargeIsRefusedBeforeAllocating)
{
    grid::SphericalGrid g = centredGrid(1000, 500, 1000);
    EXPECT_EQ(preprocessMemoryBytes(g, 11), 12ull * 500'000'000 * 4);
    try {
        grid::checkGridFitsMemory(g, preprocessMemoryBytes(g, 11), "huge.nc", "preprocess", {8'000'000'000, "ulimit -v"});
        FAIL() << "24 GB fit into 8 GB";
    } catch (const Error& e) {
        EXPECT_STREQ(e.what(), "huge.nc: grid 1000x500x1000 (lat x r x lon) needs 24.0 GB of memory to preprocess, "
                               "8.0 GB available (ulimit -v)");
    }
    EXPECT_NO_THROW(grid::checkGridFitsMemory(g, preprocessMemoryBytes(g, 11), "huge.nc", "preprocess", {24'000'000'000, "x"}));
    g = centredGrid(2000, 1000, 4000);
    EXPECT_THROW(grid::checkGridFitsMemory(g, 0, "many.nc", "read", {UINT64_MAX, "x"}), Error);
}

TEST(DatasetWriteLock, OneWriterAtATimeAndTheOtherIsToldWho)
{
    TempDir dir("lock");
    {
        dataset::DatasetWriteLock first(dir / "ds");
        try {
            dataset::DatasetWriteLock second(dir / "ds");
            FAIL() << "two writers";
        } catch (const Error& e) {
            EXPECT_NE(std::string(e.what()).find(fmt::format("(pid {} on host", getpid())), std::string::npos)
                << e.what();
        }
        // The holder may remove the file (a run that leaves nothing); the next writer still locks.
        first.removeFile();
        dataset::DatasetWriteLock third(dir / "ds");
        EXPECT_THROW(dataset::DatasetWriteLock(dir / "ds"), Error);
    }
    EXPECT_NO_THROW(dataset::DatasetWriteLock(dir / "ds"));
}

TEST(Preprocess, AFreshRunThatFailsLeavesNothing)
{
    TempDir dir("fresh");
    grid::Snapshot broken = io::readSnapshot(fixtureFiles()[0]);
    broken.find("vx")->values[7] = 1e30f;
    io::writeContestFile(dir / "spherical001.nc", broken);
    try {
        preprocess({dir / "spherical001.nc"}, dir / "ds", quiet());
        FAIL() << "vx = 1e30 passed";
    } catch (const Error& e) {
        EXPECT_NE(std::string(e.what()).find("spherical001.nc: velocity magnitude: inf"), std::string::npos)
            << e.what();
    }
    EXPECT_FALSE(std::filesystem::exists(dir / "ds"));
    std::filesystem::create_directories(dir / "empty");
    EXPECT_THROW(preprocess({dir / "spherical001.nc"}, dir / "empty", quiet()), Error);
    EXPECT_TRUE(std::filesystem::is_empty(dir / "empty"));
}

// `raypc serve FILE.nc…` runs preprocessing in the background: it reports the steps done before it
// starts, then every step and pathline set, and a cancel stops it between steps with what was
// finished kept for the next run.
TEST(Preprocess, ACancelledRunKeepsItsStepsAndProgressCountsEveryItem)
{
    TempDir dir("cancel");
    std::atomic<bool> cancel{false};
    std::vector<std::string> events;
    PreprocessOptions o = quiet();
    o.cancel = &cancel;
    o.onProgress = [&](const PreprocessProgress& p) {
        events.push_back(fmt::format("{} {}/{}", p.phase, p.done, p.total));
        if (p.done == 1)
            cancel = true;
    };
    try {
        preprocess(fixtureFiles(), dir / "ds", o);
        FAIL() << "the cancelled run finished";
    } catch (const Error& e) {
        EXPECT_NE(std::string(e.what()).find("cancelled"), std::string::npos) << e.what();
    }
    EXPECT_EQ(events, (std::vector<std::string>{"steps 0/3", "steps 1/3"}));
    EXPECT_TRUE(std::filesystem::exists(dir / "ds" / "steps" / "0000" / "step.json"));
    EXPECT_FALSE(std::filesystem::exists(dir / "ds" / "steps" / "0001"));
    EXPECT_THROW(dataset::Dataset::open(dir / "ds"), Error);

    cancel = false;
    events.clear();
    o.onProgress = [&](const PreprocessProgress& p) { events.push_back(fmt::format("{} {}/{}", p.phase, p.done, p.total)); };
    const auto summary = preprocess(fixtureFiles(), dir / "ds", o);
    EXPECT_EQ(summary.stepsSkipped, 1);
    EXPECT_EQ(summary.stepsWritten, 2);
    EXPECT_EQ(events, (std::vector<std::string>{"steps 1/3", "steps 2/3", "steps 3/3", "pathlines 1/3", "pathlines 2/3",
                                                "pathlines 3/3"}));
    EXPECT_EQ(dataset::Dataset::open(dir / "ds")->steps().size(), 3u);
}

TEST(Preprocess, ContestFixtureDatasetHoldsEveryProduct)
{
    TempDir dir("pp");
    const auto summary = preprocess(fixtureFiles(), dir / "ds", quiet());
    EXPECT_EQ(summary.stepsWritten, 3);
    const auto ds = dataset::Dataset::open(dir / "ds");
    ASSERT_EQ(ds->steps().size(), 3u);
    EXPECT_DOUBLE_EQ(ds->steps()[2].timeMyr, 4.0);
    EXPECT_EQ(ds->steps()[1].source, "spherical002.nc");
    // The file's 8, the velocity's 2 stored, then the shell anomalies computed when read: of the
    // conductivity and the expansivity (the temperature's is the file's), and the temperature's
    // percentage (the fixture's conductivity and expansivity are anomalies: no percentage).
    ASSERT_EQ(ds->variables().size(), 13u);
    EXPECT_EQ(ds->variables()[8].name, "radial velocity");
    EXPECT_TRUE(ds->variables()[8].derived);
    EXPECT_TRUE(ds->variables()[9].stored);
    EXPECT_EQ(ds->variables()[11].name, "thermal expansivity anomaly");
    EXPECT_EQ(ds->variables()[11].units, "1/K");
    EXPECT_FALSE(ds->variables()[11].stored);
    EXPECT_EQ(ds->variables()[12].name, "temperature anomaly %");
    ASSERT_EQ(ds->levels().size(), 3u);
    EXPECT_EQ(ds->levels()[1].grid.nLat(), 18u);
    EXPECT_EQ(ds->levels()[1].grid.nR(), 21u);
    EXPECT_EQ(ds->levels()[2].grid.nR(), 11u);

    const grid::Snapshot snap = io::readSnapshot(fixtureFiles()[1]);
    const int anomaly = ds->variableIndex("temperature anomaly");
    ASSERT_GE(anomaly, 0);
    for (int level = 0; level < 3; ++level) {
        const auto vol = ds->load(1, level);
        const auto& g = vol->grid();
        // Level 0 is the input, quantised (u16, the default) within a 65535th of its brick's range
        // (value_encoding_test checks the exact bound); every level's bricks bound its values.
        const auto& layout = vol->bricks();
        if (level == 0) {
            for (size_t i = 0; i < g.cellCount(); ++i) {
                const size_t brick = layout.index(uint32_t(i / (g.nR() * g.nLon()) / layout.size),
                                                  uint32_t(i / g.nLon() % g.nR() / layout.size),
                                                  uint32_t(i % g.nLon() / layout.size));
                const float range = vol->brickBounds(anomaly)[2 * brick + 1] - vol->brickBounds(anomaly)[2 * brick];
                ASSERT_NEAR(vol->values(anomaly)[i], snap.find("temperature anomaly")->values[i], range / 65535 + 1e-4);
            }
        }
        for (size_t a = 0; a < g.nLat(); ++a)
            for (size_t b = 0; b < g.nR(); ++b)
                for (size_t c = 0; c < g.nLon(); ++c) {
                    const size_t brick = layout.index(a / layout.size, b / layout.size, c / layout.size);
                    const float v = vol->values(anomaly)[g.index(a, b, c)];
                    ASSERT_GE(v, vol->brickBounds(anomaly)[2 * brick]);
                    ASSERT_LE(v, vol->brickBounds(anomaly)[2 * brick + 1]);
                }
    }
    // Global ranges cover every step's range.
    for (const auto& step : ds->steps())
        for (size_t v = 0; v < ds->variables().size(); ++v) {
            EXPECT_LE(ds->variables()[v].global.range.min, step.stats[v].range.min);
            EXPECT_GE(ds->variables()[v].global.range.max, step.stats[v].range.max);
        }
    // The sample: coordinates consistent with each other, values those of the sampled points.
    const auto table = ds->loadSample(1);
    ASSERT_EQ(table.rows, 5000u);
    ASSERT_EQ(table.columns.size(), 7u + ds->variables().size());
    EXPECT_EQ(table.columns[6], "depth");
    const grid::SphericalGrid& g = snap.grid;
    for (size_t row = 0; row < table.rows; row += 97) {
        const double lat = table.at(row, 3), lon = table.at(row, 4), r = table.at(row, 5);
        const Vec3d p = sphericalToCartesianKm(lat, lon, r);
        ASSERT_NEAR(table.at(row, 0), p.x, 1e-2);
        ASSERT_NEAR(table.at(row, 6), kSurfaceRadiusKm - r, 1e-3);
        // The sample stores float coordinates: find the grid point they round from.
        auto nearest = [](const std::vector<double>& axis, double x) {
            size_t best = 0;
            for (size_t i = 1; i < axis.size(); ++i)
                if (std::abs(axis[i] - x) < std::abs(axis[best] - x))
                    best = i;
            EXPECT_NEAR(axis[best], x, 1e-3 * std::max(1.0, std::abs(x)));
            return best;
        };
        const size_t a = nearest(g.latDeg, lat), b = nearest(g.rKm, r), c = nearest(g.lonDeg, lon);
        ASSERT_EQ(table.at(row, 7 + anomaly), snap.find("temperature anomaly")->values[g.index(a, b, c)]);
        // A computed column: the file's temperature less the step's level-0 shell mean.
        const size_t percent = size_t(ds->variableIndex("temperature anomaly %"));
        const double mean = ds->steps()[1].shellMeans[size_t(ds->variableIndex("temperature"))][b];
        ASSERT_NEAR(table.at(row, 7 + percent), 100 * (snap.find("temperature")->values[g.index(a, b, c)] - mean) / mean,
                    1e-4);
    }
}

TEST(Preprocess, ResumesAfterAFailedRunAndSkipsFinishedSteps)
{
    TempDir dir("resume");
    // The third input's first variable is missing everywhere, which only shows when its data are
    // read: the run stops there, leaving two finished steps.
    auto files = fixtureFiles();
    std::filesystem::copy_file(files[0], dir / "spherical001.nc");
    std::filesystem::copy_file(files[1], dir / "spherical002.nc");
    grid::Snapshot broken = io::readSnapshot(files[2]);
    std::fill(broken.fields[0].values.begin(), broken.fields[0].values.end(), std::nanf(""));
    io::writeContestFile(dir / "spherical003.nc", broken);
    const std::vector<std::filesystem::path> inputs = {dir / "spherical001.nc", dir / "spherical002.nc",
                                                       dir / "spherical003.nc"};
    EXPECT_THROW(preprocess(inputs, dir / "ds", quiet()), Error);
    try {
        dataset::Dataset::open(dir / "ds");
        FAIL() << "an unfinished dataset opened";
    } catch (const Error& e) {
        EXPECT_NE(std::string(e.what()).find("did not finish"), std::string::npos) << e.what();
    }
    EXPECT_TRUE(std::filesystem::exists(dataset::format::stepDir(dir / "ds", 1) / dataset::format::kStepManifest));
    EXPECT_FALSE(std::filesystem::exists(dataset::format::stepDir(dir / "ds", 2)));
    // A stale temporary step directory (as a kill would leave) is cleaned up.
    std::filesystem::create_directories(dir / "ds" / "steps" / ".0002.tmp-1-0");

    std::filesystem::remove(dir / "spherical003.nc");
    std::filesystem::copy_file(files[2], dir / "spherical003.nc");
    const auto summary = preprocess(inputs, dir / "ds", quiet());
    EXPECT_EQ(summary.stepsSkipped, 2);
    EXPECT_EQ(summary.stepsWritten, 1);
    EXPECT_FALSE(std::filesystem::exists(dir / "ds" / "steps" / ".0002.tmp-1-0"));
    EXPECT_EQ(dataset::Dataset::open(dir / "ds")->steps().size(), 3u);

    // Other settings into the same directory are refused rather than mixed.
    auto other = quiet();
    other.dtMyr = 5;
    EXPECT_THROW(preprocess(inputs, dir / "ds", other), Error);
}

// A synthetic series of `steps` steps on a small grid, written into `dir` (its netCDF files).
std::vector<std::filesystem::path> synthSeries(const std::filesystem::path& dir, int steps)
{
    synth::SynthOptions o;
    o.nLat = 24;
    o.nR = 17;
    o.nLon = 48;
    o.steps = steps;
    synth::writeSyntheticSeries(dir, o);
    return io::listSnapshotFiles({dir});
}

// The one pass traces each line interval by interval as the steps are written; the lines and their
// attributes must be those of one trace over steps s..end of the written dataset's decoded arrays
// (what the pathline phase did before, re-reading the steps), to the bit.
TEST(Preprocess, PathlinesOfTheOnePassEqualOneTraceOverTheWrittenSteps)
{
    TempDir dir("onepass");
    PreprocessOptions o = quiet();
    o.pathlines.steps = 3;  // sets that end inside the series and sets cut by its end
    const auto summary = preprocess(synthSeries(dir / "in", 7), dir / "ds", o);
    EXPECT_EQ(summary.pathlineSetsWritten, 7);
    const auto ds = dataset::Dataset::open(dir / "ds");
    std::vector<std::string> names, units;
    for (const auto& v : ds->variables()) {
        names.push_back(v.name);
        units.push_back(v.units);
    }
    const size_t field = size_t(ds->variableIndex(o.pathlines.field));
    const size_t vx = size_t(ds->variableIndex("vx")), vy = size_t(ds->variableIndex("vy")),
                 vz = size_t(ds->variableIndex("vz"));
    size_t lines = 0;
    for (int s = 0; s < 7; ++s) {
        const int end = std::min(s + 3, 6);
        // The reference reads every variable from whole decoded arrays; the one pass reads the
        // velocity point by point where the lines sample it.
        analysis::FieldSeries series;
        series.grid = ds->levels()[0].grid;
        std::vector<std::shared_ptr<const dataset::StepVolume>> volumes;
        for (int k = s; k <= end; ++k) {
            series.timesMyr.push_back(ds->steps()[size_t(k)].timeMyr);
            const auto& volume = volumes.emplace_back(ds->load(k, 0));
            auto& fields = series.fields.emplace_back();
            for (size_t v = 0; v < volume->variableCount(); ++v)
                fields.push_back(volume->values(v));
        }
        const std::span<const float> values(series.field(0, field), series.grid.cellCount());
        const auto all = analysis::findCriticalPoints(series.grid, values);
        const auto seeds = analysis::selectSeeds(series.grid, values, all, o.pathlines.filter).seeds;
        const analysis::PathlineTracer tracer(series, vx, vy, vz, o.pathlines.tracer);
        const analysis::PathlineSet want = analysis::tracePathlines(series, tracer, seeds, 0, end - s, names, units);
        const analysis::PathlineSet got = analysis::loadPathlineSet(dir / "ds", s);
        ASSERT_GT(want.lineCount(), 0u) << s;
        EXPECT_EQ(got.endStep, end);
        ASSERT_EQ(got.offsets, want.offsets) << "set " << s;
        ASSERT_EQ(got.columns, want.columns);
        for (size_t i = 0; i < want.points.size(); ++i)
            ASSERT_EQ(got.points[i], want.points[i]) << "set " << s << " value " << i;
        for (size_t i = 0; i < want.attributes.size(); ++i)
            ASSERT_EQ(std::bit_cast<uint32_t>(got.attributes[i]), std::bit_cast<uint32_t>(want.attributes[i]))
                << "set " << s << " " << want.columns[i % want.columns.size()] << " of line " << i / want.columns.size();
        lines += want.lineCount();
    }
    EXPECT_EQ(summary.pathlineCount, lines);
}

// A rerun traces the sets still to do from the steps an earlier run wrote, with the shell means
// their manifests keep: a damaged one is one error naming the file and the field, as Dataset::open
// gives it.
TEST(Preprocess, ADamagedKeptShellMeanIsOneErrorNamingTheStepManifest)
{
    TempDir dir("keptmeans");
    const auto inputs = synthSeries(dir / "in", 4);
    PreprocessOptions o = quiet();
    o.pathlines.steps = 2;
    preprocess(inputs, dir / "ds", o);
    const auto manifestPath = dataset::format::stepDir(dir / "ds", 1) / dataset::format::kStepManifest;
    nlohmann::json step = nlohmann::json::parse(readFile(manifestPath));
    nlohmann::json& kept = step.at("level_shell_means").at(0);
    ASSERT_FALSE(kept.empty());
    const std::string base = kept.begin().key();
    kept[base][2] = "x";
    writeFileAtomic(manifestPath, step.dump(1));
    std::filesystem::remove_all(analysis::pathlineDir(dir / "ds", 0));
    try {
        preprocess(inputs, dir / "ds", o);
        FAIL() << "a damaged shell mean passed";
    } catch (const Error& e) {
        const std::string what = e.what();
        EXPECT_NE(what.find(manifestPath.string() + ": level_shell_means[0][\"" + base + "\"][2]: \"x\""),
                  std::string::npos)
            << what;
    }
}

// The pathlines are traced with a window of the newest steps' velocity, read point by point: what
// the tracing holds decoded does not grow with the number of steps (the pathline phase before held
// the 11 steps of a set: here 4 + 1 steps of 5, then 10 + 1 of 16), and is no velocity at all.
TEST(Preprocess, ThePathlineWindowDoesNotGrowWithTheSteps)
{
    TempDir dir("window");
    const auto few = preprocess(synthSeries(dir / "few", 5), dir / "ds-few", quiet());
    const auto many = preprocess(synthSeries(dir / "many", 16), dir / "ds-many", quiet());
    EXPECT_EQ(many.pathlineSetsWritten, 16);
    const size_t array = size_t(24) * 17 * 48 * sizeof(float);
    // Only a seed field with the variable it is computed from (decoded three steps' velocity was
    // 9 arrays more).
    EXPECT_GT(many.pathlineWindowPeakBytes, 0u);
    EXPECT_LE(many.pathlineWindowPeakBytes, 2 * array);
    EXPECT_LE(many.pathlineWindowPeakBytes, few.pathlineWindowPeakBytes + 3 * array)
        << few.pathlineWindowPeakBytes / array << " arrays for 5 steps, " << many.pathlineWindowPeakBytes / array
        << " for 16";
}

// Every regular file under `dir` (the write lock aside) and its bytes, by path relative to `dir`.
std::map<std::string, std::string> filesUnder(const std::filesystem::path& dir)
{
    std::map<std::string, std::string> files;
    for (const auto& entry : std::filesystem::recursive_directory_iterator(dir))
        if (entry.is_regular_file() && entry.path().filename() != ".lock")
            files[std::filesystem::relative(entry.path(), dir).string()] = readFile(entry.path());
    return files;
}

// One process reads step k + 1 on another thread while it writes step k (and traces its
// pathlines): the dataset must be byte for byte that of one step at a time, with and without
// pathlines; a step whose input fails to read stops the run after the steps before it are
// finished, with no temporary directory left and the failing step not begun.
TEST(Preprocess, ReadingAheadWritesTheBytesOfOneStepAtATime)
{
    TempDir dir("readahead");
    const auto inputs = synthSeries(dir / "in", 6);
    for (const bool pathlines : {true, false}) {
        PreprocessOptions o = quiet();
        o.pathlines.enabled = pathlines;
        o.pathlines.steps = 3;
        o.readAhead = false;
        const std::string tag = pathlines ? "lines" : "nolines";
        preprocess(inputs, dir / ("serial-" + tag), o);
        o.readAhead = true;
        const auto summary = preprocess(inputs, dir / ("ahead-" + tag), o);
        EXPECT_EQ(summary.stepsWritten, 6);
        EXPECT_EQ(summary.pathlineSetsWritten, pathlines ? 6 : 0);
        const auto serial = filesUnder(dir / ("serial-" + tag)), ahead = filesUnder(dir / ("ahead-" + tag));
        EXPECT_GT(serial.size(), 6u * 2 * dataset::kLevelCount);
        ASSERT_EQ(serial.size(), ahead.size()) << tag;
        for (const auto& [path, bytes] : serial) {
            ASSERT_TRUE(ahead.contains(path)) << tag << ": " << path;
            EXPECT_TRUE(ahead.at(path) == bytes) << tag << ": " << path << " differs";
        }
    }

    // Step 3's first variable is missing everywhere, which shows only when its values are read:
    // ahead of the run, while step 2 is being written.
    grid::Snapshot broken = io::readSnapshot(inputs[3]);
    std::fill(broken.fields[0].values.begin(), broken.fields[0].values.end(), std::nanf(""));
    io::writeContestFile(inputs[3], broken);
    std::vector<std::string> events;
    PreprocessOptions o = quiet();
    o.onProgress = [&](const PreprocessProgress& p) { events.push_back(fmt::format("{} {}/{}", p.phase, p.done, p.total)); };
    try {
        preprocess(inputs, dir / "failed", o);
        FAIL() << "a step missing everywhere passed";
    } catch (const Error& e) {
        EXPECT_NE(std::string(e.what()).find(inputs[3].filename().string()), std::string::npos) << e.what();
        EXPECT_NE(std::string(e.what()).find("3 finished steps stay"), std::string::npos) << e.what();
    }
    EXPECT_EQ(events, (std::vector<std::string>{"steps 0/6", "steps 1/6", "steps 2/6", "steps 3/6"}));
    std::vector<std::string> stepDirs;
    for (const auto& entry : std::filesystem::directory_iterator(dir / "failed" / "steps"))
        stepDirs.push_back(entry.path().filename().string());
    std::sort(stepDirs.begin(), stepDirs.end());
    EXPECT_EQ(stepDirs, (std::vector<std::string>{"0000", "0001", "0002"}));
    for (int s = 0; s < 3; ++s)
        EXPECT_TRUE(std::filesystem::exists(dataset::format::stepDir(dir / "failed", s) / dataset::format::kStepManifest));
}

// A run takes the finished steps of another dataset made with the same settings from the same files
// (hard links) instead of making them again (`raypc serve FILES`: the one-step preview takes the
// series' step 0). Here a series takes a one-step dataset's step 0 and is byte for byte the series
// made without it; a donor made with other settings, or from a file changed since, gives nothing.
TEST(Preprocess, TakesTheStepsOfAnotherDatasetMadeWithTheSameSettingsFromTheSameFiles)
{
    TempDir dir("donor");
    const auto inputs = synthSeries(dir / "in", 4);
    PreprocessOptions o = quiet();
    o.pathlines.steps = 2;
    preprocess(inputs, dir / "made", o);

    PreprocessOptions preview = quiet();
    preview.pathlines.enabled = false;
    preprocess({inputs.front()}, dir / "preview", preview);
    PreprocessOptions taking = o;
    taking.stepsFrom = dir / "preview";
    auto summary = preprocess(inputs, dir / "taken", taking);
    EXPECT_EQ(summary.stepsTaken, 1);
    EXPECT_EQ(summary.stepsSkipped, 1);
    EXPECT_EQ(summary.stepsWritten, 3);
    EXPECT_EQ(summary.pathlineSetsWritten, 4);
    const auto made = filesUnder(dir / "made"), taken = filesUnder(dir / "taken");
    ASSERT_EQ(made.size(), taken.size());
    for (const auto& [path, bytes] : made) {
        ASSERT_TRUE(taken.contains(path)) << path;
        EXPECT_TRUE(taken.at(path) == bytes) << path << " differs";
    }
    // Linked, not copied: the preview keeps its own names to the same files.
    const auto sample = [&](const std::filesystem::path& ds) {
        return dataset::format::stepDir(ds, 0) / dataset::format::kStepSample;
    };
    EXPECT_EQ(std::filesystem::hard_link_count(sample(dir / "taken")), 2u);
    EXPECT_TRUE(std::filesystem::equivalent(sample(dir / "taken"), sample(dir / "preview")));
    EXPECT_TRUE(std::filesystem::exists(dataset::format::stepDir(dir / "preview", 0) / dataset::format::kStepManifest));

    // Another brick size: the preview's step is not this dataset's.
    PreprocessOptions bricks = taking;
    bricks.brickSize = 4;
    summary = preprocess(inputs, dir / "bricks", bricks);
    EXPECT_EQ(summary.stepsTaken, 0);
    EXPECT_EQ(summary.stepsWritten, 4);

    // The first file changed since the preview was made (its modification time): made again.
    std::filesystem::last_write_time(inputs.front(),
                                     std::filesystem::last_write_time(inputs.front()) + std::chrono::seconds(5));
    summary = preprocess(inputs, dir / "changed", taking);
    EXPECT_EQ(summary.stepsTaken, 0);
    EXPECT_EQ(summary.stepsWritten, 4);
}

// netCDF files as a StepSource that records which thread read each step, and at which nice value.
class ReadRecordingSource final : public StepSource {
public:
    explicit ReadRecordingSource(std::vector<std::filesystem::path> files) : m_files(std::move(files)) {}
    size_t stepCount() const override { return m_files.size(); }
    std::string path(size_t s) const override { return m_files[s].string(); }
    std::string label(size_t s) const override { return m_files[s].filename().string(); }
    nlohmann::json fingerprint(size_t s) const override { return label(s); }
    io::FileHeader plan() override { return io::readStepHeader(m_files.front(), {}); }
    grid::Snapshot read(size_t s) const override
    {
        {
            std::lock_guard lock(m_mutex);
            m_reads.push_back({::gettid(), ::getpriority(PRIO_PROCESS, static_cast<id_t>(::gettid()))});
        }
        return io::readStep(m_files[s], {});
    }
    std::vector<std::pair<pid_t, int>> reads() const
    {
        std::lock_guard lock(m_mutex);
        return m_reads;
    }

private:
    std::vector<std::filesystem::path> m_files;
    mutable std::mutex m_mutex;
    mutable std::vector<std::pair<pid_t, int>> m_reads;  // thread, nice
};

// A run beside an interactive user lowers its own thread's priority once it has started the thread
// that reads the steps ahead; that thread reads every step at the caller's priority (reading is the
// run's critical path). The run is on a thread of its own: a thread's nice cannot be raised again.
TEST(Preprocess, ABackgroundRunLowersItsPriorityAndReadsAtTheCallers)
{
    TempDir dir("nice");
    ReadRecordingSource source(synthSeries(dir / "in", 4));
    PreprocessOptions o = quiet();
    o.pathlines.steps = 2;
    o.niceIncrement = 4;
    int before = 0, after = 0;
    pid_t caller = 0;
    std::thread run([&] {
        caller = ::gettid();
        before = ::getpriority(PRIO_PROCESS, static_cast<id_t>(caller));
        preprocess(source, dir / "ds", o);
        after = ::getpriority(PRIO_PROCESS, static_cast<id_t>(caller));
    });
    run.join();
    if (before > 15)
        GTEST_SKIP() << "this process runs at nice " << before << ": no room to lower a thread's priority";
    EXPECT_EQ(after, before + 4);
    const auto reads = source.reads();
    ASSERT_EQ(reads.size(), 4u);
    for (const auto& [thread, nice] : reads) {
        EXPECT_NE(thread, caller);
        EXPECT_EQ(thread, reads.front().first) << "one thread reads every step";
        EXPECT_EQ(nice, before);
    }
}

}  // namespace
}  // namespace raypc::preprocess
