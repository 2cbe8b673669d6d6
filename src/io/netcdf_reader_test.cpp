#include "io/netcdf_reader.h"

#include "core/atomic_file.h"
#include "core/error.h"
#include "core/spherical.h"
#include "core/strings.h"
#include "grid/sampler.h"
#include "io/netcdf_classic.h"
#include "preprocess/preprocess.h"
#include "grid/test_util.h"

#include <fmt/format.h>
#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include <cmath>
#include <fstream>
#include <sstream>

namespace raypc::io {
namespace {

using testing::contestLayoutDir;
using testing::ncgen;
using testing::TempDir;

// The analytic fields of the contest-layout fixture (truth.json), evaluated independently.
struct Truth {
    nlohmann::json j = nlohmann::json::parse(readFile(contestLayoutDir() / "truth.json"));
    double omega = j["omega_rad_per_s"], u0 = j["u0_m_per_s"], dtMyr = j["dt_myr"];

    // The blob sum before the per-shell mean is removed.
    double blobs(double latDeg, double lonDeg, double rKm, double tS) const
    {
        const Vec3d p = sphericalToCartesianKm(latDeg, lonDeg, rKm);
        double sum = 0;
        for (const auto& b : j["blobs_lat_lon_rkm_amp_sigma"]) {
            const double lon = b[1].get<double>() + radToDeg(omega * tS);
            const double r = b[2].get<double>() + u0 * tS / 1000.0;
            const Vec3d c = sphericalToCartesianKm(b[0].get<double>(), lon, r);
            const double d2 = (p.x - c.x) * (p.x - c.x) + (p.y - c.y) * (p.y - c.y) + (p.z - c.z) * (p.z - c.z);
            const double sigma = b[4].get<double>();
            sum += b[3].get<double>() * std::exp(-d2 / (2 * sigma * sigma));
        }
        return sum;
    }
};

TEST(NetcdfReader, ContestLayoutMatchesTruth)
{
    const Truth truth;
    for (int k = 0; k < 3; ++k) {
        const auto path = contestLayoutDir() / fmt::format("spherical{:03d}.nc", k + 1);
        const grid::Snapshot s = readSnapshot(path);
        const auto& g = s.grid;
        ASSERT_EQ(g.nLat(), 36u);
        ASSERT_EQ(g.nR(), 41u);
        ASSERT_EQ(g.nLon(), 72u);
        EXPECT_DOUBLE_EQ(g.latDeg.front(), -87.5);  // canonical: ascending, although the file descends
        EXPECT_DOUBLE_EQ(g.rKm.front(), 3485.0);
        EXPECT_DOUBLE_EQ(g.rKm.back(), 6371.0);
        ASSERT_EQ(s.fields.size(), 8u);
        const double tS = k * truth.dtMyr * kSecondsPerMyr;
        const auto& T = s.find("temperature")->values;
        const auto& dT = s.find("temperature anomaly")->values;
        const auto& vx = s.find("vx")->values;
        const auto& vy = s.find("vy")->values;
        const auto& vz = s.find("vz")->values;
        const auto& k_ = s.find("thermal conductivity")->values;
        const auto& rho = s.find("spin transition-induced density anomaly")->values;
        for (size_t iR = 0; iR < g.nR(); ++iR) {
            const double r = g.rKm[iR];
            double mean = 0;
            for (size_t a = 0; a < g.nLat(); ++a)
                for (size_t c = 0; c < g.nLon(); ++c)
                    mean += truth.blobs(g.latDeg[a], g.lonDeg[c], r, tS);
            mean /= g.nLat() * g.nLon();
            for (size_t a = 0; a < g.nLat(); a += 5)
                for (size_t c = 0; c < g.nLon(); c += 7) {
                    const size_t i = g.index(a, iR, c);
                    const double anomaly = truth.blobs(g.latDeg[a], g.lonDeg[c], r, tS) - mean;
                    ASSERT_NEAR(dT[i], anomaly, 1e-3 * 400) << "lat " << g.latDeg[a] << " lon " << g.lonDeg[c];
                    ASSERT_NEAR(T[i], 300 + 3700 * (6371 - r) / (6371 - 3485) + anomaly, 0.05);
                    ASSERT_NEAR(k_[i], -1e-3 * anomaly, 1e-3);
                    ASSERT_NEAR(rho[i], -0.05 * anomaly * std::exp(-std::pow((6371 - r - 1800) / 300, 2)), 1e-2);
                    const Vec3d p = sphericalToCartesianKm(g.latDeg[a], g.lonDeg[c], r);
                    const double ex = truth.omega * -p.y * 1000 + truth.u0 * p.x / r;
                    const double ey = truth.omega * p.x * 1000 + truth.u0 * p.y / r;
                    const double ez = truth.u0 * p.z / r;
                    ASSERT_NEAR(vx[i], ex, 1e-6 * 3e-9);
                    ASSERT_NEAR(vy[i], ey, 1e-6 * 3e-9);
                    ASSERT_NEAR(vz[i], ez, 1e-6 * 3e-9);
                }
        }
    }
}

TEST(NetcdfReader, DerivedRadialVelocityIsU0)
{
    const Truth truth;
    grid::Snapshot s = readSnapshot(contestLayoutDir() / "spherical002.nc");
    preprocess::addDerivedVariables(s);
    const grid::Field* ur = s.find("radial velocity");
    ASSERT_TRUE(ur);
    EXPECT_EQ(ur->units, "cm/yr");
    const double expected = truth.u0 * kMpsToCmPerYr;  // radial velocity == u0 everywhere
    for (float v : ur->values)
        ASSERT_NEAR(v, expected, 1e-4 * expected + 1e-6);
    // |v|² = (omega * distance from the axis)² + u0²
    const grid::Field* mag = s.find("velocity magnitude");
    const auto& g = s.grid;
    const size_t i = g.index(20, 30, 10);
    const double axisKm = g.rKm[30] * std::cos(degToRad(g.latDeg[20]));
    EXPECT_NEAR(mag->values[i], std::hypot(truth.omega * axisKm * 1000, truth.u0) * kMpsToCmPerYr, 1e-4);
}

// The expansivity anomaly has zero area-weighted mean on every shell and differs from the
// expansivity by that shell's mean only.
TEST(NetcdfReader, DerivedExpansivityAnomalyIsTheLateralDeviation)
{
    grid::Snapshot s = readSnapshot(contestLayoutDir() / "spherical001.nc");
    preprocess::addDerivedVariables(s);
    const grid::Field* alpha = s.find("thermal expansivity");
    const grid::Field* anomaly = s.find("thermal expansivity anomaly");
    ASSERT_TRUE(anomaly);
    EXPECT_EQ(anomaly->units, alpha->units);
    const auto& g = s.grid;
    for (size_t iR = 0; iR < g.nR(); iR += 5) {
        double sum = 0, area = 0;
        for (size_t a = 0; a < g.nLat(); ++a) {
            const double w = std::sin(degToRad(std::min(90.0, g.latDeg[a] + 2.5))) - std::sin(degToRad(std::max(-90.0, g.latDeg[a] - 2.5)));
            for (size_t c = 0; c < g.nLon(); ++c) {
                sum += w * anomaly->values[g.index(a, iR, c)];
                area += w;
            }
        }
        EXPECT_NEAR(sum / area, 0.0, 1e-12) << "r " << g.rKm[iR];
        const double offset = alpha->values[g.index(3, iR, 5)] - anomaly->values[g.index(3, iR, 5)];
        EXPECT_NEAR(alpha->values[g.index(30, iR, 60)] - anomaly->values[g.index(30, iR, 60)], offset, 1e-12);
    }
}

TEST(NetcdfReader, BothNetcdfFlavoursGiveIdenticalValues)
{
    TempDir dir("flavours");
    const auto source = contestLayoutDir() / "spherical001.nc";
    const grid::Snapshot reference = readSnapshot(source);
    for (const std::string kind : {"nc4", "classic"}) {
        const auto copy = dir / (kind + ".nc");
        ASSERT_EQ(testing::run(fmt::format("nccopy -k {} '{}' '{}'", kind, source.string(), copy.string())), 0);
        const auto header = readHeader(copy);
        EXPECT_EQ(header.format, kind == "nc4" ? "netCDF-4" : "classic");
        const grid::Snapshot s = readSnapshot(copy);
        ASSERT_TRUE(s.grid.sameAs(reference.grid, 0.0));
        for (size_t f = 0; f < s.fields.size(); ++f)
            ASSERT_EQ(s.fields[f].values, reference.fields[f].values) << kind << " " << s.fields[f].name;
    }
}

// A file that differs from the contest layout in every way the reader must handle: dims
// (lon, r, lat), lat ascending as float, r descending in metres, lon in [-180, 180] with the
// seam repeated, other names (mapped by options).
TEST(NetcdfReader, ReordersAnyLayoutIntoCanonicalOrder)
{
    TempDir dir("layout");
    const std::vector<double> lats = {-45, 45}, rsM = {6371000, 4900000, 3485000},
                              lons = {-180, -90, 0, 90, 180};
    // The value encodes the canonical position: 100*iLat + 10*iR + iLon.
    auto canonLat = [&](size_t i) { return i; };
    auto canonR = [&](size_t i) { return 2 - i; };
    auto canonLon = [&](size_t i) { return i == 4 ? size_t(2) : (i + 2) % 4; };  // 180 -> 0 -> ...
    std::string data;
    for (size_t o = 0; o < lons.size(); ++o)
        for (size_t r = 0; r < rsM.size(); ++r)
            for (size_t a = 0; a < lats.size(); ++a)
                data += fmt::format("{}{}", data.empty() ? "" : ", ", 100 * canonLat(a) + 10 * canonR(r) + canonLon(o));
    const std::string cdl = fmt::format(R"(netcdf layout {{
dimensions: longitude = 5 ; radius = 3 ; latitude = 2 ;
variables:
  double longitude(longitude) ; longitude:units = "degrees_east" ;
  double radius(radius) ; radius:units = "m" ;
  float latitude(latitude) ; latitude:units = "degrees_north" ;
  float T(longitude, radius, latitude) ; T:units = "K" ;
data:
  longitude = -180, -90, 0, 90, 180 ;
  radius = 6371000, 4900000, 3485000 ;
  latitude = -45, 45 ;
  T = {} ;
}})",
                                        data);
    const auto path = ncgen(dir.path(), "layout", cdl);
    ReaderOptions options;
    options.variables = {"temperature"};
    options.variableNames["temperature"] = "T";
    const grid::Snapshot s = readSnapshot(path, options);
    EXPECT_EQ(s.grid.latDeg, (std::vector<double>{-45, 45}));
    EXPECT_EQ(s.grid.rKm, (std::vector<double>{3485, 4900, 6371}));
    EXPECT_EQ(s.grid.lonDeg, (std::vector<double>{0, 90, 180, 270}));
    const auto& v = s.fields[0].values;
    for (size_t a = 0; a < 2; ++a)
        for (size_t r = 0; r < 3; ++r)
            for (size_t o = 0; o < 4; ++o)
                ASSERT_EQ(v[s.grid.index(a, r, o)], 100 * a + 10 * r + o) << a << r << o;
    EXPECT_EQ(s.fields[0].units, "K");
    EXPECT_EQ(s.fields[0].name, "temperature");
}

