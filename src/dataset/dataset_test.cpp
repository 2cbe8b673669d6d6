// Reading a dataset that is damaged or edited: every field of the manifest is checked at
// Dataset::open with one raypc::Error naming the manifest and the field; the arrays' sizes agree
// with the manifest; a float32 array holding NaN, Inf or a value beyond the step's range is refused
// when it is first read; a file cut short after it was mapped is an error, not SIGBUS.
#include "dataset/dataset.h"

#include "core/atomic_file.h"
#include "core/error.h"
#include "dataset/dataset_format.h"
#include "io/netcdf_reader.h"
#include "preprocess/preprocess.h"
#include "synth/synth.h"
#include "grid/test_util.h"

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include <array>
#include <bit>
#include <cmath>
#include <cstring>
#include <functional>
#include <limits>
#include <string>
#include <vector>

namespace raypc::dataset {
namespace {

using nlohmann::json;
using testing::TempDir;
namespace fs = std::filesystem;

// A small dataset of each encoding, written once by the project's own synth and preprocess
// (2 steps of a 12 x 9 x 16 grid, no pathlines), copied by each test that damages it.
class DamagedDatasets : public ::testing::Test {
protected:
    static void SetUpTestSuite()
    {
        s_dir = std::make_unique<TempDir>("damaged-datasets");
        synth::SynthOptions synth;
        synth.steps = 2;
        synth.nLat = 12;
        synth.nR = 9;
        synth.nLon = 16;
        synth::writeSyntheticSeries(s_dir->path() / "nc", synth);
        const auto files = io::listSnapshotFiles({s_dir->path() / "nc"});
        for (const auto encoding : {ValueEncoding::Uint16, ValueEncoding::Float32}) {
            preprocess::PreprocessOptions o;
            o.quiet = true;
            o.sampleRows = 200;
            o.encoding = encoding;
            o.pathlines.enabled = false;
            preprocess::preprocess(files, s_dir->path() / std::string(encodingName(encoding)), o);
        }
    }
    static void TearDownTestSuite() { s_dir.reset(); }

