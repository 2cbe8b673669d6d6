// Which variables of a netCDF file are read (netcdf_variables.h), and checking that each has the
// grid's dims and at most one dimension of steps besides them.
#include "io/netcdf_variables.h"

#include "grid/variable_names.h"

#include <fmt/format.h>

#include <algorithm>
#include <optional>

namespace raypc::io::netcdf {
namespace {

// The name a variable of the file is read as: the one --map gives it, else its own.
std::string canonicalNameOf(const ReaderOptions& options, const std::string& fileName)
{
    for (const auto& [canonical, inFile] : options.variableNames)
        if (inFile == fileName)
            return canonical;
    return fileName;
}

}  // namespace

std::string fileNameOf(const ReaderOptions& options, const std::string& canonicalName)
{
    const auto it = options.variableNames.find(canonicalName);
    return it == options.variableNames.end() ? canonicalName : it->second;
}

std::vector<std::string> requestedVariables(const NcFile& file, const ReaderOptions& options,
                                            const OpenedHeader* h)
{
    if (!options.variables.empty())
        return options.variables;
    const auto& contest = grid::contestVariableNames();
    // The contest's eight variables when the file has them all, else every variable on the grid's dims.
    const bool contestFile = std::all_of(contest.begin(), contest.end(), [&](const std::string& name) {
        return file.findVar(fileNameOf(options, name)).has_value();
    });
    std::vector<std::string> names = contestFile ? contest : std::vector<std::string>{};
    int nVars = 0;
    if (!contestFile)
        file.check(nc_inq_nvars(file.id(), &nVars), "listing variables");
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

}  // namespace raypc::io::netcdf
