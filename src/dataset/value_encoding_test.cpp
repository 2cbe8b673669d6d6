// The u16 encoding of the level arrays (value_encoding.h) against truth: every point's error
// within (max − min) / 131070 of the brick that owns it, with the brick bounds computed here by
// brute force (not by computeBrickBounds); decoded values inside every brick that covers them; a
// constant brick, extreme ranges, the lon seam and the poles. Datasets: the contest-layout files
// (written by Python netCDF4) preprocessed both ways, version-1 datasets, damaged files.
#include "dataset/value_encoding.h"

#include "core/atomic_file.h"
#include "core/error.h"
#include "dataset/bricks.h"
#include "dataset/dataset.h"
#include "dataset/dataset_format.h"
#include "dataset/shell_anomaly.h"
#include "io/netcdf_reader.h"
#include "analysis/pathline_storage.h"
#include "preprocess/preprocess.h"
#include "preprocess/preprocess_numerics.h"
#include "grid/test_util.h"

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include <bit>
#include <cmath>
#include <cstring>
#include <limits>
#include <random>

namespace raypc::dataset {
namespace {

using testing::centredGrid;
using testing::TempDir;

// Brick b's points along an axis, by the rule of docs/format.md ("Bricks"): [b·s, (b+1)·s]
// inclusive, clamped at the last point, or for lon wrapping to column 0 (at most n points).
std::vector<size_t> brickPoints(size_t b, size_t s, size_t n, bool wraps)
{
    std::vector<size_t> points;
    if (wraps) {
        for (size_t k = 0; k <= s && k < n; ++k)
            points.push_back((b * s + k) % n);
    } else {
        for (size_t i = b * s; i <= std::min((b + 1) * s, n - 1); ++i)
            points.push_back(i);
    }
    return points;
}

struct Checked {
    double worstRatio = 0;  // largest error / bound over the points
    size_t points = 0;
    std::vector<float> decoded;  // the values after the round trip
};

// Encodes and decodes `values`, checking every point against its owning brick's bound and every
// brick's decoded values against its exact bounds (both computed here).
Checked checkRoundTrip(const grid::SphericalGrid& g, const std::vector<float>& values, uint32_t size = 8)
{
    const grid::BrickLayout layout = grid::BrickLayout::forGrid(g, size);
    std::vector<float> bounds(2 * layout.brickCount());
    computeBrickBounds(g, layout, values, bounds);
    std::vector<uint16_t> encoded(values.size());
    encodeUint16(g, layout, values, bounds, encoded);
    std::vector<float> decoded(values.size());
    decodeUint16(g, layout, encoded, bounds, decoded);

    // Brute-force bounds of every brick and, per point, those of its owner.
    std::vector<float> lo(layout.brickCount()), hi(layout.brickCount());
    for (size_t a = 0; a < layout.count[0]; ++a)
        for (size_t b = 0; b < layout.count[1]; ++b)
            for (size_t c = 0; c < layout.count[2]; ++c) {
                const size_t brick = layout.index(a, b, c);
                lo[brick] = INFINITY;
                hi[brick] = -INFINITY;
                for (size_t i : brickPoints(a, size, g.nLat(), false))
                    for (size_t j : brickPoints(b, size, g.nR(), false))
                        for (size_t k : brickPoints(c, size, g.nLon(), true)) {
                            lo[brick] = std::min(lo[brick], values[g.index(i, j, k)]);
                            hi[brick] = std::max(hi[brick], values[g.index(i, j, k)]);
                        }
                EXPECT_EQ(bounds[2 * brick], lo[brick]);
                EXPECT_EQ(bounds[2 * brick + 1], hi[brick]);
                // Skipping by the stored bounds stays exact: every decoded point of the brick is inside.
                for (size_t i : brickPoints(a, size, g.nLat(), false))
                    for (size_t j : brickPoints(b, size, g.nR(), false))
                        for (size_t k : brickPoints(c, size, g.nLon(), true)) {
                            const float d = decoded[g.index(i, j, k)];
                            EXPECT_GE(d, lo[brick]) << "brick " << brick << " point " << i << " " << j << " " << k;
                            EXPECT_LE(d, hi[brick]) << "brick " << brick << " point " << i << " " << j << " " << k;
                        }
            }
    Checked result;
    const Uint16PointDecoder pointDecoder(g, layout);
    for (size_t i = 0; i < g.nLat(); ++i)
        for (size_t j = 0; j < g.nR(); ++j)
            for (size_t k = 0; k < g.nLon(); ++k) {
                const size_t owner = layout.index(i / size, j / size, k / size);
                const size_t p = g.index(i, j, k);
                const double quantisation = (double(hi[owner]) - double(lo[owner])) / 131070.0;
                // Plus half an ulp of the decoded float (value_encoding.h).
                const double rounding = 0.5 * std::abs(std::nextafter(decoded[p], INFINITY) - decoded[p]);
                const double error = std::abs(double(decoded[p]) - double(values[p]));
                // One point decoded alone gives the same bits, and so does the decoder of many points.
                EXPECT_EQ(decodeUint16Point(g, layout, encoded.data(), bounds.data(), i, j, k), decoded[p]);
                EXPECT_EQ(pointDecoder.decode(encoded.data(), bounds.data(), p, i, j, k, false), decoded[p]);
                EXPECT_LE(error, quantisation * (1 + 1e-9) + rounding)
                    << "point " << i << " " << j << " " << k << ": " << values[p] << " -> " << decoded[p];
                if (quantisation > 0)
                    result.worstRatio = std::max(result.worstRatio, error / (quantisation + rounding));
                else
                    EXPECT_EQ(decoded[p], values[p]);  // a constant brick decodes exactly
                ++result.points;
            }
    result.decoded = std::move(decoded);
    return result;
}

// computeBrickBounds keeps four running extremes per brick: its bounds have the bits of one
// std::min and std::max value after value in the brick's order (lat, r, lon from the brick's first
// column, wrapping at the seam), on values with zeros of both signs, NaN and ties, on grids whose
// last bricks are short and whose lon bricks wrap.
TEST(BrickBounds, TheBitsOfOneValueAfterAnother)
{
    std::mt19937 rng(11);
    for (const auto& g : {centredGrid(9, 7, 13), centredGrid(12, 10, 21), centredGrid(5, 4, 3)})
        for (const uint32_t size : {2u, 4u, 8u}) {
            const grid::BrickLayout layout = grid::BrickLayout::forGrid(g, size);
            for (int field = 0; field < 4; ++field) {
                std::uniform_int_distribution<int> pick(0, 9);
                std::uniform_real_distribution<float> real(-1, 1);
                std::vector<float> values(g.cellCount());
                for (float& v : values) {
                    const int k = pick(rng);
                    v = field == 0 ? real(rng) : k < 3 ? 0.0f : k < 6 ? -0.0f : k < 7 ? NAN : field == 1 ? real(rng) : float(k);
                    if (field == 3)
                        v = std::abs(v);  // zeros the lowest values
                }
                std::vector<float> got(2 * layout.brickCount());
                computeBrickBounds(g, layout, values, got);
                for (size_t b = 0; b < layout.brickCount(); ++b) {
                    const size_t bLon = b % layout.count[2], bR = (b / layout.count[2]) % layout.count[1],
                                 bLat = b / (size_t(layout.count[2]) * layout.count[1]);
                    float lo = INFINITY, hi = -INFINITY;
                    for (size_t i = bLat * size; i <= std::min<size_t>((bLat + 1) * size, g.nLat() - 1); ++i)
                        for (size_t j = bR * size; j <= std::min<size_t>((bR + 1) * size, g.nR() - 1); ++j)
                            for (size_t k = 0; k < std::min<size_t>(size + 1, g.nLon()); ++k) {
                                const float v = values[g.index(i, j, (bLon * size + k) % g.nLon())];
                                lo = std::min(lo, v);
                                hi = std::max(hi, v);
                            }
                    EXPECT_EQ(std::bit_cast<uint32_t>(got[2 * b]), std::bit_cast<uint32_t>(lo))
                        << "brick " << b << " field " << field << ": " << got[2 * b] << " " << lo;
                    EXPECT_EQ(std::bit_cast<uint32_t>(got[2 * b + 1]), std::bit_cast<uint32_t>(hi))
                        << "brick " << b << " field " << field << ": " << got[2 * b + 1] << " " << hi;
                }
            }
        }
}

// encodeUint16 rounds the points within their brick's bounds first and clamps the integer: the
// codes of u = round((v − min) / (max − min) · levels), clamped, for every point, with the bounds
// computeBrickBounds gives, with narrower ones (points outside them), with constant bricks and with
// missing values.
TEST(Uint16Encoding, CodesOfTheFormulaForEveryPoint)
{
    std::mt19937 rng(5);
    const grid::SphericalGrid g = centredGrid(11, 9, 37);
    const grid::BrickLayout layout = grid::BrickLayout::forGrid(g, 4);
    for (int field = 0; field < 4; ++field) {
        std::uniform_real_distribution<float> real(-3, 5);
        std::uniform_int_distribution<int> pick(0, 19);
        std::vector<float> values(g.cellCount());
        const bool missing = field == 3;
        for (size_t i = 0; i < values.size(); ++i)
            values[i] = field == 2 && (i / g.nLon()) % 3 == 0 ? 1.25f : missing && pick(rng) == 0 ? NAN : real(rng);
        std::vector<float> bounds(2 * layout.brickCount());
        computeBrickBounds(g, layout, values, bounds);
        if (field == 1)
            for (size_t b = 0; b < layout.brickCount(); ++b)
                if (b % 2 == 0 && bounds[2 * b] < bounds[2 * b + 1]) {  // points on either side outside
                    const float quarter = (bounds[2 * b + 1] - bounds[2 * b]) / 4;
                    bounds[2 * b] += quarter;
                    bounds[2 * b + 1] -= quarter;
                }
        std::vector<uint16_t> codes(g.cellCount());
        encodeUint16(g, layout, values, bounds, codes, missing);
        const double levels = missing ? 65534.0 : 65535.0;
        for (size_t iLat = 0; iLat < g.nLat(); ++iLat)
            for (size_t iR = 0; iR < g.nR(); ++iR)
                for (size_t iLon = 0; iLon < g.nLon(); ++iLon) {
                    const size_t i = g.index(iLat, iR, iLon), b = layout.index(iLat / 4, iR / 4, iLon / 4);
                    const double lo = bounds[2 * b], hi = bounds[2 * b + 1];
                    uint16_t expected = 65535;
                    if (!std::isnan(values[i])) {
                        const double perUnit = hi > lo ? levels / (hi - lo) : 0.0, t = (double(values[i]) - lo) * perUnit;
                        expected = uint16_t(std::floor(std::clamp(t, 0.0, levels) + 0.5));
                    }
                    ASSERT_EQ(codes[i], expected) << "field " << field << " at " << iLat << " " << iR << " " << iLon;
                }
    }
}

TEST(Uint16Encoding, RandomValuesStayWithinTheBoundOfTheirBrick)
{
    // Odd sizes: the last lat and r bricks hold one point, the last lon brick wraps past column 0.
    const grid::SphericalGrid g = centredGrid(17, 9, 21);
    std::mt19937 rng(7);
    std::uniform_real_distribution<float> u(-500, 1500);
    std::vector<float> values(g.cellCount());
    for (auto& v : values)
        v = u(rng);
    const Checked c = checkRoundTrip(g, values);
    EXPECT_EQ(c.points, g.cellCount());
    // Rounding to the nearest level uses about the whole bound on random data.
    EXPECT_GT(c.worstRatio, 0.99);
    EXPECT_LE(c.worstRatio, 1.0 + 1e-6);
}

TEST(Uint16Encoding, AConstantBrickDecodesExactly)
{
    const grid::SphericalGrid g = centredGrid(16, 16, 32);
    // Constant 3.25 in the lat and r bricks 0 away from their shared points, a gradient elsewhere.
    auto values = testing::fillGrid(g, [](size_t i, size_t j, size_t k) {
        return i < 8 && j < 8 && k < 24 ? 3.25 : 3.25 + double(i + j + k);
    });
    const std::vector<float> decoded = checkRoundTrip(g, values).decoded;
    for (size_t i = 0; i < 8; ++i)
        for (size_t j = 0; j < 8; ++j)
            for (size_t k = 1; k < 8; ++k)  // brick (0, 0, 1) and (0, 0, 2) are constant
                ASSERT_EQ(decoded[g.index(i, j, 8 + k)], 3.25f);
}

TEST(Uint16Encoding, ExtremeRangesOfFloat32)
{
    const grid::SphericalGrid g = centredGrid(9, 9, 16);
    // Float32's largest magnitudes beside tiny ones in one brick (max − min overflows float, not
    // double), a brick of denormals, and one of values 1 ulp apart.
    const float big = std::numeric_limits<float>::max();
    const float tiny = std::numeric_limits<float>::denorm_min();
    auto values = testing::fillGrid(g, [&](size_t i, size_t j, size_t k) -> double {
        if (k < 8)
            return (i + j + k) % 3 == 0 ? big : (i + j + k) % 3 == 1 ? -big : 1e-30 * double(i);
        if (i < 4)
            return tiny * double(j + k);
        return std::nextafter(1.0f, 2.0f) * ((i + j + k) % 2 ? 1.0f : std::nextafter(1.0f, 0.0f));
    });
    checkRoundTrip(g, values);
}

TEST(Uint16Encoding, JumpsAtTheLonSeamAndAtThePoles)
{
    // A field that jumps by 1e6 between the last column and column 0 and at the pole rows: the shared
    // points clamp into the neighbouring bricks' bounds, so each brick still bounds what it holds.
    const grid::SphericalGrid g = centredGrid(18, 10, 36);
    auto values = testing::fillGrid(g, [&](size_t i, size_t j, size_t k) {
        const double jump = (k == 0 ? 1e6 : 0) + (i == 0 || i == g.nLat() - 1 ? -1e6 : 0);
        return jump + double(j) * 0.5 + std::sin(double(k));
    });
    const Checked c = checkRoundTrip(g, values);
    EXPECT_LE(c.worstRatio, 1.0 + 1e-6);
    // Smaller bricks, as a coarse level or another --brick-size would have.
    checkRoundTrip(g, values, 4);
    checkRoundTrip(g, values, 2);
}

TEST(Uint16Encoding, EncodingNames)
{
    EXPECT_EQ(parseEncoding("u16", "x"), ValueEncoding::Uint16);
    EXPECT_EQ(parseEncoding("float32", "x"), ValueEncoding::Float32);
    try {
        parseEncoding("f16", "--encoding");
        FAIL();
    } catch (const Error& e) {
        EXPECT_STREQ(e.what(), "--encoding: encoding 'f16' is unknown, expected float32 or u16");
    }
}

// --- Datasets ------------------------------------------------------------------------------------

preprocess::PreprocessOptions options(ValueEncoding encoding)
{
    preprocess::PreprocessOptions o;
    o.quiet = true;
    o.sampleRows = 2000;
    o.encoding = encoding;
    return o;
}

// The contest-layout files preprocessed once per encoding, shared by the tests below.
class EncodedDatasets : public ::testing::Test {
protected:
    static void SetUpTestSuite()
    {
        s_dir = std::make_unique<TempDir>("encodings");
        const auto files = io::listSnapshotFiles({testing::contestLayoutDir()});
        preprocess::preprocess(files, s_dir->path() / "u16", options(ValueEncoding::Uint16));
        preprocess::preprocess(files, s_dir->path() / "f32", options(ValueEncoding::Float32));
    }
    static void TearDownTestSuite() { s_dir.reset(); }
    static std::filesystem::path dir(const char* name) { return s_dir->path() / name; }
    static std::unique_ptr<TempDir> s_dir;
};
std::unique_ptr<TempDir> EncodedDatasets::s_dir;

TEST_F(EncodedDatasets, EveryPointOfTheContestFilesIsWithinTheBound)
{
    const auto u16 = Dataset::open(dir("u16"));
    const auto f32 = Dataset::open(dir("f32"));
    EXPECT_EQ(u16->encoding(), ValueEncoding::Uint16);
    EXPECT_EQ(f32->encoding(), ValueEncoding::Float32);
    const auto files = io::listSnapshotFiles({testing::contestLayoutDir()});
    size_t checked = 0;
    double worst = 0;
    for (int step = 0; step < int(files.size()); ++step) {
        // The truth at level 0: the file's values (and the derived ones from them).
        grid::Snapshot truth = io::readSnapshot(files[size_t(step)]);
        preprocess::addDerivedVariables(truth);
        ASSERT_EQ(truth.fields.size(), u16->variables().size());
        for (int level = 0; level < kLevelCount; ++level) {
            const auto a = u16->load(step, level);
            const auto b = f32->load(step, level);
            const auto& g = a->grid();
            const auto& layout = a->bricks();
            for (size_t v = 0; v < a->variableCount(); ++v) {
                // The encoding of the stored ones (computed variables: shell_anomaly_test.cpp).
                if (!u16->variables()[v].stored)
                    continue;
                // Coarser levels: the truth is the float32 dataset's (exact) means.
                const float* exact = level == 0 ? truth.fields[v].values.data() : b->values(v);
                if (level == 0) {
                    for (size_t i = 0; i < g.cellCount(); ++i)
                        ASSERT_EQ(b->values(v)[i], exact[i]);  // float32 is exact
                }
                for (size_t i = 0; i < g.nLat(); ++i)
                    for (size_t j = 0; j < g.nR(); ++j)
                        for (size_t k = 0; k < g.nLon(); ++k) {
                            const size_t p = g.index(i, j, k);
                            const size_t owner = layout.index(uint32_t(i / 8), uint32_t(j / 8), uint32_t(k / 8));
                            const float lo = a->brickBounds(v)[2 * owner], hi = a->brickBounds(v)[2 * owner + 1];
                            ASSERT_LE(lo, exact[p]);
                            ASSERT_GE(hi, exact[p]);
                            const double bound = uint16ErrorBound(lo, hi);
                            const double decoded = a->values(v)[p];
                            const double error = std::abs(decoded - exact[p]);
                            const double ulp = std::abs(std::nextafter(float(decoded), INFINITY) - float(decoded));
                            ASSERT_LE(error, bound * (1 + 1e-9) + 0.5 * ulp)
                                << u16->variables()[v].name << " step " << step << " level " << level;
                            if (bound > 0)
                                worst = std::max(worst, error / (bound + 0.5 * ulp));
                            ++checked;
                        }
            }
        }
    }
    EXPECT_GT(checked, size_t(3 * 11 * 36 * 41 * 72));
    EXPECT_LE(worst, 1 + 1e-6);
    std::printf("%zu values checked; the largest error is %.6f of its bound\n", checked, worst);
    // Statistics stay exact (computed before quantising): the same in both datasets.
    for (size_t s = 0; s < u16->steps().size(); ++s)
        for (size_t v = 0; v < u16->variables().size(); ++v) {
            EXPECT_EQ(u16->steps()[s].stats[v].range.min, f32->steps()[s].stats[v].range.min);
            EXPECT_EQ(u16->steps()[s].stats[v].range.max, f32->steps()[s].stats[v].range.max);
            EXPECT_EQ(u16->steps()[s].stats[v].mean, f32->steps()[s].stats[v].mean);
            EXPECT_EQ(u16->steps()[s].stats[v].histogram, f32->steps()[s].stats[v].histogram);
        }
    EXPECT_EQ(u16->loadSample(1).values, f32->loadSample(1).values);
}

TEST_F(EncodedDatasets, HalfTheBytesOfFloat32)
{
    auto bytes = [](const std::filesystem::path& root, const std::string& ext) {
        size_t sum = 0;
        for (const auto& e : std::filesystem::recursive_directory_iterator(root / "steps"))
            if (e.is_regular_file() && e.path().extension() == ext)
                sum += e.file_size();
        return sum;
    };
    const size_t u = bytes(dir("u16"), ".u16"), f = bytes(dir("f32"), ".f32") - bytes(dir("u16"), ".f32");
    // The float32 dataset's .f32 level arrays minus what both hold (bounds, samples) is the values.
    EXPECT_EQ(2 * u, f);
}

TEST_F(EncodedDatasets, PathlinesOfBothEncodingsAgree)
{
    // The contest-layout velocities (solid-body rotation plus a uniform radial drift) quantised to
    // 1/131070 of a brick's range move a point by metres over the 4 Myr traced: the lines agree
    // far within the tracer's stored-point spacing (25 km).
    constexpr double kToleranceKm = 0.05;
    double worstKm = 0;
    for (int s = 0; s < 3; ++s) {
        const analysis::PathlineSet a = analysis::loadPathlineSet(dir("u16"), s);
        const analysis::PathlineSet b = analysis::loadPathlineSet(dir("f32"), s);
        ASSERT_EQ(a.lineCount(), b.lineCount()) << "step " << s;
        ASSERT_EQ(a.offsets, b.offsets) << "step " << s;
        for (size_t i = 0; i < a.points.size(); i += 4) {
            const double d = std::hypot(a.points[i] - b.points[i], a.points[i + 1] - b.points[i + 1],
                                        a.points[i + 2] - b.points[i + 2]);
            worstKm = std::max(worstKm, d);
            ASSERT_LE(d, kToleranceKm) << "step " << s << " point " << i / 4;
            // Point times follow the adaptive steps, which the velocity's last digits shift.
            ASSERT_NEAR(a.points[i + 3], b.points[i + 3], 1e-4);
        }
    }
    std::printf("pathlines u16 vs float32: largest distance between corresponding points %.3g km\n", worstKm);
}

TEST_F(EncodedDatasets, VersionOneDatasetsStillOpen)
{
    // A version-1 dataset: float32 arrays and a manifest without `encoding`.
    TempDir tmp("v1");
    std::filesystem::copy(dir("f32"), tmp / "v1", std::filesystem::copy_options::recursive);
    const auto manifest = tmp / "v1" / format::kManifest;
    auto j = nlohmann::json::parse(readFile(manifest));
    j["version"] = 1;
    j.erase("encoding");
    writeFileAtomic(manifest, j.dump(1));
    const auto v1 = Dataset::open(tmp / "v1");
    EXPECT_EQ(v1->encoding(), ValueEncoding::Float32);
    const grid::Snapshot truth = io::readSnapshot(io::listSnapshotFiles({testing::contestLayoutDir()})[2]);
    const auto volume = v1->load(2, 0);
    for (size_t i = 0; i < truth.grid.cellCount(); ++i)
        ASSERT_EQ(volume->values(0)[i], truth.fields[0].values[i]);
    // A version from the future is refused with what this raypc reads.
    j["version"] = 3;
    writeFileAtomic(manifest, j.dump(1));
    try {
        Dataset::open(tmp / "v1");
        FAIL();
    } catch (const Error& e) {
        EXPECT_NE(std::string(e.what()).find("format version 3, this raypc reads versions 1 to 2"), std::string::npos)
            << e.what();
    }
}

TEST_F(EncodedDatasets, ARerunWithTheOtherEncodingIsRefused)
{
    TempDir tmp("rerun_encoding");
    std::filesystem::copy(dir("u16"), tmp / "ds", std::filesystem::copy_options::recursive);
    try {
        preprocess::preprocess(io::listSnapshotFiles({testing::contestLayoutDir()}), tmp / "ds", options(ValueEncoding::Float32));
        FAIL() << "a float32 run resumed a u16 dataset";
    } catch (const Error& e) {
        EXPECT_NE(std::string(e.what()).find("a different 'encoding'"), std::string::npos) << e.what();
    }
    EXPECT_EQ(Dataset::open(tmp / "ds")->encoding(), ValueEncoding::Uint16);
}

TEST_F(EncodedDatasets, ADamagedFileIsOneErrorNamingIt)
{
    TempDir tmp("damaged");
    std::filesystem::copy(dir("u16"), tmp / "ds", std::filesystem::copy_options::recursive);
    const auto ds = Dataset::open(tmp / "ds");
    const auto level = format::levelDir(format::stepDir(tmp / "ds", 1), 0);
    auto expectError = [&](const std::filesystem::path& file, const std::string& what) {
        try {
            ds->load(1, 0);
            FAIL() << "no error for " << file;
        } catch (const Error& e) {
            const std::string message = e.what();
            EXPECT_NE(message.find(file.string()), std::string::npos) << message;
            EXPECT_NE(message.find(what), std::string::npos) << message;
        }
    };
    // Truncated.
    const auto values = format::encodedValuesFile(level, "temperature");
    std::filesystem::resize_file(values, std::filesystem::file_size(values) - 2);
    expectError(values, "bytes, expected 212544 (106272 points of u16)");
    std::filesystem::remove(values);
    expectError(values, "");
    std::filesystem::copy_file(format::encodedValuesFile(format::levelDir(format::stepDir(dir("u16"), 1), 0), "temperature"),
                               values);
    EXPECT_NO_THROW(ds->load(1, 0));
    // Bounds that are not finite or out of order.
    const auto bounds = format::boundsFile(level, "vx");
    std::string bytes = readFile(bounds);
    const float nan = std::nanf("");
    std::memcpy(bytes.data() + 8 * 5, &nan, 4);
    writeFileAtomic(bounds, bytes);
    expectError(bounds, "brick 5 has bounds (nan");
}

}  // namespace
}  // namespace raypc::dataset

