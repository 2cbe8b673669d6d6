// raypc probe DATASET --time T --lat A --lon B --r R_KM [--var NAME]
#include "app/command.h"
#include "app/options.h"
#include "core/error.h"
#include "core/spherical.h"
#include "data/dataset.h"
#include "data/sampler.h"

#include <fmt/format.h>
#include <nlohmann/json.hpp>

namespace raypc::app {
namespace {

struct ProbeArgs {
    std::string dataset, time = "0", var;
    double latDeg = 0, lonDeg = 0, rKm = 0;
    int level = 0;
};

const CommandRegistration kRegistration(
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
            const auto dataset = Dataset::open(args->dataset);
            const int step = parseStep(*dataset, args->time);
            if (!(args->latDeg >= -90 && args->latDeg <= 90))
                fail("--lat: {} is outside [-90, 90] degrees", args->latDeg);
            int only = -1;
            if (!args->var.empty() && (only = dataset->variableIndex(args->var)) < 0) {
                fail("--var: unknown variable '{}'; the dataset has: {}", args->var,
                     fmt::join(dataset->variableNames(), ", "));
            }
            const auto volume = dataset->load(step, args->level);
            const GridSampler sampler(volume->grid());
            const auto at = sampler.locate(args->latDeg, args->lonDeg, args->rKm);
            if (!at)
                fail("--r: {} km is outside the mantle shell {}..{} km", args->rKm, volume->grid().rKm.front(),
                     volume->grid().rKm.back());
            const Vec3d p = sphericalToCartesianKm(args->latDeg, args->lonDeg, args->rKm);
            nlohmann::json j{{"step", step},
                             {"time_myr", dataset->steps()[step].timeMyr},
                             {"level", args->level},
                             {"point",
                              {{"lat", {{"value", args->latDeg}, {"units", "degrees_north"}}},
                               {"lon", {{"value", wrapLonDeg(args->lonDeg)}, {"units", "degrees_east"}}},
                               {"radius", {{"value", args->rKm}, {"units", "km"}}},
                               {"depth", {{"value", kSurfaceRadiusKm - args->rKm}, {"units", "km"}}},
                               {"x", {{"value", p.x}, {"units", "km"}}},
                               {"y", {{"value", p.y}, {"units", "km"}}},
                               {"z", {{"value", p.z}, {"units", "km"}}}}}};
            nlohmann::json values = nlohmann::json::object();
            for (size_t v = 0; v < dataset->variables().size(); ++v) {
                if (only >= 0 && static_cast<int>(v) != only)
                    continue;
                const auto& info = dataset->variables()[v];
                values[info.name] = {{"value", sampler.sample(volume->values(v), *at)}, {"units", info.units}};
            }
            j["values"] = values;
            fmt::print("{}\n", j.dump(2));
        });
    },
    40);

}  // namespace
}  // namespace raypc::app