// A minimal valid file; `values` fills "temperature" (lat 2 x r 2 x lon 4).
std::string smallCdl(const std::string& values, const std::string& extra = "", const std::string& r = "3485, 6371")
{
    return fmt::format(R"(netcdf small {{
dimensions: lat = 2 ; r = 2 ; lon = 4 ;
variables:
  double lat(lat) ; lat:units = "degrees_north" ;
  double r(r) ; r:units = "km" ;
  double lon(lon) ; lon:units = "degrees_east" ;
  float temperature(lat, r, lon) ; temperature:units = "K" ; {}
data:
  lat = 45, -45 ; r = {} ; lon = 0, 90, 180, 270 ;
  temperature = {} ;
}})",
                       extra, r, values);
}

// A file "small" like smallCdl's with fewer attributes (lon and temperature without units) and a
// temperature of CDL `type`; `lat` and `temperature` are their data (`_`: a value never written).
std::string plainCdl(const std::string& type, const std::string& lat, const std::string& temperature)
{
    return fmt::format(R"(netcdf small {{
dimensions: lat = 2 ; r = 2 ; lon = 4 ;
variables:
  double lat(lat) ; lat:units = "degrees_north" ; double r(r) ; r:units = "km" ; double lon(lon) ;
  {} temperature(lat, r, lon) ;
data:
  lat = {} ; r = 3485, 6371 ; lon = 0, 90, 180, 270 ;
  temperature = {} ;
}})",
                       type, lat, temperature);
}

