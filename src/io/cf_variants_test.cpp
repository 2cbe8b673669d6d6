// The netCDF reader against files in the shapes CF-conforming models and tomography tools write,
// written at test time by Python's netCDF4 (tests/data/cf-variants): each variant
// is read and compared with the analytic truth, and each refusal must be one error naming the file
// and what is wrong.
#include "core/atomic_file.h"
#include "core/error.h"
#include "dataset/dataset.h"
#include "io/netcdf_reader.h"
#include "io/series_input.h"
#include "preprocess/preprocess.h"
#include "grid/test_util.h"

#include <fmt/format.h>
#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include <cmath>

// A namespace of its own: the unity build compiles the test files together (vtk_xml_test.cpp has a
// variantsDir() too).
namespace raypc::io::cf_variants_test {
namespace {

namespace fs = std::filesystem;
using RadiusUnits = ReaderOptions::RadiusUnits;

fs::path variantsDir() { return fs::path(RAYPC_TEST_DATA_DIR) / "cf-variants"; }

const nlohmann::json& truth()
{
    static const nlohmann::json j = nlohmann::json::parse(readFile(variantsDir() / "truth.json"));
    return j;
}

const nlohmann::json& variant(const std::string& name)
{
    const auto& variants = truth()["variants"];
    if (!variants.contains(name))
        throw std::runtime_error("truth.json has no variant " + name);
    return variants[name];
}

fs::path fileOf(const std::string& name) { return variantsDir() / variant(name)["file"].get<std::string>(); }

// The options a variant's truth names, for the two variables every variant holds.
ReaderOptions optionsOf(const std::string& name)
{
    ReaderOptions o;
    o.variables = {"temperature", "vx"};
    const auto& v = variant(name);
    if (!v.contains("options"))
        return o;
    const auto& given = v["options"];
    if (given.contains("map"))
        for (const auto& [canonical, inFile] : given["map"].items())
            o.variableNames[canonical] = inFile.get<std::string>();
    o.fillMissing = given.value("fill_missing", false);
    o.latName = given.value("lat_name", "");
    const std::string units = given.value("radius_units", "");
    o.radiusUnits = units == "km" ? RadiusUnits::Km
                    : units == "m" ? RadiusUnits::M
                    : units == "nondimensional" ? RadiusUnits::Nondimensional
                                                : RadiusUnits::FromFile;
    return o;
}

// The options of variant `name` without its --radius-units.
ReaderOptions withoutRadiusUnits(const std::string& name)
{
    ReaderOptions o = optionsOf(name);
    o.radiusUnits = RadiusUnits::FromFile;
    return o;
}

void expectAxis(const std::vector<double>& got, const nlohmann::json& expected, double tolerance, const char* axis)
{
    ASSERT_EQ(got.size(), expected.size()) << axis;
    for (size_t i = 0; i < got.size(); ++i)
        ASSERT_NEAR(got[i], expected[i].get<double>(), tolerance) << axis << "[" << i << "]";
}

// Reads variant `name` with `options` and compares its header, grid and values with the truth.
void expectMatchesTruth(const std::string& name, const ReaderOptions& options)
{
    const auto& v = variant(name);
    const auto path = variantsDir() / v["file"].get<std::string>();
    const FileHeader header = readHeader(path, options);
    const grid::Snapshot s = readSnapshot(path, options);
    ASSERT_TRUE(header.grid.sameAs(s.grid, 0.0));
    expectAxis(s.grid.latDeg, truth()["lat_deg"], 1e-9, "lat");
    expectAxis(s.grid.rKm, truth()["r_km"], 1e-9, "r");
    expectAxis(s.grid.lonDeg, truth()["lon_deg"], 1e-9, "lon");
    ASSERT_EQ(s.fields.size(), 2u);
    for (size_t f = 0; f < s.fields.size(); ++f) {
        const grid::Field& field = s.fields[f];
        EXPECT_EQ(field.units, v["units"][field.name].get<std::string>()) << field.name;
        EXPECT_EQ(header.variables[f].units, v["units"][field.name].get<std::string>()) << field.name;
        const auto& expected = v.contains("values") ? v["values"][field.name] : truth()["values"][field.name];
        const double tolerance = v["tolerance"][field.name];
        ASSERT_EQ(field.values.size(), expected.size()) << field.name;
        size_t wrong = 0, first = 0;
        for (size_t i = 0; i < field.values.size(); ++i)
            if (!(std::abs(field.values[i] - expected[i].get<double>()) <= tolerance) && wrong++ == 0)
                first = i;
        EXPECT_EQ(wrong, 0u) << name << ": " << field.name << ": " << wrong << " values differ from the truth, the first at "
                             << grid::describeGridPoint(s.grid, first) << ": " << field.values[first] << ", expected "
                             << expected[first].get<double>();
    }
}

void expectMatchesTruth(const std::string& name) { expectMatchesTruth(name, optionsOf(name)); }

// Expects readHeader and readSnapshot to throw one Error whose message contains every fragment.
void expectRefused(const fs::path& path, const ReaderOptions& options, const std::vector<std::string>& fragments,
                   bool headerToo = true)
{
    auto check = [&](const char* what, auto&& read) {
        try {
            read();
            ADD_FAILURE() << what << " accepted " << path;
        } catch (const Error& e) {
            const std::string message = e.what();
            EXPECT_EQ(message.find('\n'), std::string::npos) << message;
            for (const auto& f : fragments)
                EXPECT_NE(message.find(f), std::string::npos) << what << ": '" << message << "' lacks '" << f << "'";
        }
    };
    if (headerToo)
        check("readHeader", [&] { readHeader(path, options); });
    check("readSnapshot", [&] { readSnapshot(path, options); });
}

std::string pointText(const nlohmann::json& at)
{
    return fmt::format("lat {:g}°, r {:g} km, lon {:g}°", at["lat_deg"].get<double>(), at["r_km"].get<double>(),
                       at["lon_deg"].get<double>());
}

// The range of a coordinate's stored numbers as an error message gives it.
std::string storedRange(const std::string& name)
{
    const auto& range = variant(name)["stored_range"];
    return fmt::format("{:g}..{:g}", range[0].get<double>(), range[1].get<double>());
}

// 1. One time step per file.

TEST(CfVariants, TimeDimensionOfLengthOne)
{
    expectMatchesTruth("time_fixed");
}

TEST(CfVariants, UnlimitedTimeDimensionOfLengthOne)
{
    expectMatchesTruth("time_unlimited");      // a record dimension of a 64-bit-offset file
    expectMatchesTruth("time_unlimited_nc4");  // compressed netCDF-4, dims (time, lon, lat, r), lat descending
}

// A time dimension longer than 1: the file is that many steps, FILE#K, each read from its own
// hyperslab (step k holds the values + 100 k).
TEST(CfVariants, ATimeDimensionLongerThanOneIsASeriesOfSteps)
{
    const auto& v = variant("time_three_steps");
    const fs::path file = fileOf("time_three_steps");
    const ReaderOptions options = optionsOf("time_three_steps");
    EXPECT_EQ(readHeader(file, options).steps, 3u);
    const SeriesListing listing = listSeries({file}, options);
    ASSERT_EQ(listing.steps.size(), v["length"].get<size_t>());
    EXPECT_FALSE(listing.vtk);
    EXPECT_EQ(listing.steps[2].filename().string(), "time_three_steps.nc#2");
    const grid::Snapshot first = readStep(listing.steps[0], options);
    const grid::Snapshot one = readSnapshot(fileOf("time_unlimited"), optionsOf("time_unlimited"));
    ASSERT_TRUE(first.grid.sameAs(one.grid));
    for (size_t f = 0; f < first.fields.size(); ++f)
        for (size_t i = 0; i < first.fields[f].values.size(); ++i)
            ASSERT_NEAR(first.fields[f].values[i], one.fields[f].values[i], 1e-3) << first.fields[f].name << " " << i;
    for (size_t k = 1; k < listing.steps.size(); ++k) {
        const grid::Snapshot step = readStep(listing.steps[k], options);
        for (size_t f = 0; f < step.fields.size(); ++f)
            for (size_t i = 0; i < step.fields[f].values.size(); ++i)
                ASSERT_NEAR(step.fields[f].values[i] - first.fields[f].values[i],
                            v["step_offset"].get<double>() * double(k), 1e-3)
                    << "step " << k << " " << step.fields[f].name << " " << i;
    }
    ReaderOptions beyond = options;
    beyond.timeIndex = 3;
    expectRefused(file, beyond, {"time_three_steps.nc", "step 3 of a file holding 3"});
}

// 2. Doubles are read as doubles; packed values are unpacked in double.

TEST(CfVariants, DoubleFillValueBeyondFloatIsMissing)
{
    const auto& fill = variant("double_fill_1e300")["fill"];
    ReaderOptions strict = optionsOf("double_fill_1e300");
    strict.fillMissing = false;
    // Kept missing: NaN at the writer's fill cells (as many, the first where it says), nowhere else.
    const grid::Snapshot s = readSnapshot(fileOf("double_fill_1e300"), strict);
    const auto& values = s.fields.front().values;
    const auto first = std::find_if(values.begin(), values.end(), [](float v) { return std::isnan(v); });
    ASSERT_NE(first, values.end());
    EXPECT_EQ(grid::describeGridPoint(s.grid, size_t(first - values.begin())).rfind(pointText(fill["first"]), 0), 0u);
    EXPECT_EQ(std::count_if(values.begin(), values.end(), [](float v) { return std::isnan(v); }),
              fill["count"].get<int>());
    expectMatchesTruth("double_fill_1e300");  // with --fill-missing: the shell's mean
}

TEST(CfVariants, DoubleValueBeyondFloatIsRefused)
{
    const auto& v = variant("double_beyond_float");
    for (const bool fill : {false, true}) {
        ReaderOptions options = optionsOf("double_beyond_float");
        options.fillMissing = fill;
        expectRefused(fileOf("double_beyond_float"), options,
                      {"double_beyond_float.nc", "temperature", fmt::format("{:g}", v["value"].get<double>()),
                       pointText(v["at"]), "float32"},
                      false);
    }
}

// Packed unsigned shorts.

TEST(CfVariants, UnsignedShorts)
{
    expectMatchesTruth("unsigned_short");
}

// 3. Units and names read from CF attributes.

TEST(CfVariants, RadiusInMetresWithStringAttributes)
{
    expectMatchesTruth("radius_m_string_units");  // units NC_STRING, of the coordinates and the variables
}

TEST(CfVariants, RadiusInMetresWithoutUnits)
{
    expectRefused(fileOf("radius_m_no_units"), withoutRadiusUnits("radius_m_no_units"),
                  {"radius_m_no_units.nc", "'r'", "no units", storedRange("radius_m_no_units"), "--radius-units"});
    expectMatchesTruth("radius_m_no_units");  // --radius-units m
}

TEST(CfVariants, NondimensionalRadius)
{
    expectRefused(fileOf("radius_nondimensional"), withoutRadiusUnits("radius_nondimensional"),
                  {"radius_nondimensional.nc", "'r'", "no units", storedRange("radius_nondimensional"),
                   "--radius-units"});
    expectMatchesTruth("radius_nondimensional");  // --radius-units nondimensional
}

TEST(CfVariants, RadiusInKmWithoutUnits)
{
    expectMatchesTruth("radius_km_no_units");
}

TEST(CfVariants, RadiusWithUnknownUnitsIsRefused)
{
    expectRefused(fileOf("radius_unknown_units"), optionsOf("radius_unknown_units"),
                  {"radius_unknown_units.nc", "'r'", "'miles'", "--radius-units"});
}

TEST(CfVariants, AnglesInRadians)
{
    expectMatchesTruth("angles_radians");
}

TEST(CfVariants, LatitudeInRadiansWithoutUnitsIsRefused)
{
    expectRefused(fileOf("lat_radians_no_units"), optionsOf("lat_radians_no_units"),
                  {"lat_radians_no_units.nc", "'lat'", "no units", "radians"});
}

TEST(CfVariants, DegreesSouth)
{
    expectMatchesTruth("lat_degrees_south");
}

TEST(CfVariants, DegreesWest)
{
    expectMatchesTruth("lon_degrees_west");
}

TEST(CfVariants, DepthInKm)
{
    expectMatchesTruth("depth_km");
}

TEST(CfVariants, DepthInMetresFoundByAxisAndPositive)
{
    expectMatchesTruth("depth_m_cf");
}

TEST(CfVariants, CoordinatesFoundByStandardNameAndAxis)
{
    expectMatchesTruth("cf_names");
}

TEST(CfVariants, StaggeredCoordinateOnAnotherDimIsNotTheGrids)
{
    expectMatchesTruth("staggered_lat");
}

TEST(CfVariants, TwoClaimantsOfAnAxisAreRefused)
{
    ReaderOptions options = optionsOf("ambiguous_lat");
    options.latName.clear();
    const auto& claimants = variant("ambiguous_lat")["claimants"];
    expectRefused(fileOf("ambiguous_lat"), options,
                  {"ambiguous_lat.nc", fmt::format("{}, {}", claimants[0].get<std::string>(), claimants[1].get<std::string>()),
                   "lat coordinate", "--lat-name"});
    expectMatchesTruth("ambiguous_lat");  // --lat-name lat_b
}

// 4. Series: the errors of a variable missing in one step and of a grid that differs stay.

preprocess::PreprocessOptions seriesOptions()
{
    preprocess::PreprocessOptions options;
    options.reader.variables = {"temperature", "vx"};
    options.quiet = true;
    options.sampleRows = 100;
    options.pathlines.enabled = false;
    return options;
}

std::vector<fs::path> seriesFiles(const std::string& name)
{
    std::vector<fs::path> files;
    for (const auto& f : variant(name)["files"])
        files.push_back(variantsDir() / f.get<std::string>());
    return files;
}

void expectPreprocessRefused(const std::string& name, const std::vector<std::string>& fragments)
{
    testing::TempDir dir("cfseries");
    try {
        preprocess::preprocess(seriesFiles(name), dir / "out", seriesOptions());
        ADD_FAILURE() << name << " was preprocessed";
    } catch (const Error& e) {
        for (const auto& f : fragments)
            EXPECT_NE(std::string(e.what()).find(f), std::string::npos) << "'" << e.what() << "' lacks '" << f << "'";
    }
    EXPECT_FALSE(fs::exists(dir / "out"));  // refused before anything was written
}

TEST(CfVariants, VariableMissingInOneStep)
{
    const auto& v = variant("series_missing_variable");
    expectPreprocessRefused("series_missing_variable",
                            {v["in"].get<std::string>(),
                             fmt::format("missing variable '{}'", v["missing"].get<std::string>())});
}

TEST(CfVariants, GridThatDiffersBetweenSteps)
{
    // Step 2 holds the radius in metres: the same grid once converted; step 3's lat is shifted.
    expectPreprocessRefused("series_grid_differs",
                            {variant("series_grid_differs")["differs"].get<std::string>(), "differ from the first step"});
    const auto files = seriesFiles("series_grid_differs");
    EXPECT_TRUE(readHeader(files[1], seriesOptions().reader).grid.sameAs(readHeader(files[0], seriesOptions().reader).grid));
}

}  // namespace
}  // namespace raypc::io::cf_variants_test
