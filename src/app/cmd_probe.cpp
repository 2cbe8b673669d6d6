// raypc probe DATASET --time T --lat A --lon B --r R_KM [--var NAME]
#include "app/command.h"
#include "app/options.h"
#include "core/error.h"
#include "core/spherical.h"
#include "data/dataset.h"
#include "data/sampler.h"

#include <fmt/format.h>
#include <nlohmann/json.hpp>

#include <algorithm>

namespace raypc::app {
namespace {

// The largest error a sample's value can have from quantisation (docs/format.md, "Encoding of the
// level arrays"): the sample is a weighted mean of grid values (trilinear, and in a pole cap also
// the outermost row's ring means), so its error is at most the largest bound among those points.
double quantisationBound(const StepVolume& volume, size_t var, const GridSampler::Location& at)
{
    if (volume.encoding() == ValueEncoding::Float32)
        return 0;
    double bound = 0;
    for (size_t iLat : {at.lat0, at.lat1})
        for (size_t iR : {at.r0, at.r1}) {
            if (at.poleWeight > 0) {
                for (size_t iLon = 0; iLon < volume.grid().nLon(); ++iLon)
                    bound = std::max(bound, volume.errorBound(var, iLat, iR, iLon));
            } else {
                for (size_t iLon : {at.lon0, at.lon1})
                    bound = std::max(bound, volume.errorBound(var, iLat, iR, iLon));
            }
        }
    return bound;
}

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
                // Point reads: a u16 variable is not decoded whole for one sample.
                auto valueAt = [&](size_t iLat, size_t iR, size_t iLon) { return volume->value(v, iLat, iR, iLon); };
                values[info.name] = {{"value", sampler.sample(valueAt, *at)},
                                     {"units", info.units},
                                     {"quantisation_error_max", quantisationBound(*volume, v, *at)}};
            }
            j["values"] = values;
            fmt::print("{}\n", j.dump(2));
        });
    },
    40);

}  // namespace
}  // namespace raypc::app