// A file `name` on a grid of depth 2 (km, positive down) x lat 2 x lon 4 holding `variables` (CDL
// declarations on those dims) with their `data`.
std::string depthGridCdl(const std::string& name, const std::string& variables, const std::string& data)
{
    return fmt::format(R"(netcdf {} {{
dimensions: depth = 2 ; lat = 2 ; lon = 4 ;
variables:
  double depth(depth) ; depth:units = "km" ; depth:positive = "down" ;
  double lat(lat) ; lat:units = "degrees_north" ; double lon(lon) ; lon:units = "degrees_east" ;
{}
data:
  depth = 100, 2000 ; lat = -45, 45 ; lon = 0, 90, 180, 270 ;
{}
}})",
                       name, variables, data);
}

ReaderOptions temperatureOnly()
{
    ReaderOptions o;
    o.variables = {"temperature"};
    return o;
}

// Expects readSnapshot to throw an Error whose message contains every fragment.
void expectReadError(const std::filesystem::path& path, const ReaderOptions& options,
                     std::initializer_list<std::string> fragments)
{
    try {
        readSnapshot(path, options);
        ADD_FAILURE() << "no error for " << path;
    } catch (const Error& e) {
        for (const auto& f : fragments)
            EXPECT_NE(std::string(e.what()).find(f), std::string::npos) << "'" << e.what() << "' lacks '" << f << "'";
    }
}

// Expects readSnapshot to give the first field missing (NaN) at the canonical points `missing` and
// nowhere else.
void expectMissingOnlyAt(const std::filesystem::path& path, const ReaderOptions& options,
                         std::initializer_list<std::array<size_t, 3>> missing)
{
    const grid::Snapshot s = readSnapshot(path, options);
    std::vector<size_t> expected;
    for (const auto& [iLat, iR, iLon] : missing)
        expected.push_back(s.grid.index(iLat, iR, iLon));
    for (size_t i = 0; i < s.fields[0].values.size(); ++i)
        EXPECT_EQ(std::isnan(s.fields[0].values[i]), std::find(expected.begin(), expected.end(), i) != expected.end())
            << path << ": point " << i << " holds " << s.fields[0].values[i];
}

TEST(NetcdfReaderBadInput, MissingFile)
{
    expectReadError("/nonexistent/spherical001.nc", {}, {"/nonexistent/spherical001.nc", "no such file"});
}

TEST(NetcdfReaderBadInput, NotNetcdf)
{
    TempDir dir("notnc");
    writeFileAtomic(dir / "text.nc", std::string_view("this is not a netCDF file\n"));
    expectReadError(dir / "text.nc", {}, {"text.nc", "not a netCDF file"});
}

TEST(NetcdfReaderBadInput, TruncatedFile)
{
    TempDir dir("truncated");
    const auto copy = dir / "spherical001.nc";
    std::filesystem::copy_file(contestLayoutDir() / "spherical001.nc", copy);
    std::filesystem::resize_file(copy, std::filesystem::file_size(copy) * 6 / 10);
    expectReadError(copy, {}, {"spherical001.nc", "truncated"});
    // A netCDF-4 (HDF5) file cut short fails too, with the file's name.
    const auto nc4 = dir / "nc4.nc";
    ASSERT_EQ(testing::run(fmt::format("nccopy -k nc4 '{}' '{}'", (contestLayoutDir() / "spherical001.nc").string(),
                                       nc4.string())),
              0);
    std::filesystem::resize_file(nc4, std::filesystem::file_size(nc4) / 2);
    expectReadError(nc4, {}, {"nc4.nc"});
}

