#include "io/citcoms.h"

#include "core/atomic_file.h"
#include "core/error.h"
#include "core/spherical.h"

#include <fmt/format.h>
#include <fmt/ranges.h>
#include <hdf5.h>

#include <algorithm>
#include <array>
#include <cctype>
#include <cmath>
#include <cstdlib>
#include <map>
#include <mutex>
#include <regex>

namespace raypc::io::citcoms {
namespace {

namespace fs = std::filesystem;

constexpr int kFullSphereCaps = 12;
constexpr double kSecondsPerMyr = 3.15576e13;

// `NAME.capNN.STEP` and `NAME.STEP.h5`, after a `.general` suffix is taken off.
const std::regex& capPattern()
{
    static const std::regex pattern(R"((.+)\.cap(\d\d)\.(\d+))");
    return pattern;
}
const std::regex& h5Pattern()
{
    static const std::regex pattern(R"((.+)\.(\d+)\.h5)");
    return pattern;
}

fs::path withoutGeneral(const fs::path& path)
{
    return path.extension() == ".general" ? path.parent_path() / path.stem() : path;
}

// One cap's nodes: (i, j, k) with k along the radius, at `index(i, j, k)` of the arrays.
struct CapBlock {
    size_t nx = 0, ny = 0, nz = 0;
    size_t nodes() const { return nx * ny * nz; }
    size_t index(size_t i, size_t j, size_t k) const { return (i * ny + j) * nz + k; }
};

// The arrays of one cap, nondimensional as written, node-major in CapBlock's order.
struct CapValues {
    CapBlock block;
    std::vector<double> colatLonR;  // 3 a node
    std::vector<double> velocity;   // 3 a node: colatitude, longitude, radial components
    std::vector<double> temperature, viscosity, pressure;
};

// The cap as a piece of the mesh: hexahedra between neighbouring nodes, points in km, the
// velocity turned into Cartesian components in m/s.
vtk::Piece toPiece(const CapValues& cap, const Scales& scales, const std::string& what)
{
    const CapBlock& b = cap.block;
    if (b.nx < 2 || b.ny < 2 || b.nz < 2)
        fail("{}: a cap of {} x {} x {} nodes has no cells", what, b.nx, b.ny, b.nz);
    vtk::Piece piece;
    piece.points.resize(3 * b.nodes());
    const double velocityScale = scales.diffusivityM2s / (scales.radiusKm * 1e3);  // κ/R, m/s
    const double temperatureScale = scales.temperatureK > 0 ? scales.temperatureK : 1.0;
    vtk::PointArray temperature{"temperature", 1, std::vector<float>(b.nodes())};
    vtk::PointArray velocity{"velocity", 3, std::vector<float>(3 * b.nodes())};
    vtk::PointArray viscosity{"viscosity", 1, std::vector<float>(b.nodes())};
    vtk::PointArray pressure{"pressure", 1, std::vector<float>(cap.pressure.empty() ? 0 : b.nodes())};
    for (size_t n = 0; n < b.nodes(); ++n) {
        const double latDeg = 90.0 - radToDeg(cap.colatLonR[3 * n]), lonDeg = radToDeg(cap.colatLonR[3 * n + 1]);
        const Vec3d up = sphericalToCartesianKm(latDeg, lonDeg, 1.0);
        const Vec3d p = cap.colatLonR[3 * n + 2] * scales.radiusKm * up;
        piece.points[3 * n] = p.x, piece.points[3 * n + 1] = p.y, piece.points[3 * n + 2] = p.z;
        // v = v_θ e_θ + v_φ e_φ + v_r e_r, with e_θ (colatitude growing) pointing south: -north.
        const EastNorth en = eastNorthAt(latDeg, lonDeg);
        const Vec3d v = (-cap.velocity[3 * n]) * en.north + cap.velocity[3 * n + 1] * en.east + cap.velocity[3 * n + 2] * up;
        velocity.values[3 * n] = float(v.x * velocityScale);
        velocity.values[3 * n + 1] = float(v.y * velocityScale);
        velocity.values[3 * n + 2] = float(v.z * velocityScale);
        temperature.values[n] = float(cap.temperature[n] * temperatureScale);
        viscosity.values[n] = float(cap.viscosity[n]);
        if (!cap.pressure.empty())
            pressure.values[n] = float(cap.pressure[n]);
    }
    const size_t cells = (b.nx - 1) * (b.ny - 1) * (b.nz - 1);
    piece.connectivity.reserve(8 * cells);
    piece.offsets.reserve(cells);
    piece.types.assign(cells, vtk::CellType::Hexahedron);
    for (size_t i = 0; i + 1 < b.nx; ++i)
        for (size_t j = 0; j + 1 < b.ny; ++j)
            for (size_t k = 0; k + 1 < b.nz; ++k) {
                // VTK's hexahedron: the inner face counterclockwise, then the outer one above it.
                for (const size_t kk : {k, k + 1})
                    for (const auto& [di, dj] : {std::pair{0, 0}, {1, 0}, {1, 1}, {0, 1}})
                        piece.connectivity.push_back(int64_t(b.index(i + size_t(di), j + size_t(dj), kk)));
                piece.offsets.push_back(int64_t(piece.connectivity.size()));
            }
    piece.pointData = {std::move(temperature), std::move(velocity), std::move(viscosity)};
    if (!cap.pressure.empty())
        piece.pointData.push_back(std::move(pressure));
    return piece;
}

void checkFiniteValues(const std::vector<double>& values, const std::string& what, const char* array)
{
    const auto bad = std::find_if(values.begin(), values.end(), [](double v) { return !std::isfinite(v); });
    if (bad != values.end())
        fail("{}: {} holds {} at value {}; RayPC needs a finite value at every node", what, array, *bad,
             bad - values.begin());
}

// ---------------------------------------------------------------------------------------------
// The combined cap files (ASCII).

CapValues readCapFile(const fs::path& path)
{
    const std::string file = path.string();
    std::error_code ec;
    if (!fs::is_regular_file(path, ec))
        fail("{}: no such file", file);
    const std::string text = readFile(path);
    const size_t eol = text.find('\n');
    const std::string header = text.substr(0, eol);
    CapValues cap;
    std::smatch m;
    static const std::regex shape(R"(\s*(\d+)\s*x\s*(\d+)\s*x\s*(\d+)\s*)");
    if (!std::regex_match(header, m, shape))
        fail("{}: header \"{}\", expected the cap's shape \"nx x ny x nz\" (CitcomS' combined cap file)", file,
             header.substr(0, 60));
    CapBlock& b = cap.block;
    b.nx = std::stoul(m[1]), b.ny = std::stoul(m[2]), b.nz = std::stoul(m[3]);
    // A node's row takes at least 16 bytes of text: more nodes than that is a corrupt header.
    if (b.nx == 0 || b.ny == 0 || b.nz == 0 || b.nx * b.ny * b.nz > text.size() / 16 + 1)
        fail("{}: header \"{}\" announces {} x {} x {} nodes, which a file of {} bytes cannot hold", file, header,
             b.nx, b.ny, b.nz, text.size());
    const size_t nodes = b.nodes();
    std::vector<double> rows;
    rows.reserve(8 * nodes);
    const char* p = text.data() + (eol == std::string::npos ? text.size() : eol + 1);
    const char* end = text.data() + text.size();
    while (p < end) {
        while (p < end && std::isspace(static_cast<unsigned char>(*p)))
            ++p;
        if (p == end)
            break;
        char* next = nullptr;
        const double v = std::strtod(p, &next);
        if (next == p)
            fail("{}: not a number after {} values: \"{}\"", file, rows.size(), std::string(p, std::min<size_t>(20, size_t(end - p))));
        if (rows.size() == 8 * nodes)
            fail("{}: more than the {} rows its header \"{}\" announces", file, nodes, header);
        rows.push_back(v);
        p = next;
    }
    if (rows.size() != 8 * nodes)
        fail("{}: {} values ({} rows of 8), its header \"{}\" announces {} nodes of 8 (colatitude, longitude, radius, "
             "three velocity components, temperature, viscosity)",
             file, rows.size(), rows.size() / 8, header, nodes);
    checkFiniteValues(rows, file, "a row");
    cap.colatLonR.resize(3 * nodes), cap.velocity.resize(3 * nodes), cap.temperature.resize(nodes),
        cap.viscosity.resize(nodes);
    // Rows in CitcomS' order: y outermost, then x, z fastest (visual/combine.py).
    size_t row = 0;
    for (size_t j = 0; j < b.ny; ++j)
        for (size_t i = 0; i < b.nx; ++i)
            for (size_t k = 0; k < b.nz; ++k, ++row) {
                const size_t n = b.index(i, j, k);
                const double* r = rows.data() + 8 * row;
                std::copy(r, r + 3, cap.colatLonR.begin() + long(3 * n));
                std::copy(r + 3, r + 6, cap.velocity.begin() + long(3 * n));
                cap.temperature[n] = r[6];
                cap.viscosity[n] = r[7];
            }
    return cap;
}

Step readCapStep(const fs::path& step, const Scales& scales)
{
    std::smatch m;
    const std::string name = step.filename().string();
    if (!std::regex_match(name, m, capPattern()))
        fail("{}: not a CitcomS cap file (NAME.capNN.STEP)", step.string());
    const std::string prefix = m[1], number = m[3];
    const auto capPath = [&](int cap) { return step.parent_path() / fmt::format("{}.cap{:02d}.{}", prefix, cap, number); };
    std::vector<int> present, missing;
    for (int cap = 0; cap < kFullSphereCaps; ++cap) {
        std::error_code ec;
        (fs::exists(capPath(cap), ec) ? present : missing).push_back(cap);
    }
    // One cap (cap 00) is a regional model; a full sphere has twelve.
    if (!(present.size() == size_t(kFullSphereCaps) || (present.size() == 1 && present[0] == 0)))
        fail("{}: {} caps of step {} found; a full sphere has 12 (missing: {}), a regional model one (cap 00)",
             step.string(), present.size(), number, fmt::join(missing, ", "));
    Step out;
    out.format = formatName(step);
    for (const int cap : present) {
        const CapValues values = readCapFile(capPath(cap));
        out.nx = values.block.nx, out.ny = values.block.ny, out.nz = values.block.nz;
        out.caps.push_back(toPiece(values, scales, capPath(cap).string()));
    }
    return out;
}

// ---------------------------------------------------------------------------------------------
// HDF5 output.

std::mutex& hdf5Mutex()
{
    static std::mutex mutex;
    return mutex;
}

// An HDF5 handle closed by `close` when it goes.
class Handle {
public:
    Handle(hid_t id, herr_t (*close)(hid_t)) : m_id(id), m_close(close) {}
    ~Handle()
    {
        if (m_id >= 0)
            m_close(m_id);
    }
    Handle(Handle&& other) noexcept : m_id(other.m_id), m_close(other.m_close) { other.m_id = -1; }
    Handle(const Handle&) = delete;
    Handle& operator=(const Handle&) = delete;
    Handle& operator=(Handle&&) = delete;
    hid_t id() const { return m_id; }
    explicit operator bool() const { return m_id >= 0; }

private:
    hid_t m_id;
    herr_t (*m_close)(hid_t);
};

Handle openFile(const fs::path& path)
{
    std::error_code ec;
    if (!fs::is_regular_file(path, ec))
        fail("{}: no such file", path.string());
    Handle file(H5Fopen(path.c_str(), H5F_ACC_RDONLY, H5P_DEFAULT), H5Fclose);
    if (!file)
        fail("{}: not an HDF5 file (or a damaged one)", path.string());
    return file;
}

// A dataset's values as double, with its dimensions; nullopt when the file has no such dataset.
struct Array {
    std::vector<hsize_t> dims;
    std::vector<double> values;
};
std::optional<Array> readArray(hid_t file, const char* name, const std::string& what)
{
    if (H5Lexists(file, name, H5P_DEFAULT) <= 0)
        return std::nullopt;
    Handle set(H5Dopen2(file, name, H5P_DEFAULT), H5Dclose);
    if (!set)
        fail("{}: {} is not a dataset", what, name);
    Handle space(H5Dget_space(set.id()), H5Sclose);
    const int rank = H5Sget_simple_extent_ndims(space.id());
    if (rank < 1 || rank > 8)
        fail("{}: {} has {} dims", what, name, rank);
    Array a;
    a.dims.resize(size_t(rank));
    H5Sget_simple_extent_dims(space.id(), a.dims.data(), nullptr);
    hsize_t count = 1;
    for (const hsize_t d : a.dims) {
        if (d == 0 || count > (hsize_t(1) << 34) / d)
            fail("{}: {} has dims ({}), more than RayPC reads", what, name, fmt::join(a.dims, ", "));
        count *= d;
    }
    a.values.resize(size_t(count));
    if (H5Dread(set.id(), H5T_NATIVE_DOUBLE, H5S_ALL, H5S_ALL, H5P_DEFAULT, a.values.data()) < 0)
        fail("{}: {} cannot be read as numbers (a damaged file?)", what, name);
    return a;
}

// A numeric attribute of `object` (a group or the file's root), or nullopt.
std::optional<double> numberAttribute(hid_t file, const char* object, const char* name)
{
    if (H5Aexists_by_name(file, object, name, H5P_DEFAULT) <= 0)
        return std::nullopt;
    Handle attribute(H5Aopen_by_name(file, object, name, H5P_DEFAULT, H5P_DEFAULT), H5Aclose);
    Handle space(H5Aget_space(attribute.id()), H5Sclose);
    if (!attribute || H5Sget_simple_extent_npoints(space.id()) != 1)
        return std::nullopt;
    double value = 0;
    if (H5Aread(attribute.id(), H5T_NATIVE_DOUBLE, &value) < 0 || !std::isfinite(value))
        return std::nullopt;
    return value;
}

// The coordinates' file of an HDF5 step `NAME.STEP.h5`: `NAME.h5` beside it.
fs::path coordFileOf(const fs::path& step)
{
    std::smatch m;
    const std::string name = step.filename().string();
    if (!std::regex_match(name, m, h5Pattern()))
        fail("{}: not a CitcomS HDF5 step file (NAME.STEP.h5)", step.string());
    return step.parent_path() / (std::string(m[1]) + ".h5");
}

// The run's own scales (`/input`'s radius_km and thermdiff), unless the command line gave them.
Scales runScales(hid_t coordFile, Scales scales, bool scalesGiven)
{
    if (!scalesGiven) {
        if (const auto r = numberAttribute(coordFile, "/input", "radius_km"); r && *r > 0)
            scales.radiusKm = *r;
        if (const auto k = numberAttribute(coordFile, "/input", "thermdiff"); k && *k > 0)
            scales.diffusivityM2s = *k;
    }
    return scales;
}

double myrOf(double nondimensionalTime, const Scales& scales)
{
    return nondimensionalTime * std::pow(scales.radiusKm * 1e3, 2) / scales.diffusivityM2s / kSecondsPerMyr;
}

Step readH5Step(const fs::path& step, Scales scales, bool scalesGiven)
{
    const fs::path coordPath = coordFileOf(step);
    std::lock_guard lock(hdf5Mutex());
    H5Eset_auto2(H5E_DEFAULT, nullptr, nullptr);  // errors are reported here, not printed by HDF5
    const Handle coordFile = openFile(coordPath);
    const Handle stepFile = openFile(step);
    scales = runScales(coordFile.id(), scales, scalesGiven);
    const std::string coordWhat = coordPath.string(), stepWhat = step.string();
    const auto coord = readArray(coordFile.id(), "coord", coordWhat);
    if (!coord)
        fail("{}: no dataset 'coord' (the nodes' colatitude, longitude and radius of CitcomS' HDF5 output)", coordWhat);
    if (coord->dims.size() != 5 || coord->dims[4] != 3)
        fail("{}: coord has dims ({}), expected (caps, nx, ny, nz, 3)", coordWhat, fmt::join(coord->dims, ", "));
    const hsize_t caps = coord->dims[0];
    CapBlock block{size_t(coord->dims[1]), size_t(coord->dims[2]), size_t(coord->dims[3])};
    const auto expect = [&](const std::optional<Array>& a, const char* array, hsize_t components) {
        if (!a)
            fail("{}: no dataset '{}'", stepWhat, array);
        std::vector<hsize_t> want{caps, block.nx, block.ny, block.nz};
        if (components > 1)
            want.push_back(components);
        if (a->dims != want)
            fail("{}: {} has dims ({}), expected ({}) as {}'s coord", stepWhat, array, fmt::join(a->dims, ", "),
                 fmt::join(want, ", "), coordPath.filename().string());
        checkFiniteValues(a->values, stepWhat, array);
    };
    checkFiniteValues(coord->values, coordWhat, "coord");
    const auto temperature = readArray(stepFile.id(), "temperature", stepWhat);
    const auto velocity = readArray(stepFile.id(), "velocity", stepWhat);
    const auto viscosity = readArray(stepFile.id(), "viscosity", stepWhat);
    const auto pressure = readArray(stepFile.id(), "pressure", stepWhat);
    expect(temperature, "temperature", 1);
    expect(velocity, "velocity", 3);
    expect(viscosity, "viscosity", 1);
    if (pressure)
        expect(pressure, "pressure", 1);
    if (caps != 1 && caps != hsize_t(kFullSphereCaps))
        fail("{}: coord holds {} caps; a full sphere has 12, a regional model one", coordWhat, caps);

    Step out;
    out.format = formatName(step);
    out.nx = block.nx, out.ny = block.ny, out.nz = block.nz;
    const size_t nodes = block.nodes();
    for (size_t cap = 0; cap < caps; ++cap) {
        // HDF5's arrays are [cap][x][y][z], CapBlock's order within a cap.
        CapValues values;
        values.block = block;
        values.colatLonR.assign(coord->values.begin() + long(3 * nodes * cap), coord->values.begin() + long(3 * nodes * (cap + 1)));
        values.velocity.assign(velocity->values.begin() + long(3 * nodes * cap), velocity->values.begin() + long(3 * nodes * (cap + 1)));
        values.temperature.assign(temperature->values.begin() + long(nodes * cap), temperature->values.begin() + long(nodes * (cap + 1)));
        values.viscosity.assign(viscosity->values.begin() + long(nodes * cap), viscosity->values.begin() + long(nodes * (cap + 1)));
        if (pressure)
            values.pressure.assign(pressure->values.begin() + long(nodes * cap), pressure->values.begin() + long(nodes * (cap + 1)));
        out.caps.push_back(toPiece(values, scales, fmt::format("{} (cap {})", stepWhat, cap)));
    }
    // Nondimensional time in R²/κ.
    if (const auto t = numberAttribute(stepFile.id(), "/", "time"))
        out.timeMyr = myrOf(*t, scales);
    return out;
}

}  // namespace

bool isStep(const fs::path& path)
{
    const std::string name = withoutGeneral(path).filename().string();
    std::smatch m;
    if (std::regex_match(name, m, capPattern()))
        return true;
    return std::regex_match(name, m, h5Pattern());
}

long stepNumber(const fs::path& step)
{
    const std::string name = withoutGeneral(step).filename().string();
    std::smatch m;
    if (std::regex_match(name, m, capPattern()))
        return std::stol(m[3]);
    if (std::regex_match(name, m, h5Pattern()))
        return std::stol(m[2]);
    return -1;
}

std::vector<fs::path> stepsIn(const fs::path& directory)
{
    std::map<long, fs::path> caps, h5;
    std::error_code ec;
    for (const auto& entry : fs::directory_iterator(directory, ec)) {
        const std::string name = entry.path().filename().string();
        std::smatch m;
        if (std::regex_match(name, m, capPattern()) && m[2] == "00")
            caps[std::stol(m[3])] = entry.path();
        else if (std::regex_match(name, m, h5Pattern()))
            h5[std::stol(m[2])] = entry.path();
    }
    std::vector<fs::path> out;
    for (const auto& [number, path] : caps.empty() ? h5 : caps)
        out.push_back(path);
    return out;
}

Step readStep(const fs::path& step, const Scales& scales, bool scalesGiven)
{
    const fs::path path = withoutGeneral(step);
    if (path.extension() == ".h5")
        return readH5Step(path, scales, scalesGiven);
    return readCapStep(path, scales);
}

std::vector<std::pair<std::string, int>> stepArrays(const fs::path& step)
{
    std::vector<std::pair<std::string, int>> arrays = {{"temperature", 1}, {"velocity", 3}, {"viscosity", 1}};
    const fs::path path = withoutGeneral(step);
    if (path.extension() != ".h5") {
        std::error_code ec;
        if (!fs::is_regular_file(path, ec))
            fail("{}: no such file", path.string());
        return arrays;
    }
    std::lock_guard lock(hdf5Mutex());
    H5Eset_auto2(H5E_DEFAULT, nullptr, nullptr);
    const Handle stepFile = openFile(path);
    if (H5Lexists(stepFile.id(), "pressure", H5P_DEFAULT) > 0)
        arrays.emplace_back("pressure", 1);
    return arrays;
}

std::optional<double> stepTimeMyr(const fs::path& step, const Scales& scales, bool scalesGiven)
{
    const fs::path path = withoutGeneral(step);
    if (path.extension() != ".h5")
        return std::nullopt;
    const fs::path coordPath = coordFileOf(path);
    std::lock_guard lock(hdf5Mutex());
    H5Eset_auto2(H5E_DEFAULT, nullptr, nullptr);
    const Handle coordFile = openFile(coordPath);
    const Handle stepFile = openFile(path);
    const auto t = numberAttribute(stepFile.id(), "/", "time");
    if (!t)
        return std::nullopt;
    return myrOf(*t, runScales(coordFile.id(), scales, scalesGiven));
}

std::vector<fs::path> stepFiles(const fs::path& step)
{
    const fs::path path = withoutGeneral(step);
    if (path.extension() == ".h5")
        return {coordFileOf(path), path};
    std::smatch m;
    const std::string name = path.filename().string();
    if (!std::regex_match(name, m, capPattern()))
        return {path};
    std::vector<fs::path> files;
    for (int cap = 0; cap < kFullSphereCaps; ++cap) {
        const fs::path p = path.parent_path() / fmt::format("{}.cap{:02d}.{}", std::string(m[1]), cap, std::string(m[3]));
        std::error_code ec;
        if (fs::exists(p, ec))
            files.push_back(p);
    }
    return files;
}

std::array<size_t, 3> naturalGridSize(const Step& step)
{
    if (step.caps.size() == 1)
        return {step.nx, step.nz, step.ny};
    const size_t around = 4 * (std::max(step.nx, step.ny) - 1);
    return {around / 2, step.nz, around};
}

std::string formatName(const fs::path& step)
{
    return withoutGeneral(step).extension() == ".h5" ? "CitcomS HDF5" : "CitcomS combined caps (ASCII)";
}

std::string unitsOf(const std::string& array, const Scales& scales)
{
    if (array == "temperature")
        return scales.temperatureK > 0 ? "K" : "1";
    if (array == "velocity")
        return "m/s";
    return "1";  // viscosity and pressure as written: nondimensional
}

}  // namespace raypc::io::citcoms
