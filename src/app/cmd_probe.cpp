// raypc probe DATASET --time T --lat A --lon B --r R_KM [--var NAME]
#include "app/command.h"
#include "app/options.h"
#include "analysis/probe.h"
#include "dataset/dataset.h"

#include <fmt/format.h>
#include <nlohmann/json.hpp>

namespace raypc::app {
namespace {

struct ProbeArgs {
    std::string dataset, time = "0", var;
    double latDeg = 0, lonDeg = 0, rKm = 0;
    int level = 0;
};

const CommandRegistration kProbeCommand(
    "probe", "Print the interpolated values at one point and step, as JSON with units",
    [](CLI::App& cmd) {
        auto args = std::make_shared<ProbeArgs>();
        cmd.add_option("dataset", args->dataset, "Dataset directory")->required();
        cmd.add_option("-t,--time", args->time, "Step index (0-based) or time like 24Myr")->capture_default_str();
        cmd.add_option("--lat", args->latDeg, "Latitude in degrees north")->required();
        cmd.add_option("--lon", args->lonDeg, "Longitude in degrees east (any range; wraps)")->required();
        cmd.add_option("--r", args->rKm, "Radius in km (3485 core-mantle boundary .. 6371 surface)")->required();
        cmd.add_option("--var", args->var, "Only this variable");
        cmd.add_option("--lod", args->level, "Level of detail (0 = full resolution)")->capture_default_str();
        cmd.callback([args] {
            const auto dataset = dataset::Dataset::open(args->dataset);
            const int step = parseStep(*dataset, args->time);
            const nlohmann::json j = analysis::probeJson(*dataset, step, args->level, args->latDeg, args->lonDeg, args->rKm, args->var);
            fmt::print("{}\n", j.dump(2));
        });
    },
    40);

}  // namespace
}  // namespace raypc::app