// A classic file cut by less than its header's size (about 1.4 KB here) was read with the
// missing values as zeros: the size check assumed a 32-byte header.
TEST(NetcdfReaderBadInput, ShortTruncationsOfAClassicFile)
{
    TempDir dir("shortcut");
    const auto original = contestLayoutDir() / "spherical001.nc";
    const auto size = std::filesystem::file_size(original);
    for (const uintmax_t cut : {1, 3, 4, 100, 1000, 1400}) {
        const auto copy = dir / fmt::format("cut{}.nc", cut);
        std::filesystem::copy_file(original, copy);
        std::filesystem::resize_file(copy, size - cut);
        expectReadError(copy, {}, {copy.filename().string(), "truncated", fmt::format("{} bytes", size - cut)});
        EXPECT_THROW(readHeader(copy), Error) << cut;
    }
    // Every classic flavour, with record variables too: the exact size reads, one byte less does not.
    for (const char* kind : {"nc3", "nc6", "nc5"}) {
        const std::string cdl = R"(netcdf rec {
dimensions: t = UNLIMITED ; x = 3 ;
variables: short a(t, x) ; byte b(t) ; double c(x) ; c:note = "padded" ;
data: a = 1, 2, 3, 4, 5, 6 ; b = 7, 8 ; c = 1, 2, 3 ;
})";
        const auto path = ncgen(dir.path(), std::string("rec-") + kind, cdl, kind);
        std::ifstream in(path, std::ios::binary);
        const uint64_t end = classicDataEndBytes(in, path.string());
        EXPECT_LE(end, std::filesystem::file_size(path)) << kind;
        // The last record's data ends within the file's padding of at most 3 bytes.
        EXPECT_GE(end + 3, std::filesystem::file_size(path)) << kind;
    }
}

TEST(NetcdfClassicLayout, RefusesWhatIsNotAClassicHeader)
{
    for (const std::string& bytes : {std::string("CDF"), std::string("HDF\x01", 4), std::string("CDF\x02\0\0\0\0\0\0\0\x0a", 12),
                                    std::string("CDF\x01\0\0\0\0\0\0\0\x0b\0\0\0\x01", 16)}) {
        std::istringstream in(bytes);
        EXPECT_THROW(classicDataEndBytes(in, "x.nc"), Error) << bytes.size();
    }
}

// A variable without _FillValue whose cells were never written holds netCDF's default fill
// value (9.96921e36 for float): it was taken as a temperature.
TEST(NetcdfReaderBadInput, DefaultFillValuesAreMissing)
{
    TempDir dir("defaultfill");
    for (const char* kind : {"nc6", "nc4"}) {
        // ncgen writes the type's default fill value for `_` when the variable has no _FillValue.
        const auto path = ncgen(dir.path(), std::string("unwritten-") + kind,
                                smallCdl("1, 2, 3, 4, 5, _, 7, 8, 9, 10, 11, 12, 13, 14, 15, 16"), kind);
        // Kept missing, at lat 45°, r 6371 km, lon 90° (canonical row 1, radius 1, column 1).
        expectMissingOnlyAt(path, temperatureOnly(), {{1, 1, 1}});
        ReaderOptions fill = temperatureOnly();
        fill.fillMissing = true;
        const grid::Snapshot s = readSnapshot(path, fill);
        EXPECT_NEAR(s.fields[0].values[s.grid.index(1, 1, 1)], (5 + 7 + 8 + 13 + 14 + 15 + 16) / 7.0, 1e-5) << kind;
    }
    // Integer variables too (NC_FILL_SHORT = -32767).
    const std::string cdl = plainCdl("short", "45, -45", "1, 2, 3, 4, 5, 6, 7, 8, 9, 10, 11, _, 13, 14, 15, 16");
    expectMissingOnlyAt(ncgen(dir.path(), "short", cdl), temperatureOnly(), {{0, 0, 3}});
    // A step whose values are all missing is an error naming it.
    const std::string none = plainCdl("float", "45, -45", "_, _, _, _, _, _, _, _, _, _, _, _, _, _, _, _");
    expectReadError(ncgen(dir.path(), "none", none), temperatureOnly(),
                    {"none.nc", "temperature", "every value of the step is missing", "default fill value"});
}

// A coordinate variable declared but never written holds the fill value: named as such, not as a
// coordinate that "repeats the value 9.97e+36".
TEST(NetcdfReaderBadInput, UnwrittenCoordinate)
{
    TempDir dir("unwrittencoord");
    const std::string cdl = plainCdl("float", "_, _", "1, 2, 3, 4, 5, 6, 7, 8, 9, 10, 11, 12, 13, 14, 15, 16");
    expectReadError(ncgen(dir.path(), "unwritten", cdl), temperatureOnly(),
                    {"unwritten.nc: coordinate 'lat' holds its fill value (9.96921e+36) at 2 of its 2 points: it was "
                     "never written"});
}

