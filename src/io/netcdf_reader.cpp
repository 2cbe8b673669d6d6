// Reading a netCDF file (netcdf_reader.h): its header and its snapshot, each from the file opened under
// the netCDF lock with its coordinates read (netcdf_coordinates.h), its variables checked
// (netcdf_variables.h) and read (netcdf_values.h); and listing a series's files.
#include "io/netcdf_reader.h"

#include "core/error.h"
#include "core/error_kinds.h"
#include "core/strings.h"
#include "core/system_memory.h"
#include "grid/variable_names.h"
#include "io/netcdf_values.h"

#include <algorithm>
#include <array>
#include <string_view>
#include <mutex>
#include <utility>

namespace raypc::io {
namespace netcdf {
namespace {

// A velocity the file names by CF standard names (upward_…, northward_…, eastward_… ending in
// "velocity", as CF spells the components of a flow): taken as the spherical components (radial,
// north, east) of vx, vy, vz, unless the user named the velocity or the file has vx, vy, vz. All
// three or nothing: two of them alone stay scalars as the file has them.
ReaderOptions withCfVelocity(const NcFile& file, ReaderOptions options)
{
    for (const char* component : varname::kVelocity)
        if (options.variableNames.contains(component) || file.findVar(component))
            return options;
    static constexpr std::array<std::string_view, 3> kPrefixes = {"upward_", "northward_", "eastward_"};
    std::array<std::vector<std::string>, 3> found;
    int nVars = 0;
    file.check(nc_inq_nvars(file.id(), &nVars), "listing variables");
    for (int v = 0; v < nVars; ++v) {
        const std::string standard = lowerCase(file.textAttribute(v, "standard_name").value_or(""));
        if (!standard.ends_with("velocity"))
            continue;
        for (size_t c = 0; c < 3; ++c)
            if (standard.starts_with(kPrefixes[c]))
                found[c].push_back(file.varName(v));
    }
    // One of each: several candidates for a component (e.g. two upward velocities) are left to --velocity.
    if (std::any_of(found.begin(), found.end(), [](const auto& names) { return names.size() != 1; }))
        return options;
    for (size_t c = 0; c < 3; ++c)
        options.variableNames[varname::kVelocity[c]] = found[c].front();
    options.velocityFrame = ReaderOptions::VelocityFrame::Spherical;
    return options;
}

// Opens `path` under the netCDF lock and reads its coordinates, what reading a header and reading a
// snapshot begin with; returns read(file, axes, options), the lock held until it returns.
template <class Read>
auto readOpened(const std::filesystem::path& path, const ReaderOptions& options, Read read)
{
    std::lock_guard lock(netcdfMutex());
    const NcFile file(path);
    const ReaderOptions effective = withCfVelocity(file, options);
    return read(file, readAxes(file, effective), effective);
}

// The header of an open file: its grid, format and steps, and every requested variable (checked)
// with its units.
FileHeader headerOf(const NcFile& file, const OpenedHeader& h, const ReaderOptions& options)
{
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
            fail("{}: {} has {} steps, {} has {}: the variables' time dimensions differ", file.path().string(),
                 fileName, layout.steps, header.variables.front().fileName, header.steps);
        header.steps = std::max(header.steps, layout.steps);
    }
    if (options.timeIndex >= header.steps)
        fail("{}: step {} of a file holding {}", file.path().string(), options.timeIndex, header.steps);
    return header;
}

// Every requested variable checked before any is read: its name in the file and its layout. Checks
// too that the step asked for is in the file and that the fields and one variable's buffer in file
// order fit in memory.
std::vector<std::pair<std::string, VariableLayout>> checkBeforeReading(const NcFile& file, const OpenedHeader& h,
                                                                       const std::vector<std::string>& requested,
                                                                       const ReaderOptions& options)
{
    const size_t fileCount = h.fileCount();
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
        fail("{}: step {} of a file holding {}", file.path().string(), options.timeIndex, steps);
    // The fields and one variable's buffer in file order.
    grid::checkGridFitsMemory(h.grid, requested.size() * fileCount * sizeof(float) + fileCount * bufferBytesPerValue,
                        file.path().string(), "read", availableMemory());
    return layouts;
}

grid::Snapshot snapshotOf(const NcFile& file, const OpenedHeader& h, const ReaderOptions& options)
{
    grid::Snapshot snapshot;
    snapshot.grid = h.grid;
    // Every variable is checked before any is read.
    const auto requested = requestedVariables(file, options, &h);
    const auto layouts = checkBeforeReading(file, h, requested, options);
    FileOrderBuffers buffers;
    for (size_t v = 0; v < requested.size(); ++v) {
        const auto& [fileName, layout] = layouts[v];
        snapshot.fields.push_back(readField(file, h, requested[v], fileName, layout, options, buffers));
    }
    normaliseVelocity(snapshot, options.velocityFrame, file.path().string());
    return snapshot;
}

}  // namespace
}  // namespace netcdf

FileHeader readHeader(const std::filesystem::path& path, const ReaderOptions& options)
{
    return netcdf::readOpened(path, options, netcdf::headerOf);
}

grid::Snapshot readSnapshot(const std::filesystem::path& path, const ReaderOptions& options)
{
    return netcdf::readOpened(path, options, netcdf::snapshotOf);
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
                failNotFound("{}: no such file", input.string());
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

}  // namespace raypc::io