namespace raypc::dataset {
namespace {

// Missing values (NaN) round-trip as NaN and never enter a brick's bounds; a brick of nothing but
// missing values has the bounds (+inf, -inf); the other points keep the error bound of 65534 levels,
// the point decoder gives the same bits as the array decoder.
TEST(ValueEncoding, MissingValuesStayMissing)
{
    const grid::SphericalGrid g = testing::centredGrid(20, 12, 24);
    std::vector<float> values(g.cellCount());
    for (size_t i = 0; i < values.size(); ++i)
        values[i] = float(std::sin(0.37 * double(i)) * 100.0 + 50.0);
    // A hole: every point of lat rows 0..9 (a whole brick and more), and scattered points elsewhere.
    for (size_t iLat = 0; iLat < 10; ++iLat)
        for (size_t iR = 0; iR < g.nR(); ++iR)
            for (size_t iLon = 0; iLon < g.nLon(); ++iLon)
                values[g.index(iLat, iR, iLon)] = NAN;
    for (size_t i = 0; i < values.size(); i += 97)
        values[i] = NAN;
    const grid::BrickLayout layout = grid::BrickLayout::forGrid(g, 8);
    std::vector<float> bounds(2 * layout.brickCount());
    computeBrickBounds(g, layout, values, bounds);
    EXPECT_EQ(bounds[0], INFINITY);  // brick (0, 0, 0): lat rows 0..8, all missing
    EXPECT_EQ(bounds[1], -INFINITY);
    std::vector<uint16_t> encoded(values.size());
    encodeUint16(g, layout, values, bounds, encoded, true);
    std::vector<float> decoded(values.size());
    decodeUint16(g, layout, encoded, bounds, decoded, true);
    size_t missing = 0;
    const Uint16PointDecoder pointDecoder(g, layout);
    for (size_t iLat = 0; iLat < g.nLat(); ++iLat)
        for (size_t iR = 0; iR < g.nR(); ++iR)
            for (size_t iLon = 0; iLon < g.nLon(); ++iLon) {
                const size_t i = g.index(iLat, iR, iLon);
                const float point = decodeUint16Point(g, layout, encoded.data(), bounds.data(), iLat, iR, iLon, true);
                const float decoderPoint = pointDecoder.decode(encoded.data(), bounds.data(), i, iLat, iR, iLon, true);
                EXPECT_EQ(std::bit_cast<uint32_t>(decoderPoint), std::bit_cast<uint32_t>(point)) << i;
                if (std::isnan(values[i])) {
                    ++missing;
                    EXPECT_TRUE(std::isnan(decoded[i])) << i;
                    EXPECT_TRUE(std::isnan(point)) << i;
                    continue;
                }
                const size_t owner = layout.index(uint32_t(iLat / 8), uint32_t(iR / 8), uint32_t(iLon / 8));
                const double bound = uint16ErrorBound(bounds[2 * owner], bounds[2 * owner + 1], true);
                EXPECT_GT(bound, (bounds[2 * owner + 1] - bounds[2 * owner]) / 131070.0);  // 65534 levels, not 65535
                EXPECT_LE(std::abs(double(decoded[i]) - values[i]), bound * (1 + 1e-6) + 1e-5) << i;
                EXPECT_EQ(point, decoded[i]) << i;
            }
    EXPECT_GT(missing, 10 * g.nR() * g.nLon());
    EXPECT_EQ(missing, size_t(std::count_if(values.begin(), values.end(), [](float v) { return std::isnan(v); })));

    // The shell means of the stored values, one shell decoded at a time: those of the decoded array,
    // bit for bit (a writer keeps them for readers that decode the array), on every shell.
    const std::vector<double> whole = shellMeans(g, decoded), byShell = shellMeansOfUint16(g, layout, encoded, bounds, true);
    ASSERT_EQ(byShell.size(), g.nR());
    for (size_t iR = 0; iR < g.nR(); ++iR)
        EXPECT_EQ(std::bit_cast<uint64_t>(byShell[iR]), std::bit_cast<uint64_t>(whole[iR])) << "shell " << iR;
    EXPECT_NE(shellMeans(g, values)[3], whole[3]) << "the means of the exact values: nothing was decoded";
}

}  // namespace
}  // namespace raypc::dataset