TEST(NetcdfReaderBadInput, MissingVariable)
{
    TempDir dir("missingvar");
    const auto path = ncgen(dir.path(), "small", smallCdl("1, 2, 3, 4, 5, 6, 7, 8, 9, 10, 11, 12, 13, 14, 15, 16"));
    // Variables asked for by name must be there; without a list the file's own are read (below).
    ReaderOptions contest;
    contest.variables = grid::contestVariableNames();
    expectReadError(path, contest, {"small.nc", "missing variable 'vx'"});
    ReaderOptions mapped = temperatureOnly();
    mapped.variableNames["temperature"] = "T";
    expectReadError(path, mapped, {"missing variable 'T'", "mapped from 'temperature'"});
}

// A file of a model (or a tomography) with its own variables: without a list, every variable on the
// grid's three dims is read, under its own name (or the one --map gives it), in the file's order;
// what is on other dims (a surface map) is not among them.
TEST(NetcdfReader, AnyVariablesAreReadWithoutAList)
{
    TempDir dir("anyvars");
    const std::string cdl = R"(netcdf own {
dimensions: depth = 2 ; latitude = 2 ; longitude = 4 ;
variables:
  double depth(depth) ; depth:units = "km" ; depth:positive = "down" ;
  double latitude(latitude) ; latitude:units = "degrees_north" ;
  double longitude(longitude) ; longitude:units = "degrees_east" ;
  float vs(depth, latitude, longitude) ; vs:units = "km/s" ;
  float topography(latitude, longitude) ; topography:units = "m" ;
  float rho(depth, latitude, longitude) ; rho:units = "g/cc" ;
data:
  depth = 100, 2000 ; latitude = -45, 45 ; longitude = 0, 90, 180, 270 ;
  vs = 1, 2, 3, 4, 5, 6, 7, 8, 9, 10, 11, 12, 13, 14, 15, 16 ;
  topography = 0, 0, 0, 0, 0, 0, 0, 0 ;
  rho = 3, 3, 3, 3, 3, 3, 3, 3, 4, 4, 4, 4, 4, 4, 4, 4 ;
})";
    const auto path = ncgen(dir.path(), "own", cdl);
    const FileHeader header = readHeader(path, {});
    ASSERT_EQ(header.variables.size(), 2u);
    EXPECT_EQ(header.variables[0].name, "vs");
    EXPECT_EQ(header.variables[0].units, "km/s");
    EXPECT_EQ(header.variables[1].name, "rho");
    const grid::Snapshot s = readSnapshot(path, {});
    ASSERT_EQ(s.fields.size(), 2u);
    // depth 100 km is radius 6271 km (the upper shell), lat 45 the upper row, lon 90 the second column.
    EXPECT_FLOAT_EQ(s.fields[0].values[s.grid.index(1, 1, 1)], 6.0f);
    EXPECT_FLOAT_EQ(s.fields[0].values[s.grid.index(1, 0, 1)], 14.0f);
    EXPECT_FLOAT_EQ(s.fields[1].values[s.grid.index(0, 0, 0)], 4.0f);
    // --map names a variable as the program knows it.
    ReaderOptions mapped;
    mapped.variableNames["shear velocity"] = "vs";
    EXPECT_EQ(readHeader(path, mapped).variables[0].name, "shear velocity");
    // A file with nothing on its grid says so.
    const std::string flat = R"(netcdf flat {
dimensions: depth = 2 ; latitude = 2 ; longitude = 4 ;
variables:
  double depth(depth) ; depth:units = "km" ; double latitude(latitude) ; double longitude(longitude) ;
  float topography(latitude, longitude) ;
data:
  depth = 100, 2000 ; latitude = -45, 45 ; longitude = 0, 90, 180, 270 ; topography = 0, 0, 0, 0, 0, 0, 0, 0 ;
})";
    expectReadError(ncgen(dir.path(), "flat", flat), {}, {"flat.nc: no variable on the grid's dims"});
}

// A velocity given as spherical components (radial, north, east) in cm/yr under other names
// (--velocity vr,vn,ve --velocity-frame spherical) is read as Cartesian vx, vy, vz in m/s.
TEST(NetcdfReader, SphericalVelocityInOtherUnitsBecomesCartesianMetresPerSecond)
{
    TempDir dir("sphvel");
    const std::string cdl = depthGridCdl("vel", R"(
  float vr(depth, lat, lon) ; vr:units = "cm/yr" ;
  float vn(depth, lat, lon) ; vn:units = "cm yr-1" ;
  float ve(depth, lat, lon) ; ve:units = "cm/a" ;)",
                                         R"(
  vr = 1, 1, 1, 1, 1, 1, 1, 1, 1, 1, 1, 1, 1, 1, 1, 1 ;
  vn = 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0 ;
  ve = 2, 2, 2, 2, 2, 2, 2, 2, 2, 2, 2, 2, 2, 2, 2, 2 ;)");
    const auto path = ncgen(dir.path(), "vel", cdl);
    ReaderOptions o;
    o.variableNames = {{"vx", "vr"}, {"vy", "vn"}, {"vz", "ve"}};
    o.velocityFrame = ReaderOptions::VelocityFrame::Spherical;
    const FileHeader header = readHeader(path, o);
    ASSERT_EQ(header.variables.size(), 3u);
    EXPECT_EQ(header.variables[0].name, "vx");
    EXPECT_EQ(header.variables[0].units, "m/s");
    const grid::Snapshot s = readSnapshot(path, o);
    const double cmPerYr = 0.01 / 3.15576e7;
    // At lat 45, lon 90: up = (0, cos 45, sin 45), east = (-1, 0, 0).
    const size_t i = s.grid.index(1, 0, 1);
    EXPECT_NEAR(s.find("vx")->values[i], -2 * cmPerYr, 1e-6 * cmPerYr);
    EXPECT_NEAR(s.find("vy")->values[i], std::sqrt(0.5) * cmPerYr, 1e-6 * cmPerYr);
    EXPECT_NEAR(s.find("vz")->values[i], std::sqrt(0.5) * cmPerYr, 1e-6 * cmPerYr);
    EXPECT_EQ(s.find("vz")->units, "m/s");
    // A name that is not in the file, and units that are not a velocity's, are named.
    ReaderOptions missing = o;
    missing.variableNames["vy"] = "vnorth";
    expectReadError(path, missing, {"vel.nc", "missing variable 'vnorth' (mapped from 'vy')"});
    const std::string furlongs = depthGridCdl("odd", R"(
  float vx(depth, lat, lon) ; vx:units = "furlongs/fortnight" ; float vy(depth, lat, lon) ; float vz(depth, lat, lon) ;)",
                                              R"(
  vx = 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0 ; vy = 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0 ;
  vz = 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0 ;)");
    expectReadError(ncgen(dir.path(), "odd", furlongs), {}, {"odd.nc: vx: velocity units 'furlongs/fortnight'"});
}

