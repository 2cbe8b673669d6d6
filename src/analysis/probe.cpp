#include "analysis/probe.h"

#include "core/error.h"
#include "core/error_kinds.h"
#include "grid/coordinates.h"
#include "grid/sampler.h"

#include <cmath>
#include <fmt/format.h>
#include <fmt/ranges.h>

#include <algorithm>

namespace raypc::analysis {
namespace {

// The largest error a sample's value can have from quantisation (docs/format.md, "Encoding of the
// level arrays"): the sample is a weighted mean of grid values (trilinear, and in a pole cap also
// the outermost row's ring means), so its error is at most the largest bound among those points.
double quantisationBound(const dataset::StepVolume& volume, size_t var, const grid::GridSampler::Location& at)
{
    if (volume.encoding() == dataset::ValueEncoding::Float32)
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

}  // namespace

nlohmann::json probeJson(const dataset::Dataset& dataset, int step, int level, double latDeg, double lonDeg, double rKm,
                         const std::string& var, const ProbeArgumentNames& names)
{
    dataset.checkStep(step, names.step);
    dataset.checkLevel(level, names.level);
    return probeJson(dataset, *dataset.load(step, level), step, level, latDeg, lonDeg, rKm, var, names);
}

nlohmann::json probeJson(const dataset::Dataset& dataset, const dataset::StepVolume& volumeAtStep, int step, int level, double latDeg,
                         double lonDeg, double rKm, const std::string& var, const ProbeArgumentNames& names)
{
    if (!(latDeg >= -90 && latDeg <= 90))
        fail("{}: {} is outside [-90, 90] degrees", names.lat, latDeg);
    int only = -1;
    if (!var.empty() && (only = dataset.variableIndex(var)) < 0) {
        failUnknownName("{}: unknown variable '{}'; the dataset has: {}", names.var, var,
                        fmt::join(dataset.variableNames(), ", "));
    }
    const dataset::StepVolume* volume = &volumeAtStep;  // the code below reads it through a pointer
    const grid::GridSampler sampler(volume->grid());
    const auto at = sampler.locate(latDeg, lonDeg, rKm);
    if (!at)
        fail("{}: {} km is outside the mantle shell {}..{} km", names.r, rKm, volume->grid().rKm.front(),
             volume->grid().rKm.back());
    nlohmann::json point = nlohmann::json::object();  // x, y, z, lat, lon, radius, depth (grid/coordinates.h)
    for (const grid::CoordinateInfo& c : grid::coordinateInfos())
        point[c.name] = {{"value", grid::coordinateValue(c.id, latDeg, lonDeg, rKm)}, {"units", c.units}};
    nlohmann::json j{{"step", step}, {"time_myr", dataset.steps()[step].timeMyr}, {"level", level}, {"point", point}};
    nlohmann::json values = nlohmann::json::object();
    for (size_t v = 0; v < dataset.variables().size(); ++v) {
        if (only >= 0 && static_cast<int>(v) != only)
            continue;
        const auto& info = dataset.variables()[v];
        // Point reads: a u16 variable is not decoded whole for one sample.
        auto valueAt = [&](size_t iLat, size_t iR, size_t iLon) { return volume->value(v, iLat, iR, iLon); };
        const double value = sampler.sample(valueAt, *at);
        if (std::isnan(value))  // missing there, or outside a regional model's data
            values[info.name] = {{"value", nullptr}, {"units", info.units}, {"no_data", true}};
        else
            values[info.name] = {{"value", value},
                                 {"units", info.units},
                                 {"quantisation_error_max", quantisationBound(*volume, v, *at)}};
    }
    j["values"] = values;
    return j;
}

}  // namespace raypc::analysis