    // A fresh copy of the dataset of `encoding` in `tmp`/ds.
    static fs::path copy(const TempDir& tmp, ValueEncoding encoding = ValueEncoding::Uint16)
    {
        fs::copy(s_dir->path() / std::string(encodingName(encoding)), tmp / "ds", fs::copy_options::recursive);
        return tmp / "ds";
    }
    static std::unique_ptr<TempDir> s_dir;
};
std::unique_ptr<TempDir> DamagedDatasets::s_dir;

// The message of the raypc::Error `f` throws, or "" (a test failure) when it throws none.
std::string errorOf(const std::function<void()>& f)
{
    try {
        f();
    } catch (const Error& e) {
        return e.what();
    }
    ADD_FAILURE() << "no raypc::Error";
    return "";
}

struct Corruption {
    const char* what;
    std::function<void(json&)> change;
    const char* message;  // expected in the error after "<dir>/dataset.json: "
};

TEST_F(DamagedDatasets, EveryFieldOfTheManifestIsCheckedAtOpen)
{
    const float big = std::numeric_limits<float>::max();
    const std::vector<Corruption> table = {
        {"brick size 0 (an internal check aborted on it)", [](json& j) { j["brick_size"] = 0; },
         "brick_size: 0, expected an integer 1..64"},
        {"brick size too large", [](json& j) { j["brick_size"] = 100000; }, "brick_size: 100000, expected an integer 1..64"},
        {"brick size negative", [](json& j) { j["brick_size"] = -8; }, "brick_size: -8, expected an integer 1..64"},
        {"brick size not an integer", [](json& j) { j["brick_size"] = 8.5; }, "brick_size: 8.5, expected an integer"},
        {"brick size a string", [](json& j) { j["brick_size"] = "8"; }, "brick_size: \"8\", expected an integer"},
        {"no brick size", [](json& j) { j.erase("brick_size"); }, "brick_size: missing"},
        {"newer version", [](json& j) { j["version"] = 3; }, "format version 3, this raypc reads versions 1 to 2"},
        {"version a string", [](json& j) { j["version"] = "2"; }, "version: \"2\", expected an integer"},
        {"another format", [](json& j) { j["format"] = "other"; }, "format: \"other\", expected 'raypc-dataset'"},
        {"unknown encoding", [](json& j) { j["encoding"] = "u8"; }, "encoding 'u8' is unknown"},
        {"dt negative", [](json& j) { j["dt_myr"] = -2.0; }, "dt_myr: -2.0, expected a positive number"},
        {"lat of 500 degrees", [](json& j) { j["levels"][0]["lat_deg"][11] = 500.0; },
         "levels[0].lat_deg[11]: 500.0, expected a value within [-90, 90] degrees"},
        {"lat unsorted",
         [](json& j) { std::swap(j["levels"][0]["lat_deg"][3], j["levels"][0]["lat_deg"][4]); },
         "levels[0].lat_deg[4]:"},
        {"r negative", [](json& j) { j["levels"][0]["r_km"][0] = -10.0; },
         "levels[0].r_km[0]: -10.0, expected a positive radius in km"},
        {"r not ascending (inner radius above the outer)",
         [](json& j) { j["levels"][0]["r_km"][8] = 1000.0; }, "levels[0].r_km[8]: 1000.0 after"},
        {"lon beyond 360", [](json& j) { j["levels"][0]["lon_deg"][15] = 400.0; },
         "levels[0].lon_deg[15]: 400.0, expected a value within [0, 360) degrees"},
        {"lon a string", [](json& j) { j["levels"][0]["lon_deg"][2] = "nan"; },
         "levels[0].lon_deg[2]: \"nan\", expected a finite number"},
        {"a regional extent south of its north reversed",
         [](json& j) { j["levels"][0]["data_lat_deg"] = json::array({50.0, 10.0}); }, "levels[0].data_lat_deg: "},
        {"a regional extent of one value", [](json& j) { j["levels"][0]["data_lon_deg"] = json::array({10.0}); },
         "levels[0].data_lon_deg: "},
        {"a grid too small", [](json& j) { j["levels"][0]["lat_deg"] = json::array({0.0}); }, "levels[0]: grid 1x9x16"},
        {"a coarse level that is not level 0 merged",
         [](json& j) { j["levels"][1]["r_km"][0] = j["levels"][1]["r_km"][0].get<double>() + 1.0; },
         "levels[1].r_km[0]:"},
        {"a coarse level of another size", [](json& j) { j["levels"][2]["lat_deg"].erase(0); },
         "levels[2].lat_deg: 2 values, expected 3"},
        {"no levels", [](json& j) { j["levels"] = json::array(); }, "levels: 0 entries, expected 1..3"},
        {"levels not an array", [](json& j) { j["levels"] = 3; }, "levels: 3, expected an array"},
        {"variable without a name", [](json& j) { j["variables"][1]["name"] = ""; }, "variables[1].name: \"\""},
        {"two variables of one name", [](json& j) { j["variables"][1]["name"] = j["variables"][0]["name"]; },
         "variables[1].name:"},
        {"a file stem leaving the directory", [](json& j) { j["variables"][0]["file_stem"] = "../../x"; },
         "variables[0].file_stem: \"../../x\", expected a file name"},
        {"global min above max",
         [](json& j) { j["variables"][2]["global"]["min"] = j["variables"][2]["global"]["max"].get<double>() + 1; },
         "variables[2].global.max:"},
        {"global max beyond float32", [big](json& j) { j["variables"][0]["global"]["max"] = 2.0 * double(big); },
         "variables[0].global.max: 6.805646932770577e+38, expected a finite float32 value"},
        {"histogram too short", [](json& j) { j["variables"][0]["global"]["histogram"].erase(0); },
         "variables[0].global.histogram: 255 entries, expected 256..256"},
        {"histogram negative", [](json& j) { j["variables"][0]["global"]["histogram"][7] = -1.0; },
         "variables[0].global.histogram[7]: -1.0"},
        {"step index out of order", [](json& j) { j["steps"][1]["index"] = 5; }, "steps[1].index: 5"},
        {"times not increasing", [](json& j) { j["steps"][1]["time_myr"] = j["steps"][0]["time_myr"]; },
         "steps[1].time_myr:"},
        {"a step's stats for too few variables", [](json& j) { j["steps"][0]["stats"].erase(0); },
         "steps[0].stats:"},
        {"a step's shell means of another length", [](json& j) { j["steps"][1]["shell_means"]["temperature"].erase(0); },
         "steps[1].shell_means[\"temperature\"]: an array of 8 entries, expected an array of 9 shell means (one per radius)"},
        {"a level's shell means of another length",
         [](json& j) { j["steps"][0]["level_shell_means"][1]["temperature"].erase(0); },
         "steps[0].level_shell_means[1][\"temperature\"]: an array of 4 entries, expected an array of 5 shell means (one "
         "per radius of level 1)"},
        {"a level's shell means not an object", [](json& j) { j["steps"][0]["level_shell_means"][2] = 3; },
         "steps[0].level_shell_means[2]: 3, expected an object of shell means by variable name"},
        {"a level's shell mean a string", [](json& j) { j["steps"][0]["level_shell_means"][0]["temperature"][2] = "x"; },
         "steps[0].level_shell_means[0][\"temperature\"][2]: \"x\""},
        {"shell means of too few levels", [](json& j) { j["steps"][0]["level_shell_means"].erase(0); },
         "steps[0].level_shell_means:"},
        {"a step's range beyond the global one",
         [](json& j) {
             const double max = j["variables"][3]["global"]["max"].get<double>();
             j["steps"][1]["stats"][3]["max"] = max + std::abs(max) + 1.0;
         },
         "steps[1].stats[3]: range"},
        {"no steps", [](json& j) { j.erase("steps"); }, "steps: missing"},
        {"the manifest not an object", [](json& j) { j = json::array(); }, "the manifest: [], expected an object"},
        {"sample rows negative", [](json& j) { j["sample"]["rows"] = -1; }, "sample.rows: -1"},
    };
    TempDir tmp("manifest-fields");
    const fs::path ds = copy(tmp);
    const fs::path manifest = ds / format::kManifest;
    const std::string original = readFile(manifest);
    ASSERT_NO_THROW(Dataset::open(ds));
    for (const auto& c : table) {
        json j = json::parse(original);
        c.change(j);
        writeFileAtomic(manifest, j.dump());
        const std::string message = errorOf([&] { Dataset::open(ds); });
        EXPECT_NE(message.find(manifest.string() + ": " + c.message), std::string::npos)
            << c.what << ": " << message;
        EXPECT_EQ(message.find('\n'), std::string::npos) << c.what << ": " << message;
        EXPECT_LE(message.size(), 400u) << c.what;
    }
    writeFileAtomic(manifest, original);
    EXPECT_NO_THROW(Dataset::open(ds));
}

TEST_F(DamagedDatasets, ArraysWhoseSizeDisagreesWithTheManifestAreRefusedAtOpen)
{
    TempDir tmp("file-sizes");
    const fs::path ds = copy(tmp);
    const fs::path manifest = ds / format::kManifest;
    const std::string original = readFile(manifest);
    // The sample's row count disagrees with its files.
    size_t variables = 0;  // stored: the sample's file holds those (computed columns are made when read)
    for (const auto& v : Dataset::open(ds)->variables())
        variables += v.stored ? 1 : 0;
    json j = json::parse(original);
    j["sample"]["rows"] = 7;
    writeFileAtomic(manifest, j.dump());
    EXPECT_NE(errorOf([&] { Dataset::open(ds); })
                  .find(fmt::format("steps/0000/sample.f32: {} bytes, expected {}", 200 * variables * 4, 7 * variables * 4)),
              std::string::npos);
    writeFileAtomic(manifest, original);
    // A level array cut short, then missing (level 2 is 3 x 3 x 4 points).
    const fs::path values = format::encodedValuesFile(format::levelDir(format::stepDir(ds, 1), 2), "vx");
    fs::resize_file(values, fs::file_size(values) - 1);
    EXPECT_NE(errorOf([&] { Dataset::open(ds); }).find(values.string() + ": 71 bytes, expected 72 (levels[2]: 36 points of u16"),
              std::string::npos);
    fs::remove(values);
    EXPECT_NE(errorOf([&] { Dataset::open(ds); }).find(values.string() + ": No such file"), std::string::npos);
    fs::copy(format::encodedValuesFile(format::levelDir(format::stepDir(s_dir->path() / "u16", 1), 2), "vx"), values);
    EXPECT_NO_THROW(Dataset::open(ds));
    // Bounds files of another brick size than the manifest's (level 0: 6 x 5 x 8 bricks of 2 points, not 2 x 2 x 2 of 8).
    j = json::parse(original);
    j["brick_size"] = 2;
    writeFileAtomic(manifest, j.dump());
    EXPECT_NE(errorOf([&] { Dataset::open(ds); }).find(".bricks.f32: 64 bytes, expected 1920 (240 bricks of brick_size 2 in levels[0]"),
              std::string::npos);
    writeFileAtomic(manifest, original);
    EXPECT_NO_THROW(Dataset::open(ds));
}

// Writes `value` as the float32 at `index` of `file`.
void poke(const fs::path& file, size_t index, float value)
{
    std::string bytes = readFile(file);
    ASSERT_LE((index + 1) * sizeof(float), bytes.size());
    std::memcpy(bytes.data() + index * sizeof(float), &value, sizeof value);
    writeFileAtomic(file, bytes);
}

TEST_F(DamagedDatasets, Float32ValuesOutsideTheStepsRangeAreRefusedWhenRead)
{
    const int var = 2;
    for (const float bad : {std::nanf(""), std::numeric_limits<float>::infinity(), -std::numeric_limits<float>::infinity(),
                            3.4e38f}) {
        TempDir tmp("float32-values");
        const fs::path ds = copy(tmp, ValueEncoding::Float32);
        const auto dataset = Dataset::open(ds);
        const std::string stem = dataset->variables()[var].fileStem;
        const fs::path file = format::valuesFile(format::levelDir(format::stepDir(ds, 1), 0), stem);
        const size_t index = 12 * 16 + 3;  // lat row 1, r 3, lon 3 of the 12 x 9 x 16 grid
        poke(file, index, bad);
        const auto volume = dataset->load(1, 0);  // mapping reads nothing
        const std::string message = errorOf([&] { volume->values(var); });
        EXPECT_NE(message.find(file.string() + ": point 195 (lat"), std::string::npos) << message;
        EXPECT_NE(message.find(fmt::format("holds {}, expected a finite value within the step's range", bad)),
                  std::string::npos)
            << message;
        // A single read of that point too; another point reads.
        EXPECT_NE(errorOf([&] { dataset->load(1, 0)->value(var, 1, 3, 3); }).find("point 195"), std::string::npos);
        EXPECT_NO_THROW(dataset->load(1, 0)->value(var, 1, 3, 4));
        // The other variables and steps are whole.
        EXPECT_NO_THROW(volume->values(var + 1));
        EXPECT_NO_THROW(dataset->load(0, 0)->values(var));
    }
}

TEST_F(DamagedDatasets, BrickBoundsOfBothEncodingsAreCheckedAtLoad)
{
    for (const auto encoding : {ValueEncoding::Float32, ValueEncoding::Uint16})
        for (const float bad : {std::nanf(""), std::numeric_limits<float>::infinity(), 3.4e38f}) {
            TempDir tmp("bounds");
            const fs::path ds = copy(tmp, encoding);
            const fs::path file = format::boundsFile(format::levelDir(format::stepDir(ds, 0), 0), "temperature");
            poke(file, 2 * 1 + 1, bad);  // brick 1's max (level 0 has 2 x 2 x 2 bricks)
            const auto dataset = Dataset::open(ds);
            const std::string message = errorOf([&] { dataset->load(0, 0); });
            EXPECT_NE(message.find(file.string() + ": brick 1 has bounds"), std::string::npos) << message;
            EXPECT_NE(message.find("within the step's range"), std::string::npos) << message;
            EXPECT_NO_THROW(dataset->load(0, 1));
        }
}

TEST_F(DamagedDatasets, AFileCutShortAfterItWasMappedIsAnErrorNotSigbus)
{
    for (const auto encoding : {ValueEncoding::Uint16, ValueEncoding::Float32}) {
        TempDir tmp("cut-after-mapping");
        const fs::path ds = copy(tmp, encoding);
        const auto dataset = Dataset::open(ds);
        const auto volume = dataset->load(0, 0);
        volume->values(0);  // as a first frame shows one variable
        EXPECT_FALSE(volume->filesCutShort());
        const size_t var = static_cast<size_t>(dataset->variableIndex("vx"));
        const fs::path file = encoding == ValueEncoding::Uint16
                                  ? format::encodedValuesFile(format::levelDir(format::stepDir(ds, 0), 0), "vx")
                                  : format::valuesFile(format::levelDir(format::stepDir(ds, 0), 0), "vx");
        fs::resize_file(file, 0);  // `truncate -s 0` while served
        EXPECT_TRUE(volume->filesCutShort());
        const std::string message = errorOf([&] { volume->values(var); });
        EXPECT_NE(message.find(file.string() + ": 0 bytes now"), std::string::npos) << message;
        EXPECT_NE(errorOf([&] { volume->value(var, 0, 0, 0); }).find("cut short"), std::string::npos);
        EXPECT_NE(errorOf([&] {
                      float v = 0;
                      volume->valuesInBox(var, {0, 0, 0}, {1, 1, 1}, &v);
                  }).find("cut short"),
                  std::string::npos);
        EXPECT_NE(errorOf([&] { volume->touchPages(); }).find("cut short"), std::string::npos);
        EXPECT_NO_THROW(volume->values(0));  // what was read before stays
        EXPECT_NE(errorOf([&] { dataset->load(0, 0); }).find(file.string() + ": 0 bytes, expected"), std::string::npos);
    }
}

// Python's lazy arrays read boxes (valuesInBox, point by point from the mapped file); they must be
// what decoding the whole variable gives, bit for bit, on brick borders and at the lon seam too.
TEST_F(DamagedDatasets, ValuesInABoxAreTheWholeVariablesValuesBitForBit)
{
    for (const auto encoding : {ValueEncoding::Uint16, ValueEncoding::Float32}) {
        const auto dataset = Dataset::open(s_dir->path() / std::string(encodingName(encoding)));
        const grid::SphericalGrid& g = dataset->levels()[0].grid;
        const std::array<size_t, 3> begin{3, 2, 5}, end{10, 9, 16};
        for (size_t var = 0; var < dataset->variables().size(); ++var) {
            std::vector<float> box((end[0] - begin[0]) * (end[1] - begin[1]) * (end[2] - begin[2]));
            dataset->load(1, 0)->valuesInBox(var, begin, end, box.data());  // a fresh volume: nothing decoded
            const auto whole = dataset->load(1, 0);
            const float* all = whole->values(var);
            size_t i = 0;
            for (size_t iLat = begin[0]; iLat < end[0]; ++iLat)
                for (size_t iR = begin[1]; iR < end[1]; ++iR)
                    for (size_t iLon = begin[2]; iLon < end[2]; ++iLon, ++i)
                        ASSERT_EQ(std::bit_cast<uint32_t>(box[i]), std::bit_cast<uint32_t>(all[g.index(iLat, iR, iLon)]))
                            << dataset->variables()[var].name << " at " << iLat << ", " << iR << ", " << iLon;
        }
    }
}

// What reads a few points of many variables (a selection's features) reads them one by one: the
// values of values(), bit for bit, without decoding a u16 variable or computing a shell anomaly's
// array (its base's shell means are kept in the manifest: nothing is decoded).
TEST_F(DamagedDatasets, PointValuesAreTheWholeVariablesValuesBitForBitWithoutDecodingIt)
{
    for (const auto encoding : {ValueEncoding::Uint16, ValueEncoding::Float32}) {
        const auto dataset = Dataset::open(s_dir->path() / std::string(encodingName(encoding)));
        const grid::SphericalGrid& g = dataset->levels()[0].grid;
        bool computed = false;
        for (size_t var = 0; var < dataset->variables().size(); ++var) {
            const auto fresh = dataset->load(1, 0);
            const StepVolume::PointValues points = fresh->pointValues(var);
            const auto whole = dataset->load(1, 0);
            const float* all = whole->values(var);
            for (size_t iLat = 0; iLat < g.nLat(); ++iLat)
                for (size_t iR = 0; iR < g.nR(); ++iR)
                    for (size_t iLon = 0; iLon < g.nLon(); ++iLon) {
                        const size_t i = g.index(iLat, iR, iLon);
                        ASSERT_EQ(std::bit_cast<uint32_t>(points.at(i, iLat, iR, iLon)), std::bit_cast<uint32_t>(all[i]))
                            << dataset->variables()[var].name << " at " << iLat << ", " << iR << ", " << iLon;
                    }
            const ShellAnomalyOf* of = fresh->computedFrom(var);
            computed = computed || of;
            EXPECT_FALSE(fresh->valuesReady(var) && of) << dataset->variables()[var].name << ": no array computed";
            if (encoding == ValueEncoding::Uint16) {
                EXPECT_EQ(fresh->decodedBytes(), 0u) << dataset->variables()[var].name << ": decoded nothing";
            }
        }
        EXPECT_TRUE(computed) << "the dataset has shell anomalies";
    }
}

// The shell means the manifest keeps per step and level are those a volume computes from the level's
// stored values (decoded, for u16), bit for bit: the anomalies read with them are the same.
TEST_F(DamagedDatasets, KeptShellMeansAreThoseOfTheStoredValuesBitForBit)
{
    for (const auto encoding : {ValueEncoding::Uint16, ValueEncoding::Float32}) {
        const auto dataset = Dataset::open(s_dir->path() / std::string(encodingName(encoding)));
        size_t compared = 0;
        for (size_t s = 0; s < dataset->steps().size(); ++s) {
            const auto& kept = dataset->steps()[s].levelShellMeans;
            ASSERT_EQ(kept.size(), dataset->levels().size()) << "step " << s;
            for (size_t l = 0; l < kept.size(); ++l) {
                const grid::SphericalGrid& g = dataset->levels()[l].grid;
                const auto volume = dataset->load(int(s), int(l));
                for (size_t var = 0; var < dataset->variables().size(); ++var) {
                    const ShellAnomalyOf* of = dataset->variables()[var].computed ? &*dataset->variables()[var].computed
                                                                                  : nullptr;
                    if (!of)
                        continue;
                    const std::vector<double> computed = shellMeans(g, {volume->values(of->base), g.cellCount()});
                    ASSERT_EQ(kept[l][of->base].size(), g.nR());
                    for (size_t iR = 0; iR < g.nR(); ++iR, ++compared)
                        ASSERT_EQ(std::bit_cast<uint64_t>(kept[l][of->base][iR]), std::bit_cast<uint64_t>(computed[iR]))
                            << encodingName(encoding) << " step " << s << " level " << l << " "
                            << dataset->variables()[of->base].name << " shell " << iR;
                }
            }
        }
        EXPECT_GT(compared, 0u);
    }
}

// A dataset written before the shell means were kept (no level_shell_means) opens and gives the same
// values, computing the means from the decoded base.
TEST_F(DamagedDatasets, ADatasetWithoutKeptShellMeansGivesTheSameValues)
{
    const TempDir tmp("no-kept-means");
    const fs::path dir = copy(tmp);
    json manifest = json::parse(readFile(dir / format::kManifest));
    for (json& step : manifest.at("steps")) {
        ASSERT_TRUE(step.contains("level_shell_means"));
        step.erase("level_shell_means");
    }
    writeFileAtomic(dir / format::kManifest, manifest.dump(1));
    const auto before = Dataset::open(dir);
    const auto kept = Dataset::open(s_dir->path() / "u16");
    EXPECT_TRUE(before->steps()[1].levelShellMeans.empty());
    for (int level = 0; level < int(kept->levels().size()); ++level) {
        const grid::SphericalGrid& g = kept->levels()[size_t(level)].grid;
        for (size_t var = 0; var < kept->variables().size(); ++var) {
            const ShellAnomalyOf* of = kept->variables()[var].computed ? &*kept->variables()[var].computed : nullptr;
            if (!of)
                continue;
            const auto fresh = before->load(1, level);
            const StepVolume::PointValues points = fresh->pointValues(var);
            EXPECT_EQ(fresh->decodedBytes(), g.cellCount() * sizeof(float)) << "the base decoded for its means";
            const auto other = kept->load(1, level);
            const StepVolume::PointValues keptPoints = other->pointValues(var);
            EXPECT_EQ(other->decodedBytes(), 0u);
            const auto whole = kept->load(1, level);
            const float* all = whole->values(var);
            for (size_t iLat = 0; iLat < g.nLat(); ++iLat)
                for (size_t iR = 0; iR < g.nR(); ++iR)
                    for (size_t iLon = 0; iLon < g.nLon(); ++iLon) {
                        const size_t i = g.index(iLat, iR, iLon);
                        ASSERT_EQ(std::bit_cast<uint32_t>(points.at(i, iLat, iR, iLon)), std::bit_cast<uint32_t>(all[i]));
                        ASSERT_EQ(std::bit_cast<uint32_t>(keptPoints.at(i, iLat, iR, iLon)), std::bit_cast<uint32_t>(all[i]));
                    }
            const auto wholeBefore = before->load(1, level);
            const float* computed = wholeBefore->values(var);
            EXPECT_EQ(std::memcmp(computed, all, g.cellCount() * sizeof(float)), 0) << kept->variables()[var].name;
        }
    }
}

}  // namespace
}  // namespace raypc::dataset