// CitcomS' order (--velocity vt,vp,vr --velocity-frame colatitude): colatitude (southward),
// longitude (eastward), radial. The same flow as above: 1 cm/yr up, 3 cm/yr north, 2 cm/yr east.
TEST(NetcdfReader, ColatitudeOrderedVelocityIsCitcomsOrder)
{
    TempDir dir("colatvel");
    const std::string cdl = depthGridCdl("vel", R"(
  float vt(depth, lat, lon) ; vt:units = "cm/yr" ;
  float vp(depth, lat, lon) ; vp:units = "cm/yr" ;
  float vr(depth, lat, lon) ; vr:units = "cm/yr" ;)",
                                         R"(
  vt = -3, -3, -3, -3, -3, -3, -3, -3, -3, -3, -3, -3, -3, -3, -3, -3 ;
  vp = 2, 2, 2, 2, 2, 2, 2, 2, 2, 2, 2, 2, 2, 2, 2, 2 ;
  vr = 1, 1, 1, 1, 1, 1, 1, 1, 1, 1, 1, 1, 1, 1, 1, 1 ;)");
    const auto path = ncgen(dir.path(), "vel", cdl);
    ReaderOptions o;
    o.variableNames = {{"vx", "vt"}, {"vy", "vp"}, {"vz", "vr"}};
    o.velocityFrame = ReaderOptions::VelocityFrame::Colatitude;
    const grid::Snapshot s = readSnapshot(path, o);
    const double cmPerYr = 0.01 / 3.15576e7;
    // At lat 45, lon 90: up = (0, cos 45, sin 45), north = (0, -sin 45, cos 45), east = (-1, 0, 0).
    const size_t i = s.grid.index(1, 0, 1);
    const double h = std::sqrt(0.5);
    EXPECT_NEAR(s.find("vx")->values[i], -2 * cmPerYr, 1e-6 * cmPerYr);
    EXPECT_NEAR(s.find("vy")->values[i], (h - 3 * h) * cmPerYr, 1e-6 * cmPerYr);
    EXPECT_NEAR(s.find("vz")->values[i], (h + 3 * h) * cmPerYr, 1e-6 * cmPerYr);
}

