#include "io/netcdf_reader.h"

#include "core/error.h"
#include "core/spherical.h"
#include "core/strings.h"
#include "core/system_memory.h"
#include "grid/variable_names.h"
#include "io/netcdf_classic.h"

#include <hdf5.h>
#include <netcdf.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <array>
#include <cctype>
#include <cmath>
#include <fstream>
#include <iterator>
#include <limits>
#include <map>
#include <mutex>
#include <numbers>
#include <numeric>
#include <optional>
#include <type_traits>

namespace raypc {
namespace {

// netCDF-C is not thread-safe; every call into it holds this lock.
std::mutex& netcdfMutex()
{
    static std::mutex m;
    return m;
}

std::string errorText(int status) { return nc_strerror(status); }

// netCDF-C reads past the end of a truncated classic file without an error (the missing bytes
// come back as zeros), and allocates what a header claims (a variable of 10^9 dimensions) before
// reading it. So a classic file's header is walked first, allocating nothing it claims, and the
// file's size compared with where the header says the data ends.
void checkClassicFileSize(const std::filesystem::path& path)
{
    std::ifstream in(path, std::ios::binary);
    if (!in)
        fail("{}: cannot open for reading", path.string());
    char magic[4] = {};
    in.read(magic, 4);
    if (in.gcount() != 4 || std::string_view(magic, 3) != "CDF")
        return;  // netCDF-4 (HDF5) or not netCDF: nc_open says which
    in.seekg(0);
    const uint64_t needed = classicDataEndBytes(in, path.string());
    std::error_code ec;
    const uintmax_t size = std::filesystem::file_size(path, ec);
    if (ec)
        fail("{}: cannot read the file size: {}", path.string(), ec.message());
    if (size < needed)
        fail("{}: truncated: the file has {} bytes, its header places data up to byte {}", path.string(), size,
             needed);
}

// HDF5 prints its error stack (HDF5-DIAG lines) for every failed call, also for the calls netCDF-C
// makes expecting them to fail while it opens a netCDF-4 file. netCDF-C switches that printing off
// when it initialises, but in a thread-safe HDF5 (Debian's) the setting is per thread: a thread
// other than the first to open a file (`raypc serve FILES` preprocesses on a background thread)
// printed hundreds of stacks. So every thread switches it off for itself before it opens a file.
void silenceHdf5ErrorStack()
{
    thread_local bool silenced = false;
    if (!silenced) {
        H5Eset_auto2(H5E_DEFAULT, nullptr, nullptr);
        silenced = true;
    }
}

// An open file that closes itself.
class NcFile {
public:
    explicit NcFile(const std::filesystem::path& path) : m_path(path)
    {
        std::error_code ec;
        if (!std::filesystem::exists(path, ec))
            fail("{}: no such file", path.string());
        if (std::filesystem::is_directory(path, ec))
            fail("{}: is a directory, expected a netCDF file", path.string());
        checkClassicFileSize(path);
        silenceHdf5ErrorStack();
        const int status = nc_open(path.c_str(), NC_NOWRITE, &m_id);
        if (status != NC_NOERR) {
            if (status == NC_ENOTNC)
                fail("{}: not a netCDF file (or an unsupported variant)", path.string());
            fail("{}: cannot open as netCDF: {}", path.string(), errorText(status));
        }
    }
    ~NcFile() { nc_close(m_id); }
    NcFile(const NcFile&) = delete;
    NcFile& operator=(const NcFile&) = delete;

    int id() const { return m_id; }
    const std::filesystem::path& path() const { return m_path; }
    std::string name() const { return m_path.filename().string(); }

    void check(int status, std::string_view what) const
    {
        if (status != NC_NOERR)
            fail("{}: {}: {}", m_path.string(), what, errorText(status));
    }

    std::optional<int> findVar(const std::string& name) const
    {
        int varId = -1;
        if (nc_inq_varid(m_id, name.c_str(), &varId) != NC_NOERR)
            return std::nullopt;
        return varId;
    }

    std::string varName(int varId) const
    {
        char name[NC_MAX_NAME + 1] = {};
        check(nc_inq_varname(m_id, varId, name), "reading a variable name");
        return name;
    }

    std::vector<int> varDims(int varId) const
    {
        int nDims = 0;
        check(nc_inq_varndims(m_id, varId, &nDims), "reading variable dims");
        std::vector<int> dims(nDims);
        check(nc_inq_vardimid(m_id, varId, dims.data()), "reading variable dims");
        return dims;
    }

    std::string dimName(int dimId) const
    {
        char name[NC_MAX_NAME + 1] = {};
        check(nc_inq_dimname(m_id, dimId, name), "reading a dimension name");
        return name;
    }

    size_t dimLength(int dimId) const
    {
        size_t n = 0;
        check(nc_inq_dimlen(m_id, dimId, &n), "reading a dimension length");
        return n;
    }

    // A text attribute, NC_CHAR (classic files) or NC_STRING (netCDF-4 writes these, e.g. Python's
    // netCDF4 for str values); the first string of an NC_STRING array. Trimmed of blanks and NULs.
    std::optional<std::string> textAttribute(int varId, const char* name) const
    {
        nc_type type;
        size_t len = 0;
        if (nc_inq_att(m_id, varId, name, &type, &len) != NC_NOERR)
            return std::nullopt;
        std::string value;
        if (type == NC_CHAR) {
            value.resize(len);
            check(nc_get_att_text(m_id, varId, name, value.data()), std::string("reading attribute ") + name);
        } else if (type == NC_STRING) {
            if (len == 0)
                return std::string();
            std::vector<char*> strings(len, nullptr);
            check(nc_get_att_string(m_id, varId, name, strings.data()), std::string("reading attribute ") + name);
            value = strings[0] ? strings[0] : "";
            nc_free_string(len, strings.data());
        } else {
            return std::nullopt;
        }
        while (!value.empty() && value.back() == '\0')
            value.pop_back();
        return trim(value);
    }

