#include "io/series_input.h"

#include "core/clock.h"
#include "core/error.h"
#include "core/error_kinds.h"
#include "core/spherical.h"
#include "core/strings.h"
#include "core/system_memory.h"
#include "grid/variable_names.h"
#include "io/citcoms.h"
#include "io/mesh_resample.h"
#include "io/vtk_xml.h"

#include <fmt/format.h>
#include <fmt/ranges.h>
#include <spdlog/spdlog.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <map>
#include <system_error>

namespace raypc::io {
namespace {

namespace fs = std::filesystem;


bool hasExtension(const fs::path& p, const char* ext)
{
    return p.extension() == ext;
}

// The units of the variables ASPECT writes under these names (its manual, "Visualization
// postprocessors"), for the variables' metadata; other names get none.
std::string aspectUnits(const std::string& name)
{
    static const std::map<std::string, std::string> units = {
        {"T", "K"},          {"temperature", "K"},        {"nonadiabatic_temperature", "K"},
        {"p", "Pa"},         {"nonadiabatic_pressure", "Pa"}, {"density", "kg/m^3"},
        {"viscosity", "Pa s"}, {"thermal_expansivity", "1/K"}, {"thermal_conductivity", "W/m/K"},
        {"specific_heat", "J/kg/K"}, {"strain_rate", "1/s"}, {"adiabat", "K"}};
    const auto it = units.find(name);
    return it == units.end() ? std::string() : it->second;
}

// A step's point arrays as the dataset's variables: the file's array and component of each.
struct VtkVariable {
    std::string name, units;
    ArrayComponent source;
};

std::vector<VtkVariable> vtkVariables(const std::vector<std::pair<std::string, int>>& arrays, const fs::path& step)
{
    std::vector<VtkVariable> out;
    std::vector<std::string> left;
    for (const auto& [name, components] : arrays) {
        if (components == 1) {
            out.push_back({name, aspectUnits(name), {name, -1}});
        } else if (components == 3) {
            const bool velocity = name == "velocity";
            for (int c = 0; c < 3; ++c) {
                const std::string axis(1, "xyz"[c]);
                out.push_back({velocity ? "v" + axis : name + "_" + axis, velocity ? "m/s" : aspectUnits(name), {name, c}});
            }
        } else {
            left.push_back(fmt::format("{} ({} components)", name, components));
        }
    }
    if (!left.empty())
        spdlog::debug("{}: left out: {}", step.string(), fmt::join(left, ", "));
    if (out.empty())
        fail("{}: no scalar or 3-component point array to read", step.string());
    return out;
}

// The pieces of a step: a .pvtu record's, or the .vtu itself.
std::vector<fs::path> piecesOf(const fs::path& step)
{
    if (hasExtension(step, ".pvtu"))
        return vtk::readPvtu(step).pieces;
    return {step};
}

std::vector<vtk::Piece> readPieces(const fs::path& step)
{
    const std::vector<fs::path> paths = piecesOf(step);
    std::vector<vtk::Piece> pieces(paths.size());
    std::vector<std::string> errors(paths.size());
    // The pieces are independent files (one per MPI rank of the model): read them in parallel.
    tbb::parallel_for(size_t(0), paths.size(), [&](size_t i) {
        try {
            pieces[i] = vtk::readVtu(paths[i]);
        } catch (const Error& e) {
            errors[i] = e.what();
        }
    });
    for (const std::string& e : errors)
        if (!e.empty())
            fail("{}", e);
    return pieces;
}

// The point arrays a step announces: a .pvtu's PPointData, or a .vtu's own arrays.
std::vector<std::pair<std::string, int>> announcedArrays(const fs::path& step, const std::vector<vtk::Piece>* pieces)
{
    if (hasExtension(step, ".pvtu"))
        return vtk::readPvtu(step).pointArrays;
    std::vector<std::pair<std::string, int>> out;
    const vtk::Piece piece = pieces ? pieces->front() : vtk::readVtu(step);
    for (const auto& a : piece.pointData)
        out.emplace_back(a.name, a.components);
    return out;
}

// The mesh's coordinates in km: ASPECT writes SI metres; --radius-units overrides.
double meshKmPerUnit(const ReaderOptions& options)
{
    switch (options.radiusUnits) {
    case ReaderOptions::RadiusUnits::Km: return 1;
    case ReaderOptions::RadiusUnits::Nondimensional: return 6371;
    default: return 1e-3;
    }
}

grid::SphericalGrid chooseGrid(const ShellMesh& mesh, const ReaderOptions& options, size_t variables, const fs::path& step)
{
    if (options.targetGrid)
        return *options.targetGrid;
    const auto [nLat, nR, nLon] = options.resampleSize;
    if (nLat > 0)
        return resampleGrid(mesh, nLat, nR, nLon);
    // As fine as the finest cell, but the preprocessing of a step must fit in a quarter of the
    // memory available now (the arrays of every variable, stored and derived, at float32).
    const uint64_t bytesPerPoint = (variables + 4) * sizeof(float) * 2;
    const uint64_t memoryPoints = availableMemory().bytes / 4 / bytesPerPoint;
    const grid::SphericalGrid grid = defaultResampleGrid(mesh, std::min<uint64_t>(memoryPoints, grid::kMaxGridPoints));
    spdlog::debug("{}: finest cell {:.3g}° along a shell, {:.3g} km across: grid {}x{}x{} (lat x r x lon)",
                  step.string(), mesh.finestArcDeg, mesh.finestRadialKm, grid.nLat(), grid.nR(), grid.nLon());
    return grid;
}

FileHeader vtkHeader(const fs::path& step, const ReaderOptions& options)
{
    FileHeader h;
    h.format = "VTK XML (ASPECT layout), resampled";
    std::vector<vtk::Piece> pieces;
    if (!options.targetGrid)
        pieces = readPieces(step);
    for (const auto& v : vtkVariables(announcedArrays(step, pieces.empty() ? nullptr : &pieces), step))
        h.variables.push_back({.name = v.name, .fileName = v.source.name, .units = v.units, .longName = ""});
    if (options.targetGrid) {
        h.grid = *options.targetGrid;
    } else {
        const ShellMesh mesh = makeShellMesh(std::move(pieces), meshKmPerUnit(options), step.string());
        h.grid = chooseGrid(mesh, options, h.variables.size(), step);
    }
    return h;
}

// The variables of a mesh step resampled onto the grid (chooseGrid): one field per variable, points
// in no cell refused or (--fill-missing) filled; `origin` says what was read and how it went.
grid::Snapshot resampleMesh(const ShellMesh& mesh, const std::vector<VtkVariable>& variables, const ReaderOptions& options,
                      const fs::path& step, const char* format, double readSeconds)
{
    const auto start = std::chrono::steady_clock::now();
    grid::Snapshot snap;
    snap.grid = chooseGrid(mesh, options, variables.size(), step);
    grid::checkGridFitsMemory(snap.grid, uint64_t(variables.size() + 1) * snap.grid.cellCount() * sizeof(float),
                        step.string(), "resample", availableMemory());
    std::vector<ArrayComponent> arrays;
    for (const auto& v : variables)
        arrays.push_back(v.source);
    ResampleCounts counts;
    std::vector<std::vector<float>> values = resampleOntoGrid(mesh, snap.grid, arrays, step.string(), &counts);
    spdlog::debug("{}: {} cells read in {:.2f} s, resampled onto {}x{}x{} in {:.2f} s", step.string(), mesh.cellCount,
                  readSeconds, snap.grid.nLat(), snap.grid.nR(), snap.grid.nLon(), secondsSince(start));
    for (size_t a = 0; a < variables.size(); ++a)
        snap.fields.push_back(grid::Field{variables[a].name, variables[a].units, std::move(values[a])});
    // A regional mesh's grid is padded to the globe: the points outside its extent hold no data. A
    // point within the extent that no cell holds is a hole in the mesh.
    const grid::SphericalGrid& g = snap.grid;
    const auto holdsData = [&](size_t iLat, size_t iLon) { return g.holdsData(iLat, iLon); };
    if (counts.missing > 0) {
        if (!options.fillMissing) {
            const auto& first = snap.fields.front().values;
            size_t at = 0;
            while (!(std::isnan(first[at]) && g.holdsData(at / g.nLon() / g.nR(), at % g.nLon())))
                ++at;
            fail("{}: {} of {} grid points lie in no cell of the mesh ({} cells), the first at {}; use "
                 "--fill-missing to give them the mean of their radius shell",
                 step.string(), counts.missing, counts.points - counts.outside, mesh.cellCount,
                 grid::describeGridPoint(g, at));
        }
        for (grid::Field& f : snap.fields)
            grid::fillMissingByShellMean(g, f.values, fmt::format("{}: {}", step.string(), f.name), holdsData);
    }
    snap.origin = {{"format", format},
                   {"pieces", mesh.pieces.size()},
                   {"cells", mesh.cellCount},
                   {"points", mesh.pointCount},
                   {"grid_points", counts.points - counts.outside},
                   {"inside", counts.inside},
                   {"snapped", counts.snapped},
                   {"missing", counts.missing}};
    if (g.regional())
        snap.origin["outside_region"] = counts.outside;
    return snap;
}

grid::Snapshot vtkSnapshot(const fs::path& step, const ReaderOptions& options)
{
    const auto start = std::chrono::steady_clock::now();
    std::vector<vtk::Piece> pieces = readPieces(step);
    const double readSeconds = secondsSince(start);
    const std::vector<VtkVariable> variables = vtkVariables(announcedArrays(step, &pieces), step);
    const ShellMesh mesh = makeShellMesh(std::move(pieces), meshKmPerUnit(options), step.string());
    grid::Snapshot snap = resampleMesh(mesh, variables, options, step, "VTK XML (ASPECT layout)", readSeconds);
    for (size_t a = 0; a < variables.size(); ++a)
        if (variables[a].source.name == "velocity")
            for (float& v : snap.fields[a].values)
                v = float(double(v) / (kSecondsPerMyr / 1e6));  // m/year -> m/s (Julian years)
    return snap;
}

// CitcomS output: the options' scales (citcoms.h), and whether the command line gave R or κ.
citcoms::Scales citcomsScales(const ReaderOptions& options)
{
    citcoms::Scales s;
    s.temperatureK = options.temperatureScaleK;
    s.radiusKm = options.planetRadiusKm.value_or(s.radiusKm);
    s.diffusivityM2s = options.diffusivityM2s.value_or(s.diffusivityM2s);
    return s;
}
bool citcomsScalesGiven(const ReaderOptions& options) { return options.planetRadiusKm || options.diffusivityM2s; }

// A CitcomS step's variables: temperature, the velocity as vx, vy, vz (m/s, Cartesian), viscosity,
// and pressure where the output has it.
std::vector<VtkVariable> citcomsVariables(const std::vector<std::pair<std::string, int>>& arrays,
                                          const citcoms::Scales& scales)
{
    std::vector<VtkVariable> out;
    for (const auto& [name, components] : arrays) {
        if (components == 3) {
            for (int c = 0; c < 3; ++c)
                out.push_back({varname::kVelocity[size_t(c)], citcoms::unitsOf(name, scales), {name, c}});
        } else {
            out.push_back({name, citcoms::unitsOf(name, scales), {name, -1}});
        }
    }
    return out;
}

// The reader's options for a CitcomS step: the run's own resolution unless --grid says another.
ReaderOptions citcomsGridOptions(const ReaderOptions& options, const citcoms::Step& read)
{
    ReaderOptions natural = options;
    if (natural.resampleSize[0] == 0)
        natural.resampleSize = citcoms::naturalGridSize(read);
    return natural;
}

FileHeader citcomsHeader(const fs::path& step, const ReaderOptions& options)
{
    const citcoms::Scales scales = citcomsScales(options);
    FileHeader h;
    h.format = citcoms::formatName(step) + ", resampled";
    for (const auto& v : citcomsVariables(citcoms::stepArrays(step), scales))
        h.variables.push_back({.name = v.name, .fileName = v.source.name, .units = v.units, .longName = ""});
    // A later step of a series takes the first's grid: its values are read once, when the step is.
    if (options.targetGrid) {
        h.grid = *options.targetGrid;
        return h;
    }
    citcoms::Step read = citcoms::readStep(step, scales, citcomsScalesGiven(options));
    const ReaderOptions natural = citcomsGridOptions(options, read);
    const ShellMesh mesh = makeShellMesh(std::move(read.caps), 1.0, step.string());
    h.grid = chooseGrid(mesh, natural, h.variables.size(), step);
    return h;
}

grid::Snapshot citcomsSnapshot(const fs::path& step, const ReaderOptions& options)
{
    const auto start = std::chrono::steady_clock::now();
    const citcoms::Scales scales = citcomsScales(options);
    citcoms::Step read = citcoms::readStep(step, scales, citcomsScalesGiven(options));
    const double readSeconds = secondsSince(start);
    std::vector<std::pair<std::string, int>> arrays;
    for (const vtk::PointArray& a : read.caps.front().pointData)
        arrays.emplace_back(a.name, a.components);
    const std::vector<VtkVariable> variables = citcomsVariables(arrays, scales);
    const ReaderOptions natural = citcomsGridOptions(options, read);
    const ShellMesh mesh = makeShellMesh(std::move(read.caps), 1.0, step.string());
    return resampleMesh(mesh, variables, natural, step, read.format.c_str(), readSeconds);
}

// A step of a netCDF file holding several: "FILE#K" names step K (from 0) of FILE (listSeries).
// The file and the reader's options with that step.
struct NetcdfStep {
    fs::path file;
    ReaderOptions options;
};

NetcdfStep netcdfStep(const fs::path& step, const ReaderOptions& options)
{
    NetcdfStep at{step, options};
    at.options.timeIndex = 0;
    const std::string text = step.string();
    const size_t hash = text.rfind('#');
    std::error_code ec;
    if (hash == std::string::npos || hash + 1 == text.size() ||
        text.find_first_not_of("0123456789", hash + 1) != std::string::npos || fs::exists(step, ec))
        return at;  // a plain file (also one whose name ends in #digits)
    at.file = text.substr(0, hash);
    at.options.timeIndex = size_t(std::stoull(text.substr(hash + 1)));
    return at;
}

}  // namespace

std::vector<fs::path> stepSourceFiles(const fs::path& step)
{
    if (citcoms::isStep(step))
        return citcoms::stepFiles(step);
    if (!isVtkStep(step))
        return {netcdfStep(step, {}).file};  // FILE#K: step K of a file of several
    std::vector<fs::path> files{step};
    if (hasExtension(step, ".pvtu"))
        for (const fs::path& piece : vtk::readPvtu(step).pieces)
            files.push_back(piece);
    return files;
}

bool isVtkStep(const fs::path& step)
{
    return hasExtension(step, ".pvtu") || hasExtension(step, ".vtu");
}

bool isMeshStep(const fs::path& step)
{
    return isVtkStep(step) || citcoms::isStep(step);
}

SeriesListing listSeries(const std::vector<fs::path>& args, const ReaderOptions& options)
{
    SeriesListing out;
    std::vector<fs::path> netcdf;
    const auto addCollection = [&](const fs::path& pvd) {
        out.collection = pvd;
        for (const auto& step : vtk::readPvd(pvd)) {
            std::error_code ec;
            const fs::file_status status = fs::status(step.file, ec);
            if (!fs::exists(status))
                failNotFound("{}: names {}, which does not exist", pvd.string(), step.file.string());
            if (!fs::is_regular_file(status))
                fail("{}: names {}, which is {}, not a file", pvd.string(), step.file.string(),
                     fs::is_directory(status) ? "a directory" : fs::is_fifo(status) ? "a FIFO" : "a device or socket");
            if (!isVtkStep(step.file))
                fail("{}: names {}, expected a .pvtu or .vtu file", pvd.string(), step.file.string());
            out.steps.push_back(step.file);
            // The Universe is 13 800 Myr old: a later time is a unit mistaken (or a broken file).
            const double timeMyr = step.time * options.myrPerTimeUnit;
            if (!(std::abs(timeMyr) <= 13'800.0))
                fail("{}: DataSet {}: timestep {:g} is {:g} Myr, beyond the age of the Universe; give the unit of the "
                     "timesteps with --time-units years|seconds|Myr",
                     pvd.string(), step.file.filename().string(), step.time, timeMyr);
            out.timesMyr.push_back(timeMyr);
        }
    };
    bool collection = false, vtkFiles = false;
    std::map<long, fs::path> citcomsSteps;  // by step number: a step's caps given one by one count once
    for (const auto& arg : args) {
        std::error_code ec;
        const std::vector<fs::path> citcomsIn = fs::is_directory(arg, ec) ? citcoms::stepsIn(arg) : std::vector<fs::path>{};
        if (!citcomsIn.empty()) {
            for (const fs::path& step : citcomsIn)
                citcomsSteps[citcoms::stepNumber(step)] = step;
        } else if (citcoms::isStep(arg)) {
            if (!fs::exists(arg, ec))
                failNotFound("{}: no such file", arg.string());
            citcomsSteps.emplace(citcoms::stepNumber(arg), arg);
        } else if (fs::is_directory(arg, ec)) {
            std::vector<fs::path> pvds;
            bool hasNc = false;
            for (const auto& entry : fs::directory_iterator(arg)) {
                if (entry.path().extension() == ".pvd")
                    pvds.push_back(entry.path());
                hasNc = hasNc || entry.path().extension() == ".nc";
            }
            std::sort(pvds.begin(), pvds.end());
            const auto solution = std::find_if(pvds.begin(), pvds.end(),
                                               [](const fs::path& p) { return p.filename() == "solution.pvd"; });
            if (solution != pvds.end()) {
                addCollection(*solution), collection = true;
            } else if (pvds.size() == 1 && !hasNc) {
                addCollection(pvds.front()), collection = true;
            } else if (pvds.size() > 1 && !hasNc) {
                std::vector<std::string> names;
                for (const auto& p : pvds)
                    names.push_back(p.filename().string());
                fail("{}: holds several collections ({}) and no solution.pvd; give the one to read", arg.string(),
                     fmt::join(names, ", "));
            } else {
                netcdf.push_back(arg);
            }
        } else if (hasExtension(arg, ".pvd")) {
            if (!fs::exists(arg, ec))
                failNotFound("{}: no such file", arg.string());
            addCollection(arg), collection = true;
        } else if (isVtkStep(arg)) {
            if (!fs::exists(arg, ec))
                failNotFound("{}: no such file", arg.string());
            out.steps.push_back(arg), vtkFiles = true;
        } else {
            netcdf.push_back(arg);
        }
    }
    if (!citcomsSteps.empty()) {
        if (!out.steps.empty() || !netcdf.empty())
            fail("{}: CitcomS output and other inputs ({}) cannot make one series", citcomsSteps.begin()->second.string(),
                 (out.steps.empty() ? netcdf.front() : out.steps.front()).string());
        const citcoms::Scales scales = citcomsScales(options);
        for (const auto& [number, step] : citcomsSteps) {
            out.steps.push_back(step);
            if (const auto t = citcoms::stepTimeMyr(step, scales, citcomsScalesGiven(options)))
                out.timesMyr.push_back(*t);
        }
        if (out.timesMyr.size() != out.steps.size())  // the ASCII caps carry no time: dt_myr apart
            out.timesMyr.clear();
        out.vtk = true;
        out.kind = "citcoms";
        return out;
    }
    if (!out.steps.empty() && !netcdf.empty())
        fail("{}: netCDF inputs and VTK inputs ({}) cannot make one series", netcdf.front().string(),
             out.steps.front().string());
    if (collection && (vtkFiles || args.size() > 1))
        fail("a .pvd collection (or a directory holding one) is a whole series: give it alone");
    if (!out.steps.empty()) {
        out.vtk = true;
        out.kind = "vtk";
        if (vtkFiles)  // given one by one: natural order, no times
            std::sort(out.steps.begin(), out.steps.end(), [](const fs::path& a, const fs::path& b) {
                return naturalLess(a.filename().string(), b.filename().string());
            });
        return out;
    }
    // A file whose variables have a time dimension longer than 1 holds that many steps: FILE#0, FILE#1, …
    // A file that cannot be read counts one step here: its error comes when the step is read (a
    // served series shows its first steps while a later file is bad).
    for (const fs::path& file : listSnapshotFiles(netcdf)) {
        size_t steps = 1;
        try {
            steps = readHeader(file, options).steps;
        } catch (const Error&) {
        }
        if (steps == 1) {
            out.steps.push_back(file);
            continue;
        }
        for (size_t k = 0; k < steps; ++k)
            out.steps.push_back(file.string() + "#" + std::to_string(k));
    }
    return out;
}

FileHeader readStepHeader(const fs::path& step, const ReaderOptions& options)
{
    if (citcoms::isStep(step))
        return citcomsHeader(step, options);
    if (isVtkStep(step))
        return vtkHeader(step, options);
    const NetcdfStep at = netcdfStep(step, options);
    return readHeader(at.file, at.options);
}

grid::Snapshot readStep(const fs::path& step, const ReaderOptions& options)
{
    if (citcoms::isStep(step))
        return citcomsSnapshot(step, options);
    if (isVtkStep(step))
        return vtkSnapshot(step, options);
    const NetcdfStep at = netcdfStep(step, options);
    return readSnapshot(at.file, at.options);
}

}  // namespace raypc::io