TEST(NetcdfReader, CfStandardNamesOfTheFlowAreTheSphericalVelocity)
{
    TempDir dir("cfvel");
    // The components named only by CF standard names, in another order than (up, north, east), beside a scalar.
    const std::string cdl = depthGridCdl("flow", R"(
  float w(depth, lat, lon) ; w:standard_name = "upward_mantle_velocity" ; w:units = "mm/yr" ;
  float u(depth, lat, lon) ; u:standard_name = "eastward_mantle_velocity" ; u:units = "mm/yr" ;
  float vs(depth, lat, lon) ; vs:units = "km/s" ;
  float v(depth, lat, lon) ; v:standard_name = "northward_mantle_velocity" ; v:units = "mm/yr" ;)",
                                         R"(
  w = 1, 1, 1, 1, 1, 1, 1, 1, 1, 1, 1, 1, 1, 1, 1, 1 ;
  u = 2, 2, 2, 2, 2, 2, 2, 2, 2, 2, 2, 2, 2, 2, 2, 2 ;
  vs = 4, 4, 4, 4, 4, 4, 4, 4, 4, 4, 4, 4, 4, 4, 4, 4 ;
  v = 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0 ;)");
    const auto path = ncgen(dir.path(), "flow", cdl);
    const FileHeader header = readHeader(path, {});
    std::map<std::string, FileHeader::Variable> byName;
    for (const auto& v : header.variables)
        byName[v.name] = v;
    ASSERT_EQ(byName.size(), 4u);
    ASSERT_TRUE(byName.contains("vx") && byName.contains("vy") && byName.contains("vz") && byName.contains("vs"));
    EXPECT_EQ(byName["vx"].fileName, "w");
    EXPECT_EQ(byName["vy"].fileName, "v");
    EXPECT_EQ(byName["vz"].fileName, "u");
    EXPECT_EQ(byName["vx"].units, "m/s");
    const grid::Snapshot s = readSnapshot(path, {});
    const double mmPerYr = 1e-3 / 3.15576e7;
    // At lat 45, lon 90: up = (0, cos 45, sin 45), east = (-1, 0, 0): v = 1 up + 2 east, mm/yr.
    const size_t i = s.grid.index(1, 0, 1);
    EXPECT_NEAR(s.find("vx")->values[i], -2 * mmPerYr, 1e-6 * mmPerYr);
    EXPECT_NEAR(s.find("vy")->values[i], std::sqrt(0.5) * mmPerYr, 1e-6 * mmPerYr);
    EXPECT_NEAR(s.find("vz")->values[i], std::sqrt(0.5) * mmPerYr, 1e-6 * mmPerYr);
    EXPECT_FLOAT_EQ(s.find("vs")->values[i], 4.0f);

    // Two of the three are no velocity: they stay the file's scalars, under their own names.
    const std::string two = depthGridCdl("two", R"(
  float w(depth, lat, lon) ; w:standard_name = "upward_mantle_velocity" ;
  float u(depth, lat, lon) ; u:standard_name = "eastward_mantle_velocity" ;)",
                                         R"(
  w = 1, 1, 1, 1, 1, 1, 1, 1, 1, 1, 1, 1, 1, 1, 1, 1 ;
  u = 2, 2, 2, 2, 2, 2, 2, 2, 2, 2, 2, 2, 2, 2, 2, 2 ;)");
    const FileHeader twoHeader = readHeader(ncgen(dir.path(), "two", two), {});
    ASSERT_EQ(twoHeader.variables.size(), 2u);
    EXPECT_EQ(twoHeader.variables[0].name, "w");
    EXPECT_EQ(twoHeader.variables[1].name, "u");

    // A velocity the user names wins over the standard names.
    ReaderOptions named;
    named.variableNames = {{"vx", "u"}, {"vy", "v"}, {"vz", "w"}};
    const grid::Snapshot cartesian = readSnapshot(path, named);
    EXPECT_NEAR(cartesian.find("vx")->values[i], 2 * mmPerYr, 1e-6 * mmPerYr);
    EXPECT_NEAR(cartesian.find("vz")->values[i], 1 * mmPerYr, 1e-6 * mmPerYr);
}

// A model with the 660 km discontinuity: its depth given twice, the values above it (3.5) and
// below it (4.0), the axis in either direction.
std::string discontinuityCdl(const std::string& name, bool depthDown)
{
    const std::string depths = depthDown ? "100, 660, 660, 2000" : "2000, 660, 660, 100";
    const std::string rho = depthDown ? "3.2, 3.5, 4.0, 5.0" : "5.0, 4.0, 3.5, 3.2";
    std::string values;
    for (int d = 0; d < 4; ++d)
        for (int k = 0; k < 8; ++k)
            values += (values.empty() ? "" : ", ") + split(rho, ',')[size_t(d)];
    return fmt::format(R"(netcdf {} {{
dimensions: depth = 4 ; lat = 2 ; lon = 4 ;
variables:
  double depth(depth) ; depth:units = "km" ; depth:positive = "down" ;
  double lat(lat) ; lat:units = "degrees_north" ; double lon(lon) ; lon:units = "degrees_east" ;
  float rho(depth, lat, lon) ; rho:units = "g/cc" ;
data:
  depth = {} ; lat = -45, 45 ; lon = 0, 90, 180, 270 ;
  rho = {} ;
}})",
                       name, depths, values);
}

TEST(NetcdfReader, ARepeatedDepthIsADiscontinuityWithBothSidesKept)
{
    TempDir dir("discontinuity");
    for (const bool depthDown : {true, false}) {
        SCOPED_TRACE(depthDown ? "depth ascending in the file" : "depth descending in the file");
        const auto path = ncgen(dir.path(), depthDown ? "down" : "up", discontinuityCdl(depthDown ? "down" : "up", depthDown));
        const grid::Snapshot s = readSnapshot(path, {});
        const grid::SphericalGrid& g = s.grid;
        ASSERT_EQ(g.nR(), 4u);
        const double r660 = kSurfaceRadiusKm - 660;
        // Both sides at 660 km, a metre apart, strictly ascending; the other radii as the file says.
        EXPECT_NEAR(g.rKm[0], kSurfaceRadiusKm - 2000, 1e-9);
        EXPECT_NEAR(g.rKm[1], r660, 0.001);
        EXPECT_NEAR(g.rKm[2], r660, 0.001);
        EXPECT_LT(g.rKm[1], g.rKm[2]);
        EXPECT_LT(g.rKm[1], r660);
        EXPECT_GT(g.rKm[2], r660);
        const grid::Field& rho = *s.find("rho");
        for (size_t iLat = 0; iLat < g.nLat(); ++iLat)
            for (size_t iLon = 0; iLon < g.nLon(); ++iLon) {
                EXPECT_FLOAT_EQ(rho.values[g.index(iLat, 1, iLon)], 4.0f);  // below the discontinuity
                EXPECT_FLOAT_EQ(rho.values[g.index(iLat, 2, iLon)], 3.5f);  // above it
            }
        // Nothing interpolates across it: a kilometre above and below, each side's values alone.
        const grid::GridSampler sampler(g);
        const auto above = sampler.locate(0, 45, r660 + 1);
        const auto below = sampler.locate(0, 45, r660 - 1);
        ASSERT_TRUE(above && below);
        EXPECT_NEAR(sampler.sample(rho.values.data(), *above), 3.5 - 0.3 / 560, 1e-4);
        EXPECT_NEAR(sampler.sample(rho.values.data(), *below), 4.0 + 1.0 / 1340, 1e-4);
    }
    // Three times is not a discontinuity.
    TempDir bad("thrice");
    std::string cdl = discontinuityCdl("thrice", true);
    cdl.replace(cdl.find("100, 660, 660, 2000"), 19, "660, 660, 660, 2000");
    expectReadError(ncgen(bad.path(), "thrice", cdl), {}, {"thrice.nc: coordinate 'depth' repeats the value", "three times"});
    std::string zigzag = discontinuityCdl("zigzag", true);
    zigzag.replace(zigzag.find("100, 660, 660, 2000"), 19, "660, 100, 660, 2000");
    expectReadError(ncgen(bad.path(), "zigzag", zigzag), {},
                    {"zigzag.nc: coordinate 'depth' is not monotonic: 100 after 660"});
}