    std::optional<double> numberAttribute(int varId, const char* name) const
    {
        nc_type type;
        size_t len = 0;
        if (nc_inq_att(m_id, varId, name, &type, &len) != NC_NOERR || len < 1 || type == NC_CHAR ||
            type == NC_STRING)
            return std::nullopt;
        std::vector<double> values(len);
        check(nc_get_att_double(m_id, varId, name, values.data()), std::string("reading attribute ") + name);
        return values[0];
    }

    std::string formatName() const
    {
        int fmt = 0;
        check(nc_inq_format(m_id, &fmt), "reading the format");
        switch (fmt) {
        case NC_FORMAT_CLASSIC: return "classic";
        case NC_FORMAT_64BIT_OFFSET: return "64-bit offset";
        case NC_FORMAT_CDF5: return "CDF-5";
        case NC_FORMAT_NETCDF4: return "netCDF-4";
        case NC_FORMAT_NETCDF4_CLASSIC: return "netCDF-4 classic model";
        default: return "unknown";
        }
    }

private:
    std::filesystem::path m_path;
    int m_id = -1;
};

enum Axis { kLat = 0, kR = 1, kLon = 2 };
constexpr std::array<const char*, 3> kAxisNames = {"lat", "r", "lon"};

struct CoordinateAxis {
    int varId = -1;
    int dimId = -1;
    std::vector<double> fileValues;  // in file order, converted to degrees / km (of radius)
    // canonical index -> index in the file
    std::vector<size_t> fileIndex;
    std::vector<double> canonical;
};

std::string lowerCase(std::string text)
{
    std::transform(text.begin(), text.end(), text.begin(), [](unsigned char c) { return char(std::tolower(c)); });
    return text;
}

// Units compare without regard to case ("KM", "Degrees_North").
bool unitsMatch(const std::optional<std::string>& units, std::initializer_list<const char*> accepted)
{
    if (!units)
        return false;
    const std::string u = lowerCase(*units);
    for (const char* a : accepted)
        if (u == a)
            return true;
    return false;
}

// The spellings of CF's units of latitude and longitude (CF conventions, sections 4.1 and 4.2).
constexpr std::initializer_list<const char*> kDegreesNorth = {"degrees_north", "degree_north", "degree_n",
                                                              "degrees_n", "degreen", "degreesn"};
constexpr std::initializer_list<const char*> kDegreesSouth = {"degrees_south", "degree_south", "degree_s",
                                                              "degrees_s", "degreess"};
constexpr std::initializer_list<const char*> kDegreesEast = {"degrees_east", "degree_east", "degree_e",
                                                             "degrees_e", "degreee", "degreese"};
constexpr std::initializer_list<const char*> kDegreesWest = {"degrees_west", "degree_west", "degree_w",
                                                             "degrees_w", "degreew", "degreesw"};
constexpr std::initializer_list<const char*> kDegrees = {"degrees", "degree", "deg"};
constexpr std::initializer_list<const char*> kRadians = {"radians", "radian", "rad"};
constexpr std::initializer_list<const char*> kKilometres = {"km", "kilometer", "kilometers", "kilometre",
                                                            "kilometres"};
constexpr std::initializer_list<const char*> kMetres = {"m", "meter", "meters", "metre", "metres"};

// Radii RayPC takes for a mantle's when a coordinate's units do not say what its numbers are.
constexpr double kMantleMinKm = 3000.0, kMantleMaxKm = 7000.0;

std::string fileNameOf(const ReaderOptions& options, const std::string& canonicalName)
{
    const auto it = options.variableNames.find(canonicalName);
    return it == options.variableNames.end() ? canonicalName : it->second;
}

// The name a variable of the file is read as: the one --map gives it, else its own.
std::string canonicalNameOf(const ReaderOptions& options, const std::string& fileName)
{
    for (const auto& [canonical, inFile] : options.variableNames)
        if (inFile == fileName)
            return canonical;
    return fileName;
}

// Whether variable `v` says by CF attributes that it is the coordinate of `axis`: standard_name,
// axis, units of latitude or longitude, or (vertical) positive.
bool hasCfMarks(const NcFile& file, int v, Axis axis)
{
    const std::string standardName = lowerCase(file.textAttribute(v, "standard_name").value_or(""));
    const std::string axisAttribute = lowerCase(file.textAttribute(v, "axis").value_or(""));
    const auto units = file.textAttribute(v, "units");
    switch (axis) {
    case kLat:
        return standardName == "latitude" || axisAttribute == "y" || unitsMatch(units, kDegreesNorth) ||
               unitsMatch(units, kDegreesSouth);
    case kLon:
        return standardName == "longitude" || axisAttribute == "x" || unitsMatch(units, kDegreesEast) ||
               unitsMatch(units, kDegreesWest);
    case kR:
        return standardName == "depth" || axisAttribute == "z" || file.textAttribute(v, "positive").has_value();
    }
    return false;
}

// The customary names of each axis's coordinate variable.
const std::array<std::vector<std::string>, 3>& customaryNames()
{
    static const std::array<std::vector<std::string>, 3> names = {
        std::vector<std::string>{"lat", "latitude", "Lat", "LAT"},
        std::vector<std::string>{"r", "radius", "R", "rad", "depth", "Depth"},
        std::vector<std::string>{"lon", "longitude", "Lon", "LON"}};
    return names;
}

// Finds a coordinate variable by explicit name, by CF attributes, or by customary names. Of several
// variables with CF attributes of the axis, those on a dim of the requested variables (`dataDims`),
// then coordinate variables (named as their dim), then those with a customary name are taken.
int findCoordinateVar(const NcFile& file, Axis axis, const std::string& explicitName, const std::vector<int>& dataDims)
{
    static constexpr std::array<const char*, 3> kOptions = {"--lat-name", "--r-name", "--lon-name"};
    if (!explicitName.empty()) {
        if (auto id = file.findVar(explicitName))
            return *id;
        fail("{}: no coordinate variable '{}' (given with {})", file.path().string(), explicitName, kOptions[axis]);
    }
    int nVars = 0;
    file.check(nc_inq_nvars(file.id(), &nVars), "listing variables");
    std::vector<int> found;
    for (int v = 0; v < nVars; ++v)
        if (file.varDims(v).size() == 1 && hasCfMarks(file, v, axis))
            found.push_back(v);
    const auto& names = customaryNames()[axis];
    // Keeps the candidates that `keep` accepts, if any.
    auto prefer = [&](auto keep) {
        std::vector<int> kept;
        std::copy_if(found.begin(), found.end(), std::back_inserter(kept), keep);
        if (!kept.empty())
            found = std::move(kept);
    };
    prefer([&](int v) {
        return std::find(dataDims.begin(), dataDims.end(), file.varDims(v)[0]) != dataDims.end();
    });
    prefer([&](int v) { return file.varName(v) == file.dimName(file.varDims(v)[0]); });
    prefer([&](int v) { return std::find(names.begin(), names.end(), file.varName(v)) != names.end(); });
    if (found.size() == 1)
        return found[0];
    if (found.size() > 1) {
        std::vector<std::string> claimants;
        for (int v : found)
            claimants.push_back(file.varName(v));
        fail("{}: the variables {} all say by their CF attributes that they are the {} coordinate; name one with {}",
             file.path().string(), fmt::join(claimants, ", "), axis == kR ? "radius or depth" : kAxisNames[axis],
             kOptions[axis]);
    }
    for (const auto& name : names)
        if (auto id = file.findVar(name))
            return *id;
    fail("{}: no {} coordinate variable found (looked for CF attributes standard_name, axis, units{} and the names "
         "{}); name it with {}",
         file.path().string(), axis == kR ? "radius or depth" : kAxisNames[axis], axis == kR ? ", positive" : "",
         axis == kLat ? "lat/latitude" : axis == kR ? "r/radius/depth" : "lon/longitude", kOptions[axis]);
}

// "'lat'", or "'phi' (lat)" when the name does not say which axis it is.
std::string describeCoordinate(const std::string& name, Axis axis)
{
    return name == kAxisNames[axis] ? fmt::format("'{}'", name) : fmt::format("'{}' ({})", name, kAxisNames[axis]);
}

// Latitude and longitude into degrees north and east: radians, degrees_south and degrees_west
// converted; without units degrees, unless every value lies within what radians could be.
void anglesToDegrees(const NcFile& file, Axis axis, int varId, const std::string& name, std::vector<double>& values)
{
    const auto units = file.textAttribute(varId, "units");
    const auto [minIt, maxIt] = std::minmax_element(values.begin(), values.end());
    const double lo = *minIt, hi = *maxIt;
    if (!units || units->empty()) {
        // A global grid in degrees does not fit within ±π/2 (lat) or ±2π (lon).
        const double radiansBound = axis == kLat ? std::numbers::pi / 2 : 2 * std::numbers::pi;
        if (std::max(std::abs(lo), std::abs(hi)) <= radiansBound + 1e-9)
            fail("{}: coordinate {} has no units and its values {:g}..{:g} lie within ±{}: radians, or a sliver of "
                 "degrees? Give it a units attribute (radians or {}), e.g. ncatted -a units,{},c,c,radians FILE",
                 file.path().string(), describeCoordinate(name, axis), lo, hi, axis == kLat ? "π/2" : "2π",
                 axis == kLat ? "degrees_north" : "degrees_east", name);
        return;
    }
    double scale = 1.0;  // to degrees north / east
    if (unitsMatch(units, kRadians))
        scale = radToDeg(1.0);
    else if (axis == kLat && unitsMatch(units, kDegreesSouth))
        scale = -1.0;
    else if (axis == kLon && unitsMatch(units, kDegreesWest))
        scale = -1.0;
    else if (!unitsMatch(units, kDegrees) && !unitsMatch(units, axis == kLat ? kDegreesNorth : kDegreesEast))
        fail("{}: coordinate {} has units '{}', expected {}", file.path().string(), describeCoordinate(name, axis),
             *units,
             axis == kLat ? "degrees_north, degrees_south, degrees or radians"
                          : "degrees_east, degrees_west, degrees or radians");
    for (double& v : values)
        v *= scale;
}

// The vertical coordinate into radius in km: radius or depth (positive down: radius = 6371 km -
// depth), in km, m or fractions of 6371 km as the units attribute or options.radiusUnits say.
void verticalToRadiusKm(const NcFile& file, int varId, const std::string& name, std::vector<double>& values,
                        ReaderOptions::RadiusUnits given)
{
    using RadiusUnits = ReaderOptions::RadiusUnits;
    const auto positive = file.textAttribute(varId, "positive");
    const bool depth = positive ? lowerCase(*positive) == "down"
                                : file.textAttribute(varId, "standard_name") == "depth" || lowerCase(name) == "depth";
    const char* what = depth ? "depth" : "radius";
    const auto units = file.textAttribute(varId, "units");
    const bool noUnits = !units || units->empty();
    const auto [minIt, maxIt] = std::minmax_element(values.begin(), values.end());
    const double lo = *minIt, hi = *maxIt;
    constexpr const char* kSay =
        "say what they are with --radius-units km|m|nondimensional (nondimensional: fractions of 6371 km)";
    double kmPerUnit = 1.0;
    switch (given) {
    case RadiusUnits::Km: kmPerUnit = 1.0; break;
    case RadiusUnits::M: kmPerUnit = 1e-3; break;
    case RadiusUnits::Nondimensional: kmPerUnit = kSurfaceRadiusKm; break;
    case RadiusUnits::FromFile:
        if (unitsMatch(units, kMetres))
            kmPerUnit = 1e-3;
        else if (!noUnits && !unitsMatch(units, kKilometres))
            fail("{}: coordinate '{}' ({}) has units '{}', expected km or m; {}", file.path().string(), name, what,
                 *units, kSay);
        break;
    }
    for (double& v : values)
        v = depth ? kSurfaceRadiusKm - v * kmPerUnit : v * kmPerUnit;
    // Numbers without units are taken as km only where they are a mantle's.
    if (given == RadiusUnits::FromFile && noUnits) {
        const auto [rMin, rMax] = std::minmax_element(values.begin(), values.end());
        if (*rMin < kMantleMinKm || *rMax > kMantleMaxKm) {
            const std::string radii = depth ? fmt::format(", as km of depth, give radii {:g}..{:g} km,", *rMin, *rMax)
                                            : std::string(" as km are");
            fail("{}: coordinate '{}' ({}) has no units and its values {:g}..{:g}{} not a mantle's radii ({:g}..{:g} "
                 "km); {}",
                 file.path().string(), name, what, lo, hi, radii, kMantleMinKm, kMantleMaxKm, kSay);
        }
    }
}

std::optional<double> defaultFillValue(const NcFile& file, int varId);

// An axis keeps its values in file and canonical order, a sorting copy and an index.
constexpr uint64_t kAxisBytesPerValue = 3 * sizeof(double) + sizeof(size_t);

CoordinateAxis readAxis(const NcFile& file, Axis axis, const std::string& explicitName, const ReaderOptions& options,
                        const std::vector<int>& dataDims)
{
    CoordinateAxis a;
    a.varId = findCoordinateVar(file, axis, explicitName, dataDims);
    const std::string name = file.varName(a.varId);
    const auto dims = file.varDims(a.varId);
    if (dims.size() != 1)
        fail("{}: coordinate '{}' has {} dims, expected 1", file.path().string(), name, dims.size());
    a.dimId = dims[0];
    const size_t n = file.dimLength(a.dimId);
    if (n == 0)
        fail("{}: coordinate '{}' is empty", file.path().string(), name);
    // A hostile or broken header may declare any length: check before allocating for it.
    if (n > kMaxGridPoints)
        fail("{}: coordinate '{}' has {} values, more than a grid RayPC reads may have points ({})",
             file.path().string(), name, n, kMaxGridPoints);
    if (const auto available = availableMemory(); n * kAxisBytesPerValue > available.bytes)
        fail("{}: coordinate '{}' has {} values, which need {} of memory, {} available ({})", file.path().string(),
             name, n, formatBytes(n * kAxisBytesPerValue), formatBytes(available.bytes), available.limitedBy);
    a.fileValues.resize(n);
    file.check(nc_get_var_double(file.id(), a.varId, a.fileValues.data()),
               fmt::format("reading coordinate '{}'", name));
    // A coordinate never written holds its fill value: say so, rather than "repeats the value 9.97e+36".
    std::optional<double> fill = file.numberAttribute(a.varId, "_FillValue");
    if (!fill)
        fill = defaultFillValue(file, a.varId);
    if (fill) {
        const auto unset = std::count(a.fileValues.begin(), a.fileValues.end(), *fill);
        if (unset > 0)
            fail("{}: coordinate '{}' holds its fill value ({:g}) at {} of its {} points: it was never written",
                 file.path().string(), name, *fill, unset, n);
    }
    for (double v : a.fileValues)
        if (!std::isfinite(v))
            fail("{}: coordinate '{}' holds a non-finite value", file.path().string(), name);
    if (axis == kR)
        verticalToRadiusKm(file, a.varId, name, a.fileValues, options.radiusUnits);
    else
        anglesToDegrees(file, axis, a.varId, name, a.fileValues);

    // Canonical order: ascending; lon wrapped into [0, 360) with a repeated seam dropped.
    std::vector<double> values = a.fileValues;
    std::vector<size_t> index(n);
    std::iota(index.begin(), index.end(), 0);
    if (axis == kLon) {
        if (n > 2) {
            const double span = values.back() - values.front();
            if (std::abs(std::abs(span) - 360.0) < 1e-6 * 360.0)
                index.pop_back();  // the seam is stored twice; keep the first copy
        }
        for (double& v : values)
            v = wrapLonDeg(v);
    }
    std::stable_sort(index.begin(), index.end(), [&](size_t i, size_t j) { return values[i] < values[j]; });
    a.fileIndex = index;
    for (size_t i : index)
        a.canonical.push_back(values[i]);
    for (size_t i = 1; i < a.canonical.size(); ++i)
        if (a.canonical[i] == a.canonical[i - 1])
            fail("{}: coordinate '{}' repeats the value {}", file.path().string(), name, a.canonical[i]);
    return a;
}

struct OpenedHeader {
    std::array<CoordinateAxis, 3> axes;
    SphericalGrid grid;
};

// The variables to read (canonical names): those given (ReaderOptions::variables); else the
// contest's eight when the file holds them all (in their order); else every numeric variable of
// three or more dims, in the file's order, whatever a model or a tomography file calls them (one
// `vs`, a CF output's own names). With `h` (the axes found), only those on the grid's three dims:
// a file's surface maps or other grids are not the model's fields.
std::vector<std::string> requestedVariables(const NcFile& file, const ReaderOptions& options,
                                            const OpenedHeader* h = nullptr)
{
    if (!options.variables.empty())
        return options.variables;
    const auto& contest = contestVariableNames();
    if (std::all_of(contest.begin(), contest.end(),
                    [&](const std::string& name) { return file.findVar(fileNameOf(options, name)).has_value(); }))
        return contest;
    int nVars = 0;
    file.check(nc_inq_nvars(file.id(), &nVars), "listing variables");
    std::vector<std::string> names;
    for (int v = 0; v < nVars; ++v) {
        const std::vector<int> dims = file.varDims(v);
        nc_type type = 0;
        file.check(nc_inq_vartype(file.id(), v, &type), "reading a variable type");
        if (dims.size() < 3 || type == NC_CHAR || type == NC_STRING)
            continue;
        if (h && std::any_of(h->axes.begin(), h->axes.end(), [&](const CoordinateAxis& a) {
                return std::find(dims.begin(), dims.end(), a.dimId) == dims.end();
            }))
            continue;
        names.push_back(canonicalNameOf(options, file.varName(v)));
    }
    // A variable named on the command line (--map, --velocity) must be there: asked for, it is
    // named as missing instead of left out.
    for (const auto& [canonical, inFile] : options.variableNames)
        if (std::find(names.begin(), names.end(), canonical) == names.end())
            names.push_back(canonical);
    if (names.empty() && h)
        fail("{}: no variable on the grid's dims ({}, {}, {}); a variable RayPC reads has these three dims in any "
             "order",
             file.path().string(), file.dimName(h->axes[kLat].dimId), file.dimName(h->axes[kR].dimId),
             file.dimName(h->axes[kLon].dimId));
    return names;
}

OpenedHeader readAxes(const NcFile& file, const ReaderOptions& options)
{
    // The dims of the requested variables that the file has (a missing one is named later).
    std::vector<int> dataDims;
    for (const auto& name : requestedVariables(file, options))
        if (const auto id = file.findVar(fileNameOf(options, name)))
            for (int d : file.varDims(*id))
                dataDims.push_back(d);
    OpenedHeader h;
    h.axes[kLat] = readAxis(file, kLat, options.latName, options, dataDims);
    h.axes[kR] = readAxis(file, kR, options.rName, options, dataDims);
    h.axes[kLon] = readAxis(file, kLon, options.lonName, options, dataDims);
    h.grid.latDeg = h.axes[kLat].canonical;
    h.grid.rKm = h.axes[kR].canonical;
    h.grid.lonDeg = h.axes[kLon].canonical;
    h.grid.validate(file.path().string());
    return h;
}

// Where a variable's values are: its id and, for each grid axis, the distance in elements between
// neighbours along it in the file.
struct VariableLayout {
    int id = -1;
    std::array<size_t, 3> stride{};
    // The hyperslab of one step, in the file's dim order: the whole grid, `timeIndex` of the time dim.
    std::vector<size_t> start, count;
    size_t steps = 1;  // the time dim's length (1 without one)
};

// Checks that the variable exists, is numeric and has the three grid dims in any order, and besides
// them dims of length 1 and at most one longer (CF's time, (time, lat, r, lon): a series in one file,
// of which step `timeIndex` is read).
VariableLayout checkVariable(const NcFile& file, const OpenedHeader& h, const std::string& canonicalName,
                             const std::string& fileName, size_t timeIndex)
{
    const auto id = file.findVar(fileName);
    if (!id) {
        if (fileName != canonicalName)
            fail("{}: missing variable '{}' (mapped from '{}')", file.path().string(), fileName, canonicalName);
        fail("{}: missing variable '{}'", file.path().string(), fileName);
    }
    const auto dims = file.varDims(*id);
    auto describe = [&] {
        std::vector<std::string> names;
        for (int d : dims)
            names.push_back(file.dimName(d));
        return fmt::format("({})", fmt::join(names, ", "));
    };
    const std::string gridDims = fmt::format("({}, {}, {})", file.dimName(h.axes[kLat].dimId),
                                             file.dimName(h.axes[kR].dimId), file.dimName(h.axes[kLon].dimId));
    // Which grid axis each of the variable's dims is, if any.
    std::vector<std::optional<Axis>> axisOfDim(dims.size());
    std::array<bool, 3> seen{};
    for (size_t i = 0; i < dims.size(); ++i)
        for (int a = 0; a < 3; ++a)
            if (dims[i] == h.axes[a].dimId && !seen[a]) {
                axisOfDim[i] = static_cast<Axis>(a);
                seen[a] = true;
            }
    if (!seen[kLat] || !seen[kR] || !seen[kLon]) {
        if (dims.size() < 3)
            fail("{}: {}: dims {}, expected 3 dims {}", file.path().string(), fileName, describe(), gridDims);
        fail("{}: {}: dims {}, expected the grid's dims {} in any order", file.path().string(), fileName, describe(),
             gridDims);
    }
    VariableLayout layout;
    layout.id = *id;
    layout.start.assign(dims.size(), 0);
    layout.count.assign(dims.size(), 1);
    // Element strides of one step in the file's dim order (last dim fastest); other dims count 1.
    size_t s = 1;
    std::optional<size_t> timeDim;
    for (size_t i = dims.size(); i-- > 0;) {
        if (axisOfDim[i]) {
            layout.stride[*axisOfDim[i]] = s;
            layout.count[i] = h.axes[*axisOfDim[i]].fileValues.size();
            s *= layout.count[i];
            continue;
        }
        const size_t length = file.dimLength(dims[i]);
        if (length == 0)
            fail("{}: {}: dims {}: dimension '{}' has length 0, the file holds no step", file.path().string(),
                 fileName, describe(), file.dimName(dims[i]));
        if (length == 1)
            continue;
        if (timeDim)
            fail("{}: {}: dims {}: dimensions '{}' and '{}' both have more than one entry; besides the grid's dims {} "
                 "RayPC reads one dimension of steps (time)",
                 file.path().string(), fileName, describe(), file.dimName(dims[i]), file.dimName(dims[*timeDim]),
                 gridDims);
        timeDim = i;
        layout.steps = length;
        if (timeIndex >= length)
            fail("{}: {}: step {} of a file holding {} (dimension '{}')", file.path().string(), fileName, timeIndex,
                 length, file.dimName(dims[i]));
        layout.start[i] = timeIndex;
    }

    int type = 0;
    file.check(nc_inq_vartype(file.id(), *id, &type), "reading a variable type");
    if (type == NC_CHAR || type == NC_STRING)
        fail("{}: {}: text variable, expected numbers", file.path().string(), fileName);
    return layout;
}

// The value netCDF gives a cell of variable `varId` that was never written when the variable
// has no _FillValue (NC_FILL_FLOAT etc.), or nothing for a type without one.
std::optional<double> defaultFillValue(const NcFile& file, int varId)
{
    nc_type type = 0;
    file.check(nc_inq_vartype(file.id(), varId, &type), "reading a variable type");
    switch (type) {
    case NC_BYTE: return NC_FILL_BYTE;
    case NC_UBYTE: return NC_FILL_UBYTE;
    case NC_SHORT: return NC_FILL_SHORT;
    case NC_USHORT: return NC_FILL_USHORT;
    case NC_INT: return NC_FILL_INT;
    case NC_UINT: return NC_FILL_UINT;
    case NC_INT64: return static_cast<double>(NC_FILL_INT64);
    case NC_UINT64: return static_cast<double>(NC_FILL_UINT64);
    case NC_FLOAT: return NC_FILL_FLOAT;
    case NC_DOUBLE: return NC_FILL_DOUBLE;
    default: return std::nullopt;
    }
}

// netCDF converts integers to float exactly up to 16 bits; doubles and wider integers are read as
// double and converted here, so that a fill value beyond float (1e300) is recognised and a value
// beyond float is named rather than failing the whole read ("Numeric conversion not representable").
bool readsAsDouble(const NcFile& file, int varId)
{
    nc_type type = 0;
    file.check(nc_inq_vartype(file.id(), varId, &type), "reading a variable type");
    return type == NC_DOUBLE || type == NC_INT || type == NC_UINT || type == NC_INT64 || type == NC_UINT64;
}

void readValues(const NcFile& file, const VariableLayout& layout, const std::string& fileName, float* out)
{
    if (const int status = nc_get_vara_float(file.id(), layout.id, layout.start.data(), layout.count.data(), out);
        status != NC_NOERR)
        fail("{}: {}: cannot read the values ({}); the file may be truncated or damaged", file.path().string(),
             fileName, errorText(status));
}

void readValues(const NcFile& file, const VariableLayout& layout, const std::string& fileName, double* out)
{
    if (const int status = nc_get_vara_double(file.id(), layout.id, layout.start.data(), layout.count.data(), out);
        status != NC_NOERR)
        fail("{}: {}: cannot read the values ({}); the file may be truncated or damaged", file.path().string(),
             fileName, errorText(status));
}

// How a variable's stored numbers become values (CF conventions, section 8.1, and the NUG's
// _Unsigned): which are missing, how they are unpacked. Comparisons are on the stored numbers.
struct ValueRule {
    std::optional<double> fill;  // _FillValue, or without one netCDF's default fill value of the type
    bool fillIsDefault = false;
    std::optional<double> missing;  // missing_value
    double scale = 1.0, offset = 0.0;
    // For an integer variable with _Unsigned = "true": 2^bits, added to negative stored numbers.
    double unsignedWrap = 0.0;

