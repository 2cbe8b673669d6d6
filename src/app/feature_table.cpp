#include "app/feature_table.h"

#include <fmt/format.h>

#include <cmath>
#include <iterator>

namespace raypc::app {

std::string featureTableHeader(const dataset::Dataset& dataset, const analysis::FeatureOptions& options)
{
    std::string h = "step,time_myr,feature,points,volume_km3,percent_of_mantle,top_depth_km,bottom_depth_km,mean_depth_km,"
                    "centroid_lat_deg,centroid_lon_deg,centroid_depth_km";
    for (const dataset::VariableInfo& v : dataset.variables())
        for (const char* what : {"mean", "min", "max"})
            h += fmt::format(",{} {}{}", v.name, what, v.units.empty() ? "" : fmt::format(" [{}]", v.units));
    for (const double d : options.bandDepthsKm)
        h += fmt::format(",percent_within_{:g}km_of_{:g}km", options.bandHalfWidthKm, d);
    return h + "\n";
}

std::string featureTableRows(int step, double timeMyr, const analysis::StepFeatures& features)
{
    std::string rows;
    auto out = std::back_inserter(rows);
    auto number = [](double v) { return std::isfinite(v) ? fmt::format("{:.6g}", v) : std::string(); };
    for (const analysis::Feature& f : features.features) {
        fmt::format_to(out, "{},{},{},{},{:.6e},{:.6f},{:.3f},{:.3f},{:.3f},{:.4f},{:.4f},{:.3f}", step, timeMyr, f.id,
                       f.points, f.volumeKm3, 100.0 * f.fractionOfMantle, f.topDepthKm, f.bottomDepthKm, f.meanDepthKm,
                       f.centroidLatDeg, f.centroidLonDeg, f.centroidDepthKm);
        for (const analysis::VariableSummary& v : f.variables)
            fmt::format_to(out, ",{},{},{}", number(v.mean), number(v.min), number(v.max));
        for (const double share : f.bandFractions)
            fmt::format_to(out, ",{:.4f}", 100.0 * share);
        rows += '\n';
    }
    return rows;
}

}  // namespace raypc::app