TEST(NetcdfReaderBadInput, WrongDimensions)
{
    TempDir dir("wrongdims");
    const std::string cdl = R"(netcdf small {
dimensions: lat = 2 ; r = 2 ; lon = 4 ;
variables:
  double lat(lat) ; double r(r) ; r:units = "km" ; double lon(lon) ;
  float temperature(r, lat) ;
data:
  lat = -45, 45 ; r = 3485, 6371 ; lon = 0, 90, 180, 270 ; temperature = 1, 2, 3, 4 ;
})";
    const auto path = ncgen(dir.path(), "small", cdl);
    expectReadError(path, temperatureOnly(), {"small.nc", "temperature", "dims (r, lat)", "expected 3 dims"});
}

TEST(NetcdfReaderBadInput, NanAndFillValues)
{
    TempDir dir("nan");
    const auto nan = ncgen(dir.path(), "nan", smallCdl("1, 2, 3, 4, 5, NaN, 7, 8, 9, 10, 11, 12, 13, 14, 15, 16"));
    expectMissingOnlyAt(nan, temperatureOnly(), {{1, 1, 1}});
    const auto filled = ncgen(dir.path(), "fill",
                              smallCdl("1, 2, 3, 4, 5, -999, 7, 8, 9, 10, 11, 12, 13, 14, 15, 16",
                                       "temperature:_FillValue = -999.f ;"));
    expectMissingOnlyAt(filled, temperatureOnly(), {{1, 1, 1}});
    ReaderOptions fill = temperatureOnly();
    fill.fillMissing = true;
    const grid::Snapshot s = readSnapshot(filled, fill);
    // File row lat=45 becomes canonical row 1; its r=6371 shell holds 5, -999, 7, 8 and the
    // other row's 13..16: the mean of the valid values on that shell.
    const double shellMean = (5 + 7 + 8 + 13 + 14 + 15 + 16) / 7.0;
    EXPECT_NEAR(s.fields[0].values[s.grid.index(1, 1, 1)], shellMean, 1e-5);
}

TEST(NetcdfReaderBadInput, GridsThatDifferBetweenStepsStopPreprocessing)
{
    TempDir dir("griddiff");
    const std::string values = "1, 2, 3, 4, 5, 6, 7, 8, 9, 10, 11, 12, 13, 14, 15, 16";
    auto withVelocity = [&](const std::string& r) {
        std::string cdl = smallCdl(values, "float vx(lat, r, lon) ; float vy(lat, r, lon) ; float vz(lat, r, lon) ;", r);
        cdl.insert(cdl.rfind('}'), "vx = " + values + " ; vy = " + values + " ; vz = " + values + " ;\n");
        return cdl;
    };
    const auto a = ncgen(dir.path(), "step1", withVelocity("3485, 6371"));
    const auto b = ncgen(dir.path(), "step2", withVelocity("3500, 6371"));
    preprocess::PreprocessOptions options;
    options.reader.variables = {"temperature", "vx", "vy", "vz"};
    options.quiet = true;
    options.sampleRows = 100;
    try {
        preprocess::preprocess({a, b}, dir / "out", options);
        FAIL() << "grids that differ were accepted";
    } catch (const Error& e) {
        EXPECT_NE(std::string(e.what()).find("step2.nc"), std::string::npos) << e.what();
        EXPECT_NE(std::string(e.what()).find("differ from the first step"), std::string::npos) << e.what();
    }
    EXPECT_THROW(dataset::Dataset::open(dir / "out"), Error);  // no complete dataset was left behind
}

TEST(NetcdfReader, ListsFilesInNaturalOrder)
{
    TempDir dir("natural");
    for (const char* name : {"spherical10.nc", "spherical9.nc", "spherical100.nc", "notes.txt"})
        writeFileAtomic(dir / name, std::string_view("x"));
    const auto files = listSnapshotFiles({dir.path()});
    ASSERT_EQ(files.size(), 3u);
    EXPECT_EQ(files[0].filename(), "spherical9.nc");
    EXPECT_EQ(files[1].filename(), "spherical10.nc");
    EXPECT_EQ(files[2].filename(), "spherical100.nc");
    EXPECT_THROW(listSnapshotFiles({dir / "missing.nc"}), Error);
}

}  // namespace
}  // namespace raypc::io