    bool packed() const { return scale != 1.0 || offset != 0.0; }
    bool isFill(double stored) const { return fill && stored == *fill; }
};

ValueRule valueRule(const NcFile& file, int varId)
{
    ValueRule rule;
    nc_type type = 0;
    file.check(nc_inq_vartype(file.id(), varId, &type), "reading a variable type");
    const auto isUnsigned = file.textAttribute(varId, "_Unsigned");
    if (isUnsigned && (*isUnsigned == "true" || *isUnsigned == "True" || *isUnsigned == "TRUE")) {
        switch (type) {
        case NC_BYTE: rule.unsignedWrap = 0x1p8; break;
        case NC_SHORT: rule.unsignedWrap = 0x1p16; break;
        case NC_INT: rule.unsignedWrap = 0x1p32; break;
        case NC_INT64: rule.unsignedWrap = 0x1p64; break;
        default: break;
        }
    }
    // A fill or missing value given as the unsigned number (65535) matches the stored one (-1).
    auto stored = [&](std::optional<double> v) {
        if (v && rule.unsignedWrap > 0 && *v >= rule.unsignedWrap / 2)
            *v -= rule.unsignedWrap;
        return v;
    };
    rule.fill = stored(file.numberAttribute(varId, "_FillValue"));
    if (!rule.fill) {
        rule.fill = defaultFillValue(file, varId);
        rule.fillIsDefault = rule.fill.has_value();
    }
    rule.missing = stored(file.numberAttribute(varId, "missing_value"));
    rule.scale = file.numberAttribute(varId, "scale_factor").value_or(1.0);
    rule.offset = file.numberAttribute(varId, "add_offset").value_or(0.0);
    return rule;
}

// What turning one variable into canonical order found.
struct ConversionReport {
    std::vector<size_t> missingPerShell;
    size_t firstMissing = SIZE_MAX;  // canonical index, for the message
    double firstMissingValue = 0;
    size_t firstBeyondFloat = SIZE_MAX;  // canonical index of the first value beyond float32
    double beyondFloatValue = 0;
};

// A fill or missing value as the buffer's type T holds it: none when T cannot hold it (a
// missing_value of 1e300 on a float variable matches nothing).
template <typename T>
std::optional<T> asStored(std::optional<double> v)
{
    if (!v || (std::isfinite(*v) && std::abs(*v) > double(std::numeric_limits<T>::max())))
        return std::nullopt;
    return static_cast<T>(*v);
}

// Reorders `buffer` (one variable in the file's order) into canonical order in `out`, marking missing
// values (fill value, missing_value, NaN, Inf) as NaN, unpacking the others, and noting values that
// float32 cannot hold.
template <typename T>
ConversionReport toCanonical(const std::vector<T>& buffer, const OpenedHeader& h, const VariableLayout& layout,
                             const ValueRule& rule, std::vector<float>& out)
{
    const auto fill = asStored<T>(rule.fill), missing = asStored<T>(rule.missing);
    const auto& stride = layout.stride;
    const auto& latIdx = h.axes[kLat].fileIndex;
    const auto& rIdx = h.axes[kR].fileIndex;
    const auto& lonIdx = h.axes[kLon].fileIndex;
    const SphericalGrid& grid = h.grid;
    const size_t nR = grid.nR(), nLon = grid.nLon();
    const bool convert = rule.packed() || rule.unsignedWrap > 0;
    constexpr double kFloatMax = std::numeric_limits<float>::max();
    ConversionReport report;
    report.missingPerShell.assign(nR, 0);
    std::mutex reportMutex;
    tbb::parallel_for(size_t(0), grid.nLat(), [&](size_t iLat) {
        ConversionReport local;
        local.missingPerShell.assign(nR, 0);
        for (size_t iR = 0; iR < nR; ++iR) {
            const size_t base = latIdx[iLat] * stride[kLat] + rIdx[iR] * stride[kR];
            float* row = out.data() + grid.index(iLat, iR, 0);
            for (size_t iLon = 0; iLon < nLon; ++iLon) {
                const T v = buffer[base + lonIdx[iLon] * stride[kLon]];
                if ((fill && v == *fill) || (missing && v == *missing) || !std::isfinite(v)) {
                    if (local.firstMissing == SIZE_MAX) {
                        local.firstMissing = grid.index(iLat, iR, iLon);
                        local.firstMissingValue = double(v);
                    }
                    row[iLon] = std::numeric_limits<float>::quiet_NaN();
                    ++local.missingPerShell[iR];
                    continue;
                }
                double value = double(v);
                if (convert) {
                    if (value < 0 && rule.unsignedWrap > 0)
                        value += rule.unsignedWrap;
                    value = value * rule.scale + rule.offset;
                }
                if (std::is_same_v<T, float> && !convert) {
                    row[iLon] = float(v);
                } else if (std::abs(value) <= kFloatMax) {
                    row[iLon] = static_cast<float>(value);
                } else {
                    if (local.firstBeyondFloat == SIZE_MAX) {
                        local.firstBeyondFloat = grid.index(iLat, iR, iLon);
                        local.beyondFloatValue = value;
                    }
                    row[iLon] = std::numeric_limits<float>::quiet_NaN();
                }
            }
        }
        std::lock_guard l(reportMutex);
        for (size_t iR = 0; iR < nR; ++iR)
            report.missingPerShell[iR] += local.missingPerShell[iR];
        if (local.firstMissing < report.firstMissing) {
            report.firstMissing = local.firstMissing;
            report.firstMissingValue = local.firstMissingValue;
        }
        if (local.firstBeyondFloat < report.firstBeyondFloat) {
            report.firstBeyondFloat = local.firstBeyondFloat;
            report.beyondFloatValue = local.beyondFloatValue;
        }
    });
    return report;
}

}  // namespace

FileHeader readHeader(const std::filesystem::path& path, const ReaderOptions& options)
{
    std::lock_guard lock(netcdfMutex());
    NcFile file(path);
    const auto h = readAxes(file, options);
    FileHeader header;
    header.grid = h.grid;
    header.format = file.formatName();
    const std::vector<std::string> requested = requestedVariables(file, options, &h);
    const bool velocity = varname::hasVelocity(
        [&](const char* v) { return std::find(requested.begin(), requested.end(), v) != requested.end(); });
    for (const auto& name : requested) {
        const auto fileName = fileNameOf(options, name);
        const auto layout = checkVariable(file, h, name, fileName, options.timeIndex);
        std::string units = file.textAttribute(layout.id, "units").value_or("");
        if (velocity && varname::isVelocityComponent(name))
            units = "m/s";  // converted when read (normaliseVelocity)
        header.variables.push_back({name, fileName, units, file.textAttribute(layout.id, "long_name").value_or("")});
        // Variables without the time dimension (constant in time) are read for every step.
        if (layout.steps > 1 && header.steps > 1 && layout.steps != header.steps)
            fail("{}: {} has {} steps, {} has {}: the variables' time dimensions differ", path.string(), fileName,
                 layout.steps, header.variables.front().fileName, header.steps);
        header.steps = std::max(header.steps, layout.steps);
    }
    if (options.timeIndex >= header.steps)
        fail("{}: step {} of a file holding {}", path.string(), options.timeIndex, header.steps);
    return header;
}

Snapshot readSnapshot(const std::filesystem::path& path, const ReaderOptions& options)
{
    std::lock_guard lock(netcdfMutex());
    NcFile file(path);
    const auto h = readAxes(file, options);
    Snapshot snapshot;
    snapshot.grid = h.grid;
    const size_t n = h.grid.cellCount();
    size_t fileCount = 1;
    for (const auto& axis : h.axes)
        fileCount *= axis.fileValues.size();
    // Every variable is checked before any is read.
    const auto requested = requestedVariables(file, options, &h);
    std::vector<std::pair<std::string, VariableLayout>> layouts;
    size_t bufferBytesPerValue = sizeof(float);
    for (const auto& name : requested) {
        const auto fileName = fileNameOf(options, name);
        layouts.emplace_back(fileName, checkVariable(file, h, name, fileName, options.timeIndex));
        if (readsAsDouble(file, layouts.back().second.id))
            bufferBytesPerValue = sizeof(double);
    }
    size_t steps = 1;
    for (const auto& l : layouts)
        steps = std::max(steps, l.second.steps);
    if (options.timeIndex >= steps)
        fail("{}: step {} of a file holding {}", path.string(), options.timeIndex, steps);
    // The fields and one variable's buffer in file order.
    checkGridFitsMemory(h.grid, requested.size() * fileCount * sizeof(float) + fileCount * bufferBytesPerValue,
                        path.string(), "read", availableMemory());
    std::vector<float> floatBuffer;
    std::vector<double> doubleBuffer;

    for (size_t v = 0; v < requested.size(); ++v) {
        const std::string& name = requested[v];
        const auto& [fileName, layout] = layouts[v];
        const ValueRule rule = valueRule(file, layout.id);
        Field field;
        field.name = name;
        field.units = file.textAttribute(layout.id, "units").value_or("");
        field.values.resize(n);
        ConversionReport report;
        // Only one buffer is held at a time: the memory checked above.
        if (readsAsDouble(file, layout.id)) {
            std::vector<float>().swap(floatBuffer);
            doubleBuffer.resize(fileCount);
            readValues(file, layout, fileName, doubleBuffer.data());
            report = toCanonical(doubleBuffer, h, layout, rule, field.values);
        } else {
            std::vector<double>().swap(doubleBuffer);
            floatBuffer.resize(fileCount);
            readValues(file, layout, fileName, floatBuffer.data());
            report = toCanonical(floatBuffer, h, layout, rule, field.values);
        }
        if (report.firstBeyondFloat < n)
            fail("{}: {}: the value {:g} at {} is beyond float32's range (±{:g}), in which RayPC keeps values; if it "
                 "marks missing cells, give it as the variable's _FillValue or missing_value",
                 path.string(), fileName, report.beyondFloatValue, describeGridPoint(h.grid, report.firstBeyondFloat),
                 double(std::numeric_limits<float>::max()));
        const size_t missing =
            std::accumulate(report.missingPerShell.begin(), report.missingPerShell.end(), size_t(0));
        if (missing > 0) {
            if (!options.fillMissing) {
                const double first = report.firstMissingValue;
                const std::string what =
                    !std::isfinite(first)       ? fmt::format("{}", first)
                    : rule.isFill(first)        ? fmt::format("{} {:g}",
                                                              rule.fillIsDefault
                                                                  ? "netCDF's default fill value (never written)"
                                                                  : "_FillValue",
                                                              *rule.fill)
                                                : fmt::format("missing_value {:g}", *rule.missing);
                fail("{}: {}: {} of {} values are missing (fill value, missing_value or NaN/Inf), the first at {}: {}; "
                     "use --fill-missing to replace them by the mean of their radius shell",
                     path.string(), fileName, missing, n, describeGridPoint(h.grid, report.firstMissing), what);
            }
            fillMissingByShellMean(h.grid, field.values, fmt::format("{}: {}", path.string(), fileName));
        }
        snapshot.fields.push_back(std::move(field));
    }
    normaliseVelocity(snapshot, options.velocityFrame, path.string());
    return snapshot;
}

namespace {

// Metres per second in one unit of a velocity as CF and models spell it; nullopt when unknown.
std::optional<double> metresPerSecondIn(std::string units)
{
    std::erase_if(units, [](char c) { return c == ' ' || c == '.' || c == '*'; });
    units = lowerCase(units);
    constexpr double kYear = 3.15576e7;  // Julian year, s
    static const std::map<std::string, double> known = {
        {"", 1.0},           {"m/s", 1.0},          {"ms-1", 1.0},          {"ms^-1", 1.0},
        {"m/sec", 1.0},      {"meter/second", 1.0}, {"meters/second", 1.0}, {"metre/second", 1.0},
        {"cm/yr", 0.01 / kYear}, {"cm/year", 0.01 / kYear}, {"cm/a", 0.01 / kYear}, {"cmyr-1", 0.01 / kYear},
        {"cma-1", 0.01 / kYear}, {"mm/yr", 1e-3 / kYear},  {"mm/year", 1e-3 / kYear}, {"mm/a", 1e-3 / kYear},
        {"mmyr-1", 1e-3 / kYear}, {"m/yr", 1.0 / kYear},   {"m/year", 1.0 / kYear},   {"m/a", 1.0 / kYear},
        {"myr-1", 1.0 / kYear}};
    const auto it = known.find(units);
    return it == known.end() ? std::nullopt : std::optional<double>(it->second);
}

}  // namespace

void normaliseVelocity(Snapshot& snapshot, ReaderOptions::VelocityFrame frame, const std::string& what)
{
    std::array<Field*, 3> v{};
    for (size_t c = 0; c < 3; ++c)
        for (Field& f : snapshot.fields)
            if (f.name == varname::kVelocity[c])
                v[c] = &f;
    if (!v[0] || !v[1] || !v[2])
        return;
    for (Field* f : v) {
        const auto scale = metresPerSecondIn(f->units);
        if (!scale)
            fail("{}: {}: velocity units '{}', expected m/s, cm/yr, mm/yr or m/yr (or their CF spellings)", what, f->name,
                 f->units);
        if (*scale != 1.0)
            for (float& x : f->values)
                x = float(double(x) * *scale);
        f->units = "m/s";
    }
    if (frame != ReaderOptions::VelocityFrame::Spherical)
        return;
    // (radial, north, east) at each point into (x, y, z): v = v_r e_r + v_n e_n + v_e e_e.
    const SphericalGrid& g = snapshot.grid;
    for (size_t iLat = 0; iLat < g.nLat(); ++iLat)
        for (size_t iLon = 0; iLon < g.nLon(); ++iLon) {
            const Vec3d up = sphericalToCartesianKm(g.latDeg[iLat], g.lonDeg[iLon], 1.0);
            const EastNorth en = eastNorthAt(g.latDeg[iLat], g.lonDeg[iLon]);
            for (size_t iR = 0; iR < g.nR(); ++iR) {
                const size_t i = g.index(iLat, iR, iLon);
                const Vec3d c = double(v[0]->values[i]) * up + double(v[1]->values[i]) * en.north +
                                double(v[2]->values[i]) * en.east;
                v[0]->values[i] = float(c.x), v[1]->values[i] = float(c.y), v[2]->values[i] = float(c.z);
            }
        }
}

std::vector<std::filesystem::path> listSnapshotFiles(const std::vector<std::filesystem::path>& inputs)
{
    std::vector<std::filesystem::path> files;
    for (const auto& input : inputs) {
        std::error_code ec;
        if (std::filesystem::is_directory(input, ec)) {
            std::vector<std::filesystem::path> inDir;
            for (const auto& entry : std::filesystem::directory_iterator(input))
                if (entry.is_regular_file() && entry.path().extension() == ".nc")
                    inDir.push_back(entry.path());
            if (inDir.empty())
                fail("{}: directory holds no .nc files", input.string());
            std::sort(inDir.begin(), inDir.end(),
                      [](const auto& a, const auto& b) { return naturalLess(a.filename().string(), b.filename().string()); });
            files.insert(files.end(), inDir.begin(), inDir.end());
        } else {
            if (!std::filesystem::exists(input, ec))
                fail("{}: no such file", input.string());
            files.push_back(input);
        }
    }
    // Steps are in file order: natural sort of names (spherical2 < spherical10), as given
    // order within a directory; explicit files are sorted the same way.
    std::stable_sort(files.begin(), files.end(),
                     [](const auto& a, const auto& b) { return naturalLess(a.filename().string(), b.filename().string()); });
    for (size_t i = 1; i < files.size(); ++i)
        if (files[i].filename() == files[i - 1].filename())
            fail("{}: the same file name appears twice among the inputs ({} and {})", files[i].filename().string(),
                 files[i - 1].string(), files[i].string());
    return files;
}

}  // namespace raypc
