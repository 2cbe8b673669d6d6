#include "preprocess/difference.h"

#include "core/error.h"
#include "core/error_kinds.h"
#include "core/json_input.h"
#include "core/strings.h"
#include "dataset/dataset_format.h"
#include "grid/regrid.h"
#include "grid/test_util.h"

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include <cmath>
#include <fstream>
#include <limits>
#include <random>

namespace raypc::preprocess {
namespace {

using testing::centredGrid;
using testing::TempDir;
namespace fs = std::filesystem;

// Snapshots in memory as a source of steps: datasets with known values for the difference to read.
class MemorySource final : public StepSource {
public:
    MemorySource(std::vector<grid::Snapshot> steps) : m_steps(std::move(steps)) {}
    size_t stepCount() const override { return m_steps.size(); }
    std::string path(size_t s) const override { return "memory step " + std::to_string(s); }
    std::string label(size_t s) const override { return "memory" + std::to_string(s); }
    io::FileHeader plan() override
    {
        io::FileHeader h;
        h.grid = m_steps.front().grid;
        for (const grid::Field& f : m_steps.front().fields)
            h.variables.push_back({f.name, f.name, f.units, ""});
        return h;
    }
    grid::Snapshot read(size_t s) const override { return m_steps[s]; }
    nlohmann::json fingerprint(size_t s) const override { return {{"step", s}}; }

private:
    std::vector<grid::Snapshot> m_steps;
};

std::vector<float> randomValues(size_t n, unsigned seed)
{
    std::mt19937 rng(seed);
    std::uniform_real_distribution<float> u(-100, 100);
    std::vector<float> v(n);
    for (float& x : v)
        x = u(rng);
    return v;
}

// A float32 dataset (exact values) of `steps` steps of `names` with random values, at `timesMyr`.
fs::path writeDataset(const fs::path& dir, const grid::SphericalGrid& g, const std::vector<std::string>& names,
                      int steps, unsigned seed, std::vector<double> timesMyr = {}, const std::string& units = "K")
{
    std::vector<grid::Snapshot> snaps;
    for (int s = 0; s < steps; ++s) {
        grid::Snapshot snap;
        snap.grid = g;
        for (size_t v = 0; v < names.size(); ++v)
            snap.fields.push_back({names[v], units, randomValues(g.cellCount(), seed * 1000 + unsigned(s * 10 + v))});
        snaps.push_back(std::move(snap));
    }
    MemorySource source(std::move(snaps));
    PreprocessOptions options;
    options.quiet = true;
    options.encoding = dataset::ValueEncoding::Float32;
    options.pathlines.enabled = false;
    options.sampleRows = 100;
    options.timesMyr = std::move(timesMyr);
    preprocess(source, dir, options);
    return dir;
}

std::vector<float> level0(const fs::path& dir, int step, const std::string& name)
{
    const auto d = dataset::Dataset::open(dir);
    const auto volume = d->load(step, 0);
    const float* v = volume->values(size_t(d->variableIndex(name)));
    return {v, v + volume->grid().cellCount()};
}

DifferenceRequest pair(const fs::path& a, const fs::path& b = {}, std::vector<std::string> variables = {})
{
    DifferenceRequest request;
    request.a = a;
    request.b = b;
    request.variables = std::move(variables);
    return request;
}

std::string errorOf(const DifferenceRequest& request)
{
    try {
        DifferenceSource source(request);
    } catch (const Error& e) {
        return e.what();
    }
    return "no error";
}

TEST(Difference, SameGridIsPointForPoint)
{
    TempDir tmp("difference-same");
    const grid::SphericalGrid g = centredGrid(7, 5, 9);
    const fs::path a = writeDataset(tmp / "a.ds", g, {"temperature", "density"}, 2, 1);
    const fs::path b = writeDataset(tmp / "b.ds", g, {"density", "temperature", "other"}, 2, 2);
    DifferenceSource source(pair(a, b));
    // The stored variables both have, in A's order.
    EXPECT_EQ(source.variables(), (std::vector<std::string>{"temperature", "density"}));
    EXPECT_EQ(source.coveredFraction(), 1.0);
    ASSERT_EQ(source.stepCount(), 2u);
    const grid::Snapshot snap = source.read(1);
    ASSERT_TRUE(snap.grid.sameAs(g));
    ASSERT_EQ(snap.fields.size(), 2u);
    for (const grid::Field& f : snap.fields) {
        const auto va = level0(a, 1, f.name), vb = level0(b, 1, f.name);
        ASSERT_EQ(f.values.size(), va.size());
        for (size_t i = 0; i < va.size(); ++i)
            ASSERT_EQ(f.values[i], va[i] - vb[i]) << f.name << " " << i;
    }
    EXPECT_NE(source.plan().variables[0].longName.find("temperature of a.ds − b.ds"), std::string::npos);
}

TEST(Difference, OtherGridGoesThroughRegridAndMissingStaysMissing)
{
    TempDir tmp("difference-other");
    const grid::SphericalGrid ga = centredGrid(8, 6, 12);
    // B: another grid whose shells stop halfway through A's: the rest of D is missing.
    grid::SphericalGrid gb = centredGrid(11, 4, 17);
    const double mid = 0.5 * (ga.rKm.front() + ga.rKm.back());
    for (size_t i = 0; i < gb.nR(); ++i)
        gb.rKm[i] = ga.rKm.front() + i * (mid - ga.rKm.front()) / (gb.nR() - 1);
    const fs::path a = writeDataset(tmp / "a.ds", ga, {"temperature"}, 1, 3);
    const fs::path b = writeDataset(tmp / "b.ds", gb, {"temperature"}, 1, 4);
    DifferenceSource source(pair(a, b));
    EXPECT_GT(source.coveredFraction(), 0.0);
    EXPECT_LT(source.coveredFraction(), 1.0);
    const grid::Snapshot snap = source.read(0);
    const auto va = level0(a, 0, "temperature"), vb = level0(b, 0, "temperature");
    const std::vector<float> bOnA = grid::regrid(gb, vb.data(), ga);
    size_t missing = 0, present = 0;
    for (size_t i = 0; i < va.size(); ++i) {
        const float d = snap.fields[0].values[i];
        if (std::isnan(bOnA[i])) {
            ASSERT_TRUE(std::isnan(d)) << i;
            ++missing;
        } else {
            ASSERT_EQ(d, va[i] - bOnA[i]) << i;
            ++present;
        }
    }
    EXPECT_GT(missing, 0u);
    EXPECT_GT(present, 0u);
}

TEST(Difference, StepDifferences)
{
    TempDir tmp("difference-steps");
    const grid::SphericalGrid g = centredGrid(5, 4, 8);
    const fs::path a = writeDataset(tmp / "a.ds", g, {"temperature"}, 4, 5, {10, 12, 15, 19});
    DifferenceRequest request = pair(a);
    request.stepLag = 2;
    DifferenceSource source(request);
    ASSERT_EQ(source.stepCount(), 2u);
    EXPECT_EQ(source.timesMyr(), (std::vector<double>{15, 19}));
    for (int t = 2; t < 4; ++t) {
        const auto now = level0(a, t, "temperature"), before = level0(a, t - 2, "temperature");
        const grid::Snapshot snap = source.read(size_t(t - 2));
        for (size_t i = 0; i < now.size(); ++i)
            ASSERT_EQ(snap.fields[0].values[i], now[i] - before[i]);
    }
    request.stepLag = 4;
    EXPECT_EQ(errorOf(request), "--steps: 4 out of range 1..3 (a.ds has 4 steps)");
}

TEST(Difference, Refusals)
{
    TempDir tmp("difference-refusals");
    const grid::SphericalGrid g = centredGrid(5, 4, 8);
    const fs::path a = writeDataset(tmp / "a.ds", g, {"temperature", "density"}, 2, 1, {0, 2});
    const fs::path other = writeDataset(tmp / "other.ds", g, {"vs"}, 2, 2, {0, 2});
    const fs::path three = writeDataset(tmp / "three.ds", g, {"temperature"}, 3, 3, {0, 1, 2});
    const fs::path late = writeDataset(tmp / "late.ds", g, {"temperature"}, 2, 4, {0, 3});
    // Radii entirely above A's: no overlap.
    grid::SphericalGrid above = g;
    for (double& r : above.rKm)
        r += 10000;
    const fs::path far = writeDataset(tmp / "far.ds", above, {"temperature"}, 2, 5, {0, 2});

    EXPECT_NE(errorOf(pair(a, far)).find("do not overlap"), std::string::npos) << errorOf(pair(a, far));
    EXPECT_NE(errorOf(pair(a, other)).find("a.ds and other.ds have no stored variable in common"), std::string::npos);
    DifferenceRequest named = pair(a, three, {"density"});
    EXPECT_NE(errorOf(named).find("variable 'density': three.ds has no such variable"), std::string::npos)
        << errorOf(named);
    EXPECT_THROW(DifferenceSource{named}, UnknownNameError);
    DifferenceRequest computed = pair(a, three, {"temperature anomaly"});
    EXPECT_NE(errorOf(computed).find("is computed from 'temperature' when a.ds is read"), std::string::npos)
        << errorOf(computed);
    EXPECT_NE(errorOf(pair(a, three)).find("a.ds has 2 steps and three.ds has 3"), std::string::npos);
    // By time: three.ds has steps at 0, 1, 2 Myr, so A's 0 and 2 Myr find theirs; late.ds has none at 2.
    DifferenceRequest byTime = pair(a, three);
    byTime.match = StepMatch::Time;
    DifferenceSource paired(byTime);
    EXPECT_EQ(paired.label(1), "a.ds:1 − three.ds:2");
    byTime.b = late;
    EXPECT_NE(errorOf(byTime).find("late.ds has no step at a.ds's step 1 (2 Myr): its nearest is step 1 at 3 Myr"),
              std::string::npos)
        << errorOf(byTime);
    EXPECT_NE(errorOf(pair(a)).find("give a dataset B"), std::string::npos);
    const fs::path celsius = writeDataset(tmp / "celsius.ds", g, {"temperature"}, 2, 6, {0, 2}, "degC");
    EXPECT_NE(errorOf(pair(a, celsius)).find("variable 'temperature' is in K in a.ds but in degC in celsius.ds"),
              std::string::npos)
        << errorOf(pair(a, celsius));
}

TEST(Difference, DatasetThroughThePipelineResumesAndRefusesOtherOutputs)
{
    TempDir tmp("difference-dataset");
    const grid::SphericalGrid g = centredGrid(6, 4, 10);
    const fs::path a = writeDataset(tmp / "a.ds", g, {"temperature"}, 2, 1);
    const fs::path b = writeDataset(tmp / "b.ds", g, {"temperature"}, 2, 2);
    PreprocessOptions options;
    options.quiet = true;
    // A − A is zero everywhere, also quantised to u16.
    preprocessDifference(pair(a, a), tmp / "zero.ds", options);
    for (int s = 0; s < 2; ++s)
        for (float v : level0(tmp / "zero.ds", s, "temperature"))
            ASSERT_EQ(v, 0.0f);
    const fs::path d = tmp / "d.ds";
    EXPECT_EQ(preprocessDifference(pair(a, b), d, options).stepsWritten, 2);
    const nlohmann::json manifest = parseJsonInput(readFile(d / dataset::format::kManifest), "dataset.json");
    EXPECT_EQ(manifest.at("difference").at("variables"), nlohmann::json::array({"temperature"}));
    EXPECT_EQ(manifest.at("difference").at("match"), "index");
    EXPECT_NE(manifest.at("no_pathlines").get<std::string>().find("difference"), std::string::npos);
    EXPECT_EQ(manifest.at("inputs").at(1), "a.ds:1 − b.ds:1");
    // A rerun resumes: nothing changed, nothing written.
    const PreprocessSummary again = preprocessDifference(pair(a, b), d, options);
    EXPECT_EQ(again.stepsWritten, 0);
    EXPECT_EQ(again.stepsSkipped, 2);
    // Another difference into it is refused, and so is one into a dataset that is not a difference.
    try {
        preprocessDifference(pair(b, a), d, options);
        ADD_FAILURE() << "no error";
    } catch (const Error& e) {
        EXPECT_NE(std::string(e.what()).find("holds a dataset made with a different 'difference'"), std::string::npos)
            << e.what();
    }
    EXPECT_THROW(preprocessDifference(pair(a, b), b, options), Error);
    EXPECT_EQ(level0(b, 0, "temperature").size(), g.cellCount());  // b.ds untouched
}

}  // namespace
}  // namespace raypc::preprocess
