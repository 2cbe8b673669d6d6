// A netCDF file's coordinates (netcdf_coordinates.h): found by name, CF attributes or customary
// names, their units turned into degrees and km of radius, and sorted into canonical order.
#include "io/netcdf_coordinates.h"

#include "core/spherical.h"
#include "core/system_memory.h"
#include "io/netcdf_variables.h"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <initializer_list>
#include <iterator>
#include <numbers>
#include <numeric>

namespace raypc::io::netcdf {
namespace {

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

// A discontinuity's two radii (equal, ascending) moved apart by a metre, half each way, or by a
// hundredth of the nearest other spacing when that is less: the grid's radii stay strictly
// ascending, each side keeps its own values, and what lies between them is a shell thinner than
// any picture resolves (docs/format.md, discontinuities).
void separateDiscontinuities(std::vector<double>& radiiKm)
{
    constexpr double kGapKm = 0.001;
    for (size_t i = 1; i < radiiKm.size(); ++i) {
        if (radiiKm[i] != radiiKm[i - 1])
            continue;
        double nearest = kGapKm * 100;
        if (i >= 2)
            nearest = std::min(nearest, radiiKm[i - 1] - radiiKm[i - 2]);
        if (i + 1 < radiiKm.size())
            nearest = std::min(nearest, radiiKm[i + 1] - radiiKm[i]);
        const double gap = std::min(kGapKm, 0.01 * nearest);
        radiiKm[i - 1] -= 0.5 * gap;
        radiiKm[i] += 0.5 * gap;
    }
}

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
    if (n > grid::kMaxGridPoints)
        fail("{}: coordinate '{}' has {} values, more than a grid RayPC reads may have points ({})",
             file.path().string(), name, n, grid::kMaxGridPoints);
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
    const std::vector<double> asWritten = axis == kR ? a.fileValues : std::vector<double>{};  // for messages
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
    // A radius given twice is a discontinuity (410, 660 km, the CMB in reference and tomography
    // models), the first value of the pair in the file's order on the side the file comes from: of
    // two equal radii in ascending order, the one nearer the centre in the file's order first.
    const bool inward = axis == kR && n > 1 && values.front() > values.back();
    // Which side of a discontinuity a value lies on follows from the axis' order: a vertical axis
    // must run one way (apart from its repeats), not be sorted into place.
    if (axis == kR)
        for (size_t i = 1; i < n; ++i)
            if (inward ? values[i] > values[i - 1] : values[i] < values[i - 1])
                fail("{}: coordinate '{}' is not monotonic: {} after {} (apart from a repeated value at a "
                     "discontinuity, its values must run one way)",
                     file.path().string(), name, asWritten[i], asWritten[i - 1]);
    std::stable_sort(index.begin(), index.end(), [&](size_t i, size_t j) {
        return values[i] < values[j] || (values[i] == values[j] && inward && i > j);
    });
    a.fileIndex = index;
    for (size_t i : index)
        a.canonical.push_back(values[i]);
    for (size_t i = 1; i < a.canonical.size(); ++i)
        if (a.canonical[i] == a.canonical[i - 1] &&
            (axis != kR || (i >= 2 && a.canonical[i - 2] == a.canonical[i])))
            fail("{}: coordinate '{}' repeats the value {}{}", file.path().string(), name, a.canonical[i],
                 axis == kR ? " three times (a discontinuity is a radius given twice)" : "");
    if (axis == kR)
        separateDiscontinuities(a.canonical);
    return a;
}

// A regional grid's axis padded to the globe (grid::padToGlobe): the points that pad it hold no data
// (fileIndex kNoData).
void padToGlobal(CoordinateAxis& a, bool latitude, std::optional<std::array<double, 2>>& extent)
{
    const grid::PaddedAxis padded = grid::padToGlobe(a.canonical, latitude);
    if (!padded.extent)
        return;
    extent = padded.extent;
    std::vector<size_t> fileIndex;
    for (size_t source : padded.source)
        fileIndex.push_back(source == grid::PaddedAxis::kPadding ? kNoData : a.fileIndex[source]);
    a.canonical = padded.deg;
    a.fileIndex = std::move(fileIndex);
}

}  // namespace

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
    padToGlobal(h.axes[kLat], true, h.grid.dataLatDeg);
    padToGlobal(h.axes[kLon], false, h.grid.dataLonDeg);
    h.grid.latDeg = h.axes[kLat].canonical;
    h.grid.rKm = h.axes[kR].canonical;
    h.grid.lonDeg = h.axes[kLon].canonical;
    h.grid.validate(file.path().string());
    return h;
}

}  // namespace raypc::io::netcdf
