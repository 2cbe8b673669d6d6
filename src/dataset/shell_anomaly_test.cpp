// Shell anomalies ("X anomaly", "X anomaly %"): which variables get them, their values against the
// definition computed here independently (dual-cell areas from the sines of the cells' lat edges and
// the lon spacing, not SphericalGrid::volumeFactors), on every level, in the sample and the brick
// bounds, and that a dataset written before them still opens.
#include "dataset/shell_anomaly.h"

#include "core/atomic_file.h"
#include "core/spherical.h"
#include "dataset/bricks.h"
#include "dataset/dataset.h"
#include "dataset/dataset_format.h"
#include "io/netcdf_reader.h"
#include "preprocess/preprocess.h"
#include "grid/test_util.h"

#include <gtest/gtest.h>

#include <bit>
#include <nlohmann/json.hpp>

#include <cmath>
#include <fstream>
#include <limits>
#include <string>
#include <vector>

namespace raypc::dataset {
namespace {

namespace fs = std::filesystem;
using nlohmann::json;

std::vector<std::string> namesOf(const std::vector<ShellAnomalyVariable>& vars)
{
    std::vector<std::string> out;
    for (const auto& v : vars)
        out.push_back(v.name);
    return out;
}

TEST(ShellAnomaly, EveryStoredScalarButTheVelocityAndAnomaliesGetsOne)
{
    // The contest's variables: its own temperature anomaly stays; the velocity, its derived
    // quantities and the anomalies get none.
    const std::vector<BaseVariable> contest = {
        {"temperature", "K"}, {"vx", "m/s"}, {"vy", "m/s"}, {"vz", "m/s"}, {"thermal conductivity", "W/m/K"},
        {"thermal expansivity", "1/K"}, {"temperature anomaly", "K"}, {"spin transition-induced density anomaly", "kg/m^3"},
        {"radial velocity", "cm/yr", true}, {"velocity magnitude", "cm/yr", true}};
    const auto vars = shellAnomalyVariables(contest);
    EXPECT_EQ(namesOf(vars), (std::vector<std::string>{"thermal conductivity anomaly", "thermal expansivity anomaly",
                                                       "temperature anomaly %", "thermal conductivity anomaly %",
                                                       "thermal expansivity anomaly %"}));
    EXPECT_EQ(vars[1].units, "1/K");
    EXPECT_EQ(vars[1].of, (ShellAnomalyOf{5, ShellAnomalyKind::Difference}));
    EXPECT_EQ(vars[2].units, "%");
    EXPECT_EQ(vars[2].of, (ShellAnomalyOf{0, ShellAnomalyKind::Percent}));

    // ASPECT's T: its anomaly is the temperature anomaly, not also "T anomaly".
    const std::vector<BaseVariable> aspect = {{"T", "K"}, {"vx", "m/s"}, {"vy", "m/s"}, {"vz", "m/s"}, {"viscosity", "Pa s"}};
    EXPECT_EQ(namesOf(shellAnomalyVariables(aspect)),
              (std::vector<std::string>{"temperature anomaly", "viscosity anomaly", "temperature anomaly %",
                                        "viscosity anomaly %"}));

    // A tomography model.
    const std::vector<BaseVariable> vs = {{"vs", "km/s"}};
    const auto tomography = shellAnomalyVariables(vs);
    EXPECT_EQ(namesOf(tomography), (std::vector<std::string>{"vs anomaly", "vs anomaly %"}));
    EXPECT_EQ(tomography[0].units, "km/s");

    EXPECT_EQ(parseShellAnomalyKind(shellAnomalyKindName(ShellAnomalyKind::Percent)), ShellAnomalyKind::Percent);
    EXPECT_FALSE(parseShellAnomalyKind("anomaly percent"));
}

// The area of each grid point's dual cell on its shell, up to a constant: lat edges halfway between
// rows (the outermost half a spacing out, clamped to the poles), lon edges halfway between columns.
double cellArea(const grid::SphericalGrid& g, size_t iLat, size_t iLon)
{
    const auto& lat = g.latDeg;
    const size_t n = lat.size();
    const double lo = iLat > 0 ? (lat[iLat - 1] + lat[iLat]) / 2 : std::max(-90.0, lat[0] - (n > 1 ? (lat[1] - lat[0]) / 2 : 90.0));
    const double hi = iLat + 1 < n ? (lat[iLat] + lat[iLat + 1]) / 2
                                   : std::min(90.0, lat[n - 1] + (n > 1 ? (lat[n - 1] - lat[n - 2]) / 2 : 90.0));
    const auto& lon = g.lonDeg;
    const size_t m = lon.size();
    const double prev = iLon > 0 ? lon[iLon - 1] : lon[m - 1] - 360.0;
    const double next = iLon + 1 < m ? lon[iLon + 1] : lon[0] + 360.0;
    return (std::sin(degToRad(hi)) - std::sin(degToRad(lo))) * (next - prev) / 2;
}

// The definition, in double: the area-weighted mean of the finite values of each shell.
std::vector<double> expectedShellMeans(const grid::SphericalGrid& g, const float* values)
{
    std::vector<double> means(g.nR());
    for (size_t iR = 0; iR < g.nR(); ++iR) {
        double sum = 0, area = 0;
        for (size_t a = 0; a < g.nLat(); ++a)
            for (size_t c = 0; c < g.nLon(); ++c) {
                const float x = values[g.index(a, iR, c)];
                if (std::isfinite(x)) {
                    sum += cellArea(g, a, c) * x;
                    area += cellArea(g, a, c);
                }
            }
        means[iR] = area > 0 ? sum / area : std::numeric_limits<double>::quiet_NaN();
    }
    return means;
}

TEST(ShellAnomaly, ShellMeansAreAreaWeightedAndLeaveOutMissingValues)
{
    const grid::SphericalGrid g = testing::centredGrid(6, 3, 8);
    // More weight at the equator than at the poles: a field of lat alone has a mean below its
    // plain average where it grows toward the poles.
    std::vector<float> v = testing::fillGrid(g, [&](size_t a, size_t r, size_t c) {
        return 1000.0 * double(r + 1) + std::abs(g.latDeg[a]) + 0.5 * double(c);
    });
    // Shell 1 loses two values; shell 2 has none.
    v[g.index(0, 1, 3)] = std::numeric_limits<float>::quiet_NaN();
    v[g.index(4, 1, 0)] = std::numeric_limits<float>::quiet_NaN();
    for (size_t a = 0; a < g.nLat(); ++a)
        for (size_t c = 0; c < g.nLon(); ++c)
            v[g.index(a, 2, c)] = std::numeric_limits<float>::quiet_NaN();
    const std::vector<double> expected = expectedShellMeans(g, v.data());
    const std::vector<double> got = shellMeans(g, v);
    ASSERT_EQ(got.size(), 3u);
    for (size_t r = 0; r < 2; ++r)
        EXPECT_NEAR(got[r], expected[r], 1e-9 * std::abs(expected[r]));
    EXPECT_LT(got[0], 1000.0 + 45.0 + 0.5 * 3.5);  // below the plain average of |lat| (45) and lon part
    EXPECT_TRUE(std::isnan(got[2]));
    EXPECT_TRUE(shellMeansPositive(got));  // the missing shell does not count

    std::vector<float> out(g.cellCount());
    computeShellAnomaly(g, v, got, ShellAnomalyKind::Percent, out);
    const size_t i = g.index(2, 0, 5);
    EXPECT_NEAR(out[i], 100.0 * (v[i] - expected[0]) / expected[0], 1e-4);
    EXPECT_TRUE(std::isnan(out[g.index(0, 1, 3)]));  // a missing value stays missing
    EXPECT_TRUE(std::isnan(out[g.index(3, 2, 3)]));  // and so does a shell without values

    std::vector<double> mixed = got;
    mixed[1] = -1;
    EXPECT_FALSE(shellMeansPositive(mixed));
    mixed[1] = 0;
    EXPECT_FALSE(shellMeansPositive(mixed));
}

// shellMeans sums four shells side by side: each mean has the bits of shellMean's of that shell
// alone, with missing values and a shell count that is no multiple of four.
TEST(ShellAnomaly, ShellMeansSideBySideAreEachShellsAlone)
{
    const grid::SphericalGrid g = testing::centredGrid(9, 7, 23);
    std::vector<float> v = testing::fillGrid(g, [&](size_t a, size_t r, size_t c) {
        return 700.0 + 90.0 * std::cos(0.37 * double(a * 13 + r * 3 + c));
    });
    v[g.index(4, 5, 6)] = std::numeric_limits<float>::quiet_NaN();
    for (size_t a = 0; a < g.nLat(); ++a)
        for (size_t c = 0; c < g.nLon(); ++c)
            v[g.index(a, 6, c)] = std::numeric_limits<float>::quiet_NaN();
    const auto w = g.volumeFactors();
    const std::vector<double> means = shellMeans(g, v);
    for (size_t r = 0; r < g.nR(); ++r) {
        const double alone = shellMean(w, v.data() + g.index(0, r, 0), g.nR() * g.nLon());
        EXPECT_EQ(std::bit_cast<uint64_t>(means[r]), std::bit_cast<uint64_t>(alone)) << "shell " << r;
    }
}

// computeShellAnomaly works a row at a time in a vectorised loop: every value has the bits of
// shellAnomalyValue's, both kinds, with missing values and values beyond float32 (its infinity where
// a plain conversion would round down to the largest float).
TEST(ShellAnomaly, EveryValueIsShellAnomalyValues)
{
    const grid::SphericalGrid g = testing::centredGrid(7, 5, 19);
    std::vector<float> v = testing::fillGrid(g, [&](size_t a, size_t r, size_t c) {
        return 800.0 + 50.0 * std::sin(0.3 * double(a * 19 + r * 5 + c)) + double(r);
    });
    v[g.index(2, 1, 4)] = std::numeric_limits<float>::quiet_NaN();
    v[g.index(3, 2, 7)] = std::numeric_limits<float>::max();
    v[g.index(3, 2, 8)] = -std::numeric_limits<float>::max();
    std::vector<double> means = shellMeans(g, v);
    means[2] = -3.0e38;  // shell 2: max − mean and −max − mean beyond float32, and just beyond
    means[3] = std::nextafter(0.0, 1.0);
    std::vector<float> out(g.cellCount());
    for (const ShellAnomalyKind kind : {ShellAnomalyKind::Difference, ShellAnomalyKind::Percent}) {
        computeShellAnomaly(g, v, means, kind, out);
        for (size_t a = 0; a < g.nLat(); ++a)
            for (size_t r = 0; r < g.nR(); ++r)
                for (size_t c = 0; c < g.nLon(); ++c) {
                    const size_t i = g.index(a, r, c);
                    const float expected = shellAnomalyValue(v[i], means[r], kind);
                    EXPECT_EQ(std::bit_cast<uint32_t>(out[i]), std::bit_cast<uint32_t>(expected))
                        << out[i] << " " << expected << " at " << a << " " << r << " " << c;
                }
    }
}

// Bricks skipped by a selection of an anomaly are skipped by the bounds made from the base's: those
// hold every anomaly value of the brick's points (both kinds, negative means, missing values), and
// are finite where the brick has a value (so that they can skip it).
TEST(ShellAnomaly, BrickBoundsFromTheBasesHoldEveryValueOfTheBrick)
{
    const grid::SphericalGrid g = testing::centredGrid(13, 11, 18);
    std::vector<float> v = testing::fillGrid(g, [&](size_t a, size_t r, size_t c) {
        return (r == 4 ? -1.0 : 1.0) * (500.0 + 40.0 * std::sin(0.7 * double(a * 31 + r * 7 + c * 3))) + double(r);
    });
    for (size_t c = 0; c < g.nLon(); ++c)
        v[g.index(12, 10, c)] = std::numeric_limits<float>::quiet_NaN();  // a ring without values
    v[g.index(3, 3, 3)] = std::numeric_limits<float>::quiet_NaN();
    const grid::BrickLayout layout = grid::BrickLayout::forGrid(g, 4);
    std::vector<float> baseBounds(2 * layout.brickCount()), own(baseBounds.size()), bounds(baseBounds.size()),
        anomaly(g.cellCount());
    computeBrickBounds(g, layout, v, baseBounds);
    const std::vector<double> means = shellMeans(g, v);
    for (const ShellAnomalyKind kind : {ShellAnomalyKind::Difference, ShellAnomalyKind::Percent}) {
        computeShellAnomaly(g, v, means, kind, anomaly);
        computeBrickBounds(g, layout, anomaly, own);
        shellAnomalyBrickBounds(g, layout, baseBounds, means, kind, bounds);
        for (size_t b = 0; b < layout.brickCount(); ++b) {
            EXPECT_LE(bounds[2 * b], own[2 * b]) << "brick " << b;
            EXPECT_GE(bounds[2 * b + 1], own[2 * b + 1]) << "brick " << b;
            EXPECT_TRUE(std::isfinite(bounds[2 * b]) && std::isfinite(bounds[2 * b + 1])) << "brick " << b;
        }
    }
}

// The contest fixture preprocessed (float32 and u16), read back.
class ComputedVariables : public ::testing::Test {
protected:
    static void SetUpTestSuite()
    {
        s_dir = std::make_unique<testing::TempDir>("shell-anomaly");
        const auto files = io::listSnapshotFiles({testing::contestLayoutDir()});
        for (const auto encoding : {ValueEncoding::Float32, ValueEncoding::Uint16}) {
            preprocess::PreprocessOptions o;
            o.quiet = true;
            o.sampleRows = 500;
            o.encoding = encoding;
            o.pathlines.enabled = false;
            preprocess::preprocess(files, s_dir->path() / std::string(encodingName(encoding)), o);
        }
    }
    static void TearDownTestSuite() { s_dir.reset(); }
    static fs::path dir(ValueEncoding e) { return s_dir->path() / std::string(encodingName(e)); }
    static std::unique_ptr<testing::TempDir> s_dir;
};
std::unique_ptr<testing::TempDir> ComputedVariables::s_dir;

TEST_F(ComputedVariables, TheManifestListsThemAsComputedAndNotStored)
{
    const auto ds = Dataset::open(dir(ValueEncoding::Float32));
    const int anomaly = ds->variableIndex("thermal conductivity anomaly");
    const int percent = ds->variableIndex("temperature anomaly %");  // of the temperature
    const int base = ds->variableIndex("thermal conductivity");
    ASSERT_GE(anomaly, 0);
    ASSERT_GE(percent, 0);
    EXPECT_EQ(ds->variables()[size_t(percent)].computed,
              (ShellAnomalyOf{size_t(ds->variableIndex("temperature")), ShellAnomalyKind::Percent}));
    // The fixture's conductivity is -1e-3 times the temperature anomaly: some shell mean is not
    // positive, so its percentage is not offered.
    bool someNotPositive = false;
    for (int step = 0; step < int(ds->steps().size()); ++step) {
        const auto vol = ds->load(step, 0);
        for (double m : expectedShellMeans(vol->grid(), vol->values(size_t(base))))
            someNotPositive = someNotPositive || !(m > 0);
    }
    EXPECT_TRUE(someNotPositive);
    EXPECT_EQ(ds->variableIndex("thermal conductivity anomaly %"), -1);
    EXPECT_EQ(ds->variableIndex("thermal expansivity anomaly"), anomaly + 1);
    const VariableInfo& a = ds->variables()[size_t(anomaly)];
    EXPECT_FALSE(a.stored);
    EXPECT_TRUE(a.derived);
    EXPECT_EQ(a.source, "thermal conductivity");
    EXPECT_EQ(a.units, ds->variables()[size_t(base)].units);
    EXPECT_EQ(a.computed, (ShellAnomalyOf{size_t(base), ShellAnomalyKind::Difference}));
    EXPECT_EQ(ds->variables()[size_t(percent)].units, "%");
    // No arrays of them.
    for (const auto& entry : fs::recursive_directory_iterator(dir(ValueEncoding::Float32)))
        EXPECT_EQ(entry.path().filename().string().find("anomaly_"), std::string::npos) << entry.path();
    const json manifest = json::parse(std::ifstream(dir(ValueEncoding::Float32) / "dataset.json"));
    EXPECT_EQ(manifest["variables"][size_t(anomaly)]["stored"], false);
    EXPECT_EQ(manifest["variables"][size_t(base)]["stored"], true);
    EXPECT_EQ(manifest["variables"][size_t(percent)]["kind"], "anomaly %");
}

TEST_F(ComputedVariables, ValuesOnEveryLevelAreTheirDefinitionAndBoundsHoldThem)
{
    for (const auto encoding : {ValueEncoding::Float32, ValueEncoding::Uint16}) {
        const auto ds = Dataset::open(dir(encoding));
        size_t checked = 0;
        for (int step : {0, int(ds->steps().size()) - 1})
            for (int level = 0; level < kLevelCount; ++level) {
                const auto vol = ds->load(step, level);
                const auto& g = vol->grid();
                ASSERT_EQ(vol->variableCount(), ds->variables().size());
                for (size_t v = 0; v < ds->variables().size(); ++v) {
                    const auto& of = ds->variables()[v].computed;
                    if (!of)
                        continue;
                    EXPECT_EQ(*vol->computedFrom(v), *of);
                    const float* x = vol->values(of->base);  // the level's own (decoded) values
                    const std::vector<double> means = expectedShellMeans(g, x);
                    const float* got = vol->values(v);
                    const float* bounds = vol->brickBounds(v);
                    const auto& layout = vol->bricks();
                    double scale = 0;
                    for (size_t i = 0; i < g.cellCount(); ++i)
                        scale = std::max(scale, std::abs(double(got[i])));
                    for (size_t a = 0; a < g.nLat(); ++a)
                        for (size_t r = 0; r < g.nR(); ++r)
                            for (size_t c = 0; c < g.nLon(); ++c) {
                                const size_t i = g.index(a, r, c);
                                const double d = double(x[i]) - means[r];
                                const double want = of->kind == ShellAnomalyKind::Difference ? d : 100.0 * d / means[r];
                                ASSERT_NEAR(got[i], want, 1e-5 * scale + 1e-30)
                                    << ds->variables()[v].name << " level " << level << " point " << i;
                                const size_t b = layout.index(uint32_t(a / layout.size), uint32_t(r / layout.size),
                                                              uint32_t(c / layout.size));
                                ASSERT_LE(bounds[2 * b], got[i]);
                                ASSERT_GE(bounds[2 * b + 1], got[i]);
                                ++checked;
                            }
                    // Each shell's anomaly has zero area-weighted mean.
                    if (of->kind == ShellAnomalyKind::Difference) {
                        for (double m : expectedShellMeans(g, got))
                            EXPECT_NEAR(m, 0.0, 1e-5 * scale);
                    }
                }
            }
        EXPECT_GT(checked, 0u);
    }
}

TEST_F(ComputedVariables, LevelZeroAndTheSampleAgreeWithTheExactStepStatistics)
{
    const auto f32 = Dataset::open(dir(ValueEncoding::Float32));
    const auto u16 = Dataset::open(dir(ValueEncoding::Uint16));
    const int v = f32->variableIndex("temperature anomaly %");
    ASSERT_GE(v, 0);
    for (int step = 0; step < int(f32->steps().size()); ++step) {
        const auto exact = f32->load(step, 0);
        const auto coded = u16->load(step, 0);
        const auto& g = exact->grid();
        const VariableStats& st = f32->steps()[size_t(step)].stats[size_t(v)];
        float lo = INFINITY, hi = -INFINITY;
        for (size_t i = 0; i < g.cellCount(); ++i) {
            lo = std::min(lo, exact->values(size_t(v))[i]);
            hi = std::max(hi, exact->values(size_t(v))[i]);
        }
        // The manifest's statistics (from the exact values at preprocessing) are the float32 volume's.
        EXPECT_FLOAT_EQ(st.range.min, lo);
        EXPECT_FLOAT_EQ(st.range.max, hi);
        // The u16 volume's values lie within their error bound of the exact ones.
        for (size_t a = 0; a < g.nLat(); a += 3)
            for (size_t r = 0; r < g.nR(); r += 2)
                for (size_t c = 0; c < g.nLon(); c += 5) {
                    const size_t i = g.index(a, r, c);
                    EXPECT_LE(std::abs(coded->values(size_t(v))[i] - exact->values(size_t(v))[i]),
                              coded->errorBound(size_t(v), a, r, c) * 1.01 + 1e-4);
                }
        // The sample's column is the level-0 value at its grid point.
        const SampleTable sample = f32->loadSample(step, SampleColumns::Variables);
        const std::string cellsPath = (dir(ValueEncoding::Float32) / format::kSampleCells).string();
        const std::string bytes = readFile(cellsPath);
        ASSERT_EQ(bytes.size(), sample.rows * sizeof(uint32_t));
        const auto* cells = reinterpret_cast<const uint32_t*>(bytes.data());
        for (size_t row = 0; row < sample.rows; ++row)
            ASSERT_NEAR(sample.at(row, size_t(v)), exact->values(size_t(v))[cells[row]], 1e-4) << row;
    }
}

TEST_F(ComputedVariables, ADatasetWrittenBeforeThemOpensWithoutThem)
{
    testing::TempDir tmp("shell-anomaly-old");
    fs::copy(dir(ValueEncoding::Uint16), tmp / "ds", fs::copy_options::recursive);
    const fs::path manifestPath = tmp / "ds" / "dataset.json";
    json j = json::parse(std::ifstream(manifestPath));
    // As written before: every variable stored, no "stored", no shell means, no sample cells.
    json variables = json::array();
    size_t kept = 0;
    for (auto v : j["variables"])
        if (v["stored"] == true) {
            v.erase("stored");
            variables.push_back(v);
            ++kept;
        }
    ASSERT_LT(kept, j["variables"].size());
    j["variables"] = variables;
    for (auto& s : j["steps"]) {
        s["stats"].erase(s["stats"].begin() + std::ptrdiff_t(kept), s["stats"].end());
        s.erase("shell_means");
    }
    writeFileAtomic(manifestPath, j.dump());
    fs::remove(tmp / "ds" / format::kSampleCells);
    const auto ds = Dataset::open(tmp / "ds");
    EXPECT_EQ(ds->variables().size(), kept);
    EXPECT_EQ(ds->variableIndex("thermal conductivity anomaly"), -1);
    const auto vol = ds->load(0, 0);
    EXPECT_EQ(vol->variableCount(), kept);
    EXPECT_EQ(ds->loadSample(0).columns.size(), grid::coordinateInfos().size() + kept);

    // A computed variable whose source is no stored variable is refused, naming the field.
    json bad = json::parse(std::ifstream(dir(ValueEncoding::Uint16) / "dataset.json"));
    for (auto& v : bad["variables"])
        if (v["stored"] == false) {
            v["source"] = "no such variable";
            break;
        }
    writeFileAtomic(manifestPath, bad.dump());
    fs::copy(dir(ValueEncoding::Uint16) / format::kSampleCells, tmp / "ds" / format::kSampleCells);
    try {
        Dataset::open(tmp / "ds");
        ADD_FAILURE() << "opened";
    } catch (const Error& e) {
        EXPECT_NE(std::string(e.what()).find(".source: 'no such variable'"), std::string::npos) << e.what();
    }
}

}  // namespace
}  // namespace raypc::dataset
