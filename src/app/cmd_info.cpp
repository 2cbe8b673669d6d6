// raypc info PATH [--json]: what a netCDF file or a dataset holds.
#include "app/command.h"
#include "app/options.h"
#include "core/error.h"
#include "core/json_input.h"
#include "core/atomic_file.h"
#include "dataset/dataset_format.h"
#include "dataset/dataset.h"
#include "io/netcdf_reader.h"
#include "preprocess/preprocess.h"
#include "io/series_input.h"

#include <fmt/format.h>
#include <nlohmann/json.hpp>

#include <algorithm>

namespace raypc::app {
namespace {

using nlohmann::json;

json describeGrid(const grid::SphericalGrid& g)
{
    auto axis = [](const std::vector<double>& c) {
        double minStep = c.size() > 1 ? c[1] - c[0] : 0, maxStep = minStep;
        for (size_t i = 1; i < c.size(); ++i) {
            minStep = std::min(minStep, c[i] - c[i - 1]);
            maxStep = std::max(maxStep, c[i] - c[i - 1]);
        }
        return json{{"count", c.size()}, {"first", c.front()}, {"last", c.back()}, {"min_spacing", minStep},
                    {"max_spacing", maxStep}};
    };
    json j{{"lat_deg", axis(g.latDeg)}, {"r_km", axis(g.rKm)}, {"lon_deg", axis(g.lonDeg)},
           {"cells", g.cellCount()}, {"volume_km3", g.totalVolumeKm3()}};
    // A regional grid: padded to the globe with points of no data; the volume is the region's.
    if (g.regional())
        j["data_region"] = {{"lat_deg", g.dataLatDeg ? json(*g.dataLatDeg) : json(std::array<double, 2>{-90, 90})},
                            {"lon_deg", g.dataLonDeg ? json(*g.dataLonDeg) : json(std::array<double, 2>{0, 360})}};
    return j;
}

// A netCDF file, or a VTK XML series's first step (a .pvd collection, its directory, a .pvtu or
// .vtu), as the dataset pipeline would read it: resampled, with how.
json describeFile(const std::filesystem::path& path, const io::ReaderOptions& options)
{
    const io::SeriesListing listing = io::listSeries({path}, options);
    const std::filesystem::path& step = listing.steps.front();
    // The step first (a mesh is read and resampled once), then its header on that grid (for a mesh
    // only its record is read again).
    const grid::Snapshot snap = io::readStep(step, options);
    io::ReaderOptions fixed = options;
    fixed.targetGrid = snap.grid;
    const io::FileHeader header = io::readStepHeader(step, fixed);
    json j{{"kind", listing.kind}, {"path", path.string()}, {"format", header.format},
           {"grid", describeGrid(snap.grid)}};
    if (listing.vtk) {
        j["steps"] = json::array();
        for (size_t s = 0; s < listing.steps.size(); ++s)
            j["steps"].push_back({{"source", listing.steps[s].string()},
                                  {"time_myr", listing.timesMyr.empty() ? json(nullptr) : json(listing.timesMyr[s])}});
        j["resampled"] = snap.origin;
        // How the .pvd's timesteps were read (--time-units).
        j["time_unit"] = options.myrPerTimeUnit == 1 ? "Myr" : options.myrPerTimeUnit == 1e-6 ? "years" : "seconds";
    }
    j["variables"] = json::array();
    for (size_t i = 0; i < snap.fields.size(); ++i) {
        grid::checkFinite(snap, snap.fields[i], step.string());  // as preprocess does: no range of a NaN
        const auto stats = preprocess::computeStats(snap.grid, snap.fields[i].values);
        j["variables"].push_back({{"name", snap.fields[i].name},
                                  {"name_in_file", header.variables[i].fileName},
                                  {"long_name", header.variables[i].longName},
                                  {"units", snap.fields[i].units},
                                  {"min", stats.range.min},
                                  {"max", stats.range.max},
                                  {"mean", stats.mean},
                                  {"missing_percent", 100 * stats.missingFraction}});
    }
    return j;
}

json describeDataset(const dataset::Dataset& d)
{
    json j{{"kind", "dataset"},
           {"path", d.dir().string()},
           {"dt_myr", d.dtMyr()},
           {"encoding", std::string(dataset::encodingName(d.encoding()))}};
    j["levels"] = json::array();
    for (size_t l = 0; l < d.levels().size(); ++l) {
        const auto& level = d.levels()[l];
        j["levels"].push_back({{"level", l},
                               {"grid", describeGrid(level.grid)},
                               {"bricks", level.bricks.brickCount()},
                               {"brick_size", level.bricks.size}});
    }
    j["variables"] = json::array();
    for (const auto& v : d.variables())
        j["variables"].push_back({{"name", v.name},
                                  {"units", v.units},
                                  {"derived", v.derived},
                                  {"stored", v.stored},
                                  {"source", v.source},
                                  {"long_name", v.longName},
                                  {"min", v.global.range.min},
                                  {"max", v.global.range.max},
                                  {"mean", v.global.mean},
                                  {"missing_percent", 100 * v.global.missingFraction}});
    j["coordinates"] = json::array();
    for (const auto& c : grid::coordinateInfos())
        j["coordinates"].push_back({{"name", c.name}, {"units", c.units}});
    j["steps"] = json::array();
    for (const auto& s : d.steps()) {
        j["steps"].push_back({{"index", s.index}, {"time_myr", s.timeMyr}, {"source", s.source}});
        if (!s.origin.is_null())
            j["steps"].back()["resampled"] = s.origin;
    }
    // What a difference dataset (raypc diff) is the difference of, as its manifest records it.
    const std::filesystem::path manifest = d.dir() / dataset::format::kManifest;
    if (const json m = parseJsonInput(readFile(manifest), manifest.string()); m.contains("difference"))
        j["difference"] = m["difference"];
    return j;
}

// Where a dataset's variable comes from: "  (computed from vs when read)", "  (derived from vx, vy, vz)", "  (from 'T')" when the
// input names it otherwise; a file's variables say so when --map renamed them.
std::string sourceNote(const json& v)
{
    const std::string source = v.value("source", std::string());
    if (!v.value("stored", true))
        return fmt::format("  (computed from {} when read)", source);
    if (v.value("derived", false)) {
        const std::string longName = v.value("long_name", std::string());
        return (source.empty() ? "  (derived)" : fmt::format("  (derived from {})", source)) +
               (longName.empty() ? "" : "  " + longName);
    }
    const std::string inFile = v.value("name_in_file", source), longName = v.value("long_name", std::string());
    const std::string from =
        !inFile.empty() && inFile != v["name"].get<std::string>() ? fmt::format("  (from '{}')", inFile) : "";
    return longName.empty() ? from : fmt::format("{}  {}", from, longName);
}

void printText(const json& j)
{
    auto gridLine = [](const json& g) {
        return fmt::format("{} x {} x {} (lat x r x lon) = {} points; lat {}..{} deg, r {}..{} km, lon {}..{} deg",
                           g["lat_deg"]["count"].get<size_t>(), g["r_km"]["count"].get<size_t>(),
                           g["lon_deg"]["count"].get<size_t>(), g["cells"].get<size_t>(),
                           g["lat_deg"]["first"].get<double>(), g["lat_deg"]["last"].get<double>(),
                           g["r_km"]["first"].get<double>(), g["r_km"]["last"].get<double>(),
                           g["lon_deg"]["first"].get<double>(), g["lon_deg"]["last"].get<double>()) +
               (g.contains("data_region")
                    ? fmt::format("; regional: data within lat {:g}..{:g} deg, lon {:g}..{:g} deg east (padded to the "
                                  "globe with points of no data; statistics are of the region)",
                                  g["data_region"]["lat_deg"][0].get<double>(), g["data_region"]["lat_deg"][1].get<double>(),
                                  g["data_region"]["lon_deg"][0].get<double>(), g["data_region"]["lon_deg"][1].get<double>())
                    : std::string());
    };
    if (j["kind"] == "netcdf") {
        fmt::print("{} (netCDF, {})\n  grid: {}\n", j["path"].get<std::string>(), j["format"].get<std::string>(),
                   gridLine(j["grid"]));
    } else if (j["kind"] == "vtk" || j["kind"] == "citcoms") {
        const auto& steps = j["steps"];
        const json& r = j["resampled"];
        fmt::print("{} ({})\n  steps: {}", j["path"].get<std::string>(), j["format"].get<std::string>(), steps.size());
        if (!steps.front()["time_myr"].is_null() && j["kind"] == "vtk")
            fmt::print(" ({:g} .. {:g} Myr; the collection's times read as {}, see --time-units)",
                       steps.front()["time_myr"].get<double>(), steps.back()["time_myr"].get<double>(),
                       j["time_unit"].get<std::string>());
        else if (!steps.front()["time_myr"].is_null())
            fmt::print(" ({:g} .. {:g} Myr: the nondimensional times in R^2/kappa, see --diffusivity)",
                       steps.front()["time_myr"].get<double>(), steps.back()["time_myr"].get<double>());
        fmt::print("\n  first step: {} cells in {} pieces, resampled onto {}\n", r["cells"].get<size_t>(),
                   r["pieces"].get<size_t>(), gridLine(j["grid"]));
        const double points = r["grid_points"].get<double>();
        fmt::print("  grid points inside a cell {:.2f} %, snapped to the nearest cell {:.2f} %, in none {}\n",
                   100 * r["inside"].get<double>() / points, 100 * r["snapped"].get<double>() / points,
                   r["missing"].get<size_t>());
    } else {
        fmt::print("{} (RayPC dataset, level arrays {})\n", j["path"].get<std::string>(),
                   j["encoding"].get<std::string>() == "u16" ? "u16, quantised per brick" : "float32");
        for (const auto& l : j["levels"])
            fmt::print("  level {}: {}; {} bricks of {}^3\n", l["level"].get<int>(), gridLine(l["grid"]),
                       l["bricks"].get<size_t>(), l["brick_size"].get<int>());
        const auto& steps = j["steps"];
        fmt::print("  steps: {} ({} .. {} Myr, {} Myr apart; {} .. {})\n", steps.size(),
                   steps.front()["time_myr"].get<double>(), steps.back()["time_myr"].get<double>(),
                   j["dt_myr"].get<double>(), steps.front()["source"].get<std::string>(),
                   steps.back()["source"].get<std::string>());
        if (j.contains("difference")) {
            const json& d = j["difference"];
            if (d["b"].is_null())
                fmt::print("  difference: step differences X(t) − X(t−{}) of {} ({} variables; {:.1f} % covered)\n",
                           d["step_lag"].get<int>(), d["a"].get<std::string>(), d["variables"].size(),
                           100 * d["covered_fraction"].get<double>());
            else
                fmt::print("  difference: {} − {} on the first one's grid, steps paired by {} ({} variables; the "
                           "second covers {:.1f} % of the grid)\n",
                           d["a"].get<std::string>(), d["b"].get<std::string>(), d["match"].get<std::string>(),
                           d["variables"].size(), 100 * d["covered_fraction"].get<double>());
        }
        if (const auto& first = steps.front(); first.contains("resampled")) {
            const json& r = first["resampled"];
            const double points = r.value("grid_points", 1.0);
            fmt::print("  source: {}, resampled onto level 0; step 0: {} cells in {} pieces, grid points inside a "
                       "cell {:.2f} %, snapped to the nearest cell {:.2f} %, in none {}\n",
                       r.value("format", std::string("a mesh")), r.value("cells", size_t(0)), r.value("pieces", size_t(0)),
                       100 * r.value("inside", 0.0) / points, 100 * r.value("snapped", 0.0) / points,
                       r.value("missing", size_t(0)));
        }
    }
    fmt::print("  variables{}:\n", j["kind"] == "dataset" ? " (ranges over all steps)" : "");
    for (const auto& v : j["variables"])
        fmt::print("    {:<42} [{:<8}] {:>12.5g} .. {:<12.5g} mean {:.5g}{}{}\n", v["name"].get<std::string>(),
                   v["units"].get<std::string>(), v["min"].get<double>(), v["max"].get<double>(),
                   v["mean"].get<double>(),
                   v.value("missing_percent", 0.0) > 0
                       ? fmt::format("  missing {:.3g} % (of the region)", v["missing_percent"].get<double>())
                       : std::string(),
                   sourceNote(v));
    if (j.contains("coordinates")) {
        std::vector<std::string> names;
        for (const auto& c : j["coordinates"])
            names.push_back(fmt::format("{} [{}]", c["name"].get<std::string>(), c["units"].get<std::string>()));
        fmt::print("  coordinates (brushable): {}\n", fmt::join(names, ", "));
    }
}

struct InfoArgs {
    std::string path;
    bool json = false;
    ReaderFlags reader;
};

const CommandRegistration kInfoCommand(
    "info", "Describe a netCDF snapshot or a RayPC dataset: grid, variables with units and ranges, steps, levels",
    [](CLI::App& cmd) {
        auto args = std::make_shared<InfoArgs>();
        cmd.add_option("path", args->path,
                       "A netCDF file, a dataset directory, or ASPECT's output (solution.pvd or its directory, a "
                       ".pvtu or .vtu step; the first step is described as resampled)")
            ->required();
        cmd.add_flag("--json", args->json, "Print JSON");
        args->reader.add(cmd);
        cmd.callback([args] {
            const std::filesystem::path path = args->path;
            const bool dataset = std::filesystem::is_directory(path) && std::filesystem::exists(path / "dataset.json");
            const json j = dataset ? describeDataset(*dataset::Dataset::open(path)) : describeFile(path, args->reader.toOptions());
            if (args->json)
                fmt::print("{}\n", j.dump(2));
            else
                printText(j);
        });
    },
    30);

}  // namespace
}  // namespace raypc::app
