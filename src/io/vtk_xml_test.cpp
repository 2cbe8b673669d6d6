// The VTK XML reader against files of two independent writers: Python's standard library in every
// encoding the format allows (tests/data/vtk-xml, written at test time), and deal.II 9.4's DataOut,
// the library ASPECT writes its output with (tests/data/aspect-layout).
#include "io/vtk_xml.h"

#include "core/atomic_file.h"
#include "core/error.h"

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include <fmt/format.h>
#include <sys/resource.h>

#include <cmath>
#include <cstdio>
#include <fstream>
#include <filesystem>
#include <functional>

namespace raypc::io::vtk {
namespace {

namespace fs = std::filesystem;

fs::path variantsDir() { return fs::path(RAYPC_TEST_DATA_DIR) / "vtk-xml"; }
fs::path lagrangeShellDir() { return fs::path(RAYPC_SOURCE_DIR) / "tests/data/aspect-layout/shell-lagrange"; }

nlohmann::json readJson(const fs::path& path) { return nlohmann::json::parse(readFile(path)); }

std::string errorOf(const std::function<void()>& f)
{
    try {
        f();
    } catch (const Error& e) {
        return e.what();
    }
    return "";
}

// Every variant (ascii; binary and appended raw/base64, plain or zlib, UInt32 or UInt64 headers,
// Float32 or Float64; one big-endian file) holds the same mesh with f = x + 2y + 3z, v = (y, -x, z).
TEST(VtkXml, EveryEncodingReadsTheSameMesh)
{
    const auto truth = readJson(variantsDir() / "truth.json");
    ASSERT_GE(truth["variants"].size(), 27u);
    for (const auto& name : truth["variants"]) {
        SCOPED_TRACE(name.get<std::string>());
        const Piece piece = readVtu(variantsDir() / name.get<std::string>());
        ASSERT_EQ(piece.pointCount(), truth["points"].get<size_t>());
        ASSERT_EQ(piece.cellCount(), truth["cells"].get<size_t>());
        for (size_t c = 0; c < piece.cellCount(); ++c) {
            EXPECT_EQ(int(piece.types[c]), truth["types"][c].get<int>());
            EXPECT_EQ(piece.offsets[c], truth["offsets"][c].get<int64_t>());
        }
        EXPECT_EQ(cellDegree(piece.types[3], piece.offsets[3] - piece.cellBegin(3)), 2);
        ASSERT_TRUE(piece.time && piece.cycle);
        EXPECT_DOUBLE_EQ(*piece.time, 1.5e6);
        EXPECT_EQ(*piece.cycle, 7);
        const PointArray* f = piece.find("f");
        const PointArray* v = piece.find("v");
        ASSERT_TRUE(f && v);
        ASSERT_EQ(v->components, 3);
        for (size_t i = 0; i < piece.pointCount(); ++i) {
            const double x = piece.points[3 * i], y = piece.points[3 * i + 1], z = piece.points[3 * i + 2];
            ASSERT_FLOAT_EQ(f->values[i], float(x + 2 * y + 3 * z)) << "point " << i;
            ASSERT_FLOAT_EQ(v->values[3 * i], float(y));
            ASSERT_FLOAT_EQ(v->values[3 * i + 1], float(-x));
            ASSERT_FLOAT_EQ(v->values[3 * i + 2], float(z));
        }
        // Connectivity points every cell at its own points (DataOut's patches).
        for (size_t k = 0; k < piece.connectivity.size(); ++k)
            ASSERT_EQ(piece.connectivity[k], int64_t(k));
    }
}

TEST(VtkXml, CollectionAndRecordNameTheirFilesRelativeToThemselves)
{
    const auto steps = readPvd(variantsDir() / "series.pvd");
    ASSERT_EQ(steps.size(), 2u);
    EXPECT_EQ(steps[0].time, 0.0);
    EXPECT_EQ(steps[1].time, 2e6);
    EXPECT_EQ(steps[1].file, variantsDir() / "sub/record.pvtu");
    const PieceRecord record = readPvtu(steps[1].file);
    ASSERT_EQ(record.pieces.size(), 2u);
    EXPECT_EQ(record.pieces[0], variantsDir() / "sub/binary-zlib-UInt32-Float32.vtu");
    ASSERT_EQ(record.pointArrays.size(), 2u);
    EXPECT_EQ(record.pointArrays[1], std::make_pair(std::string("v"), 3));
    for (const auto& p : record.pieces)
        EXPECT_EQ(readVtu(p).cellCount(), 4u);
}

TEST(VtkXml, CellDegrees)
{
    EXPECT_EQ(cellDegree(CellType::Tetra, 4), 1);
    EXPECT_EQ(cellDegree(CellType::Tetra, 8), 0);
    EXPECT_EQ(cellDegree(CellType::Wedge, 6), 1);
    EXPECT_EQ(cellDegree(CellType::Hexahedron, 8), 1);
    EXPECT_EQ(cellDegree(CellType::LagrangeHexahedron, 8), 1);
    EXPECT_EQ(cellDegree(CellType::LagrangeHexahedron, 27), 2);
    EXPECT_EQ(cellDegree(CellType::LagrangeHexahedron, 64), 3);
    EXPECT_EQ(cellDegree(CellType::LagrangeHexahedron, 26), 0);
}

// Each bad file gives one short message naming the file and what is wrong.
// Base64 of `bytes` (the test's own encoder, for crafted files).
std::string base64Of(const std::string& bytes)
{
    static const char* digits = "ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/";
    std::string out;
    for (size_t i = 0; i < bytes.size(); i += 3) {
        const uint32_t b0 = uint8_t(bytes[i]), b1 = i + 1 < bytes.size() ? uint8_t(bytes[i + 1]) : 0,
                       b2 = i + 2 < bytes.size() ? uint8_t(bytes[i + 2]) : 0;
        const uint32_t v = b0 << 16 | b1 << 8 | b2;
        out += digits[v >> 18 & 63], out += digits[v >> 12 & 63];
        out += i + 1 < bytes.size() ? digits[v >> 6 & 63] : '=';
        out += i + 2 < bytes.size() ? digits[v & 63] : '=';
    }
    return out;
}

// A base64 array whose header claims 4 GB (within what the Piece's counts allow for a file of this
// size) in a file of 180 KB: refused as data that ends early, without allocating the claim. Under an
// address-space limit of 1 GB more than the process uses, the old reader's reserve of the claimed
// size failed (std::bad_alloc, or ASan's out-of-memory abort that the fuzzer found).
TEST(VtkXmlBadInput, AHugeClaimInABase64ArrayIsNotAllocated)
{
    const uint64_t points = 170'000'000, bytes = points * 3 * sizeof(double);
    std::string header(8, '\0');
    for (int i = 0; i < 8; ++i)
        header[size_t(i)] = char(bytes >> (8 * i) & 0xff);
    const std::string file = fmt::format(
        R"(<VTKFile type="UnstructuredGrid" version="1.0" byte_order="LittleEndian" header_type="UInt64">
<!-- {} -->
<UnstructuredGrid><Piece NumberOfPoints="{}" NumberOfCells="0"><Points>
<DataArray type="Float64" NumberOfComponents="3" format="binary">{}</DataArray></Points>
<Cells><DataArray type="Int64" Name="connectivity" format="ascii"></DataArray>
<DataArray type="Int64" Name="offsets" format="ascii"></DataArray><DataArray type="UInt8" Name="types" format="ascii"></DataArray></Cells>
</Piece></UnstructuredGrid></VTKFile>)",
        std::string(180'000, 'x'), points, base64Of(header + std::string(24, '\1')));
    EXPECT_EXIT(
        {
            rlimit limit{};
            getrlimit(RLIMIT_AS, &limit);
            std::ifstream status("/proc/self/status");
            std::string line;
            uint64_t vmKb = 0;
            while (std::getline(status, line))
                if (line.rfind("VmSize:", 0) == 0)
                    vmKb = std::stoull(line.substr(7));
            limit.rlim_cur = rlim_t(vmKb * 1024 + (uint64_t(1) << 30));
            setrlimit(RLIMIT_AS, &limit);
            try {
                parseVtu(file, "claim.vtu");
            } catch (const Error& e) {
                std::fprintf(stderr, "%s\n", e.what());
                std::exit(std::string(e.what()).find("data ends") != std::string::npos ? 0 : 2);
            } catch (const std::exception& e) {
                std::fprintf(stderr, "not a raypc::Error: %s\n", e.what());
                std::exit(3);
            }
            std::exit(4);
        },
        ::testing::ExitedWithCode(0), "claim.vtu: Points: data ends");
}

TEST(VtkXmlBadInput, OneClearErrorEach)
{
    const struct {
        const char* file;
        const char* expected;
    } cases[] = {
        {"truncated.vtu", "truncated"},
        {"bad-zlib.vtu", "does not decompress"},
        {"not-xml.vtu", "not valid XML"},
        {"wrong-type.vtu", "type \"PolyData\", expected UnstructuredGrid"},
        {"bad-cell.vtu", "cell 3 has VTK type 42"},
        {"bad-index.vtu", "point index 999"},
        {"big-count.vtu", "expected 48000000 bytes"},
        {"count-not-a-number.vtu", "NumberOfPoints \"abc\", expected a whole number"},
        {"zero-block-size.vtu", "blocks of 0 bytes each"},
        {"nan-value.vtu", "PointData f: nan at point 30 is not a number"},
        {"inf-value.vtu", "PointData v: inf at point 0 (component 0) is infinite"},
        {"huge-value.vtu", "PointData f: 1e+39 at point 3 is beyond float32's range"},
        {"no-such-file.vtu", "no such file"},
    };
    for (const auto& c : cases) {
        const fs::path path = variantsDir() / c.file;
        const std::string message = errorOf([&] { readVtu(path); });
        EXPECT_NE(message.find(c.expected), std::string::npos) << c.file << ": " << message;
        EXPECT_NE(message.find(path.string()), std::string::npos) << message;
        EXPECT_LT(message.size(), path.string().size() + 200) << message;
    }
    EXPECT_NE(errorOf([] { readPvd(variantsDir() / "times-backwards.pvd"); }).find("does not follow"), std::string::npos);
    EXPECT_NE(errorOf([] { readPvtu(variantsDir() / "outside.pvtu"); }).find("Piece Source \"../secret.vtu\" lies outside"),
              std::string::npos);
    EXPECT_NE(errorOf([] { readPvd(variantsDir() / "no-timestep.pvd"); }).find("DataSet record.pvtu has no timestep"),
              std::string::npos);
    EXPECT_NE(errorOf([] { readPvtu(variantsDir() / "nowhere.pvtu"); }).find("no such file"), std::string::npos);
    EXPECT_NE(errorOf([] { readPvd(variantsDir() / "record.pvtu"); }).find("expected Collection"), std::string::npos);
}

// deal.II's DataOut with "Write higher order output" (ASPECT's layout): Lagrange hexahedra of degree
// 2 in two pieces, two steps. Values at the nodes against the analytic truth.
TEST(VtkXml, DealIiLagrangeShellMatchesTruth)
{
    const auto truth = readJson(lagrangeShellDir() / "truth.json");
    const auto steps = readPvd(lagrangeShellDir() / "solution.pvd");
    ASSERT_EQ(steps.size(), truth["steps"].get<size_t>());
    const double omega = truth["omega_rad_per_year"], u0 = truth["u0_m_per_year"];
    size_t cells = 0;
    double worstVelocity = 0, worstPressure = 0;
    for (size_t s = 0; s < steps.size(); ++s) {
        EXPECT_DOUBLE_EQ(steps[s].time, double(s) * truth["dt_years"].get<double>());
        const PieceRecord record = readPvtu(steps[s].file);
        ASSERT_EQ(record.pieces.size(), truth["pieces"].get<size_t>());
        for (const auto& path : record.pieces) {
            const Piece piece = readVtu(path);
            ASSERT_TRUE(piece.time);
            EXPECT_DOUBLE_EQ(*piece.time, steps[s].time);
            if (s == 0)
                cells += piece.cellCount();
            for (size_t c = 0; c < piece.cellCount(); ++c) {
                ASSERT_EQ(piece.types[c], CellType::LagrangeHexahedron);
                ASSERT_EQ(cellDegree(piece.types[c], piece.offsets[c] - piece.cellBegin(c)), 2);
            }
            const PointArray* velocity = piece.find("velocity");
            const PointArray* p = piece.find("p");
            ASSERT_TRUE(velocity && p && piece.find("T") && piece.find("nonadiabatic_temperature"));
            ASSERT_EQ(velocity->components, 3);
            for (size_t i = 0; i < piece.pointCount(); ++i) {
                const double x = piece.points[3 * i], y = piece.points[3 * i + 1], z = piece.points[3 * i + 2];
                const double r = std::sqrt(x * x + y * y + z * z);
                ASSERT_GT(r, 3485e3 * (1 - 1e-6));
                ASSERT_LT(r, 6371e3 * (1 + 1e-6));
                const double expected[3] = {-omega * y + u0 * x / r, omega * x + u0 * y / r, u0 * z / r};
                for (int k = 0; k < 3; ++k)
                    worstVelocity = std::max(worstVelocity, std::abs(velocity->values[3 * i + k] - expected[k]));
                worstPressure = std::max(worstPressure, std::abs(p->values[i] - 3300 * 9.81 * (6371e3 - r)));
            }
        }
    }
    EXPECT_EQ(cells, truth["cells"].get<size_t>());
    // |v| is about 0.1 m/yr and p up to 9.3e10 Pa; the nodes carry the interpolated field exactly
    // up to float32 and the geometry's own rounding.
    EXPECT_LT(worstVelocity, 1e-6 * 0.1 + 1e-7) << worstVelocity;
    EXPECT_LT(worstPressure, 1e-5 * 9.3e10) << worstPressure;
}

}  // namespace
}  // namespace raypc::io::vtk
