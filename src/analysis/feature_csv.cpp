#include "analysis/feature_csv.h"

#include "core/spherical.h"
#include "grid/names.h"

#include <fmt/format.h>
#include <fmt/ranges.h>

#include <cmath>
#include <iterator>

namespace raypc::analysis {

std::string trackCsv(const FeatureSeries& series)
{
    std::string rows = "track,step,time_myr,feature,volume_km3,mean_depth_km,centroid_lat_deg,centroid_lon_deg,"
                       "centroid_depth_km\n";
    for (const FeatureSeries::Row& r : series.rows()) {
        const Feature& x = r.feature;
        fmt::format_to(std::back_inserter(rows), "{},{},{},{},{:.6e},{:.3f},{:.4f},{:.4f},{:.3f}\n", r.track, r.step,
                       r.timeMyr, x.id, x.volumeKm3, x.meanDepthKm, x.centroidLatDeg, x.centroidLonDeg,
                       x.centroidDepthKm);
    }
    return rows;
}

std::string stallCsv(const FeatureSeries& series, std::span<const double> depthsKm, double halfWidthKm,
                     int seriesLastStep, StallMeasure measure)
{
    std::string rows = "track,depth_km,first_step,last_step,duration_myr,mean_radial_velocity_cm_per_yr,left\n";
    for (const auto& [track, s] : series.stalls(depthsKm, halfWidthKm, seriesLastStep, measure))
        fmt::format_to(std::back_inserter(rows), "{},{:g},{},{},{},{},{}\n", track, s.depthKm, s.firstStep,
                       s.lastStep, s.durationMyr,
                       std::isfinite(s.meanRadialVelocityCmPerYr) ? fmt::format("{:.4g}", s.meanRadialVelocityCmPerYr) : "",
                       s.left);
    return rows;
}

std::string eventCsv(const FeatureSeries& series, const dataset::Dataset& dataset)
{
    std::string rows = "step,time_myr,event,track,feature,other_features,centroid_lat_deg,centroid_lon_deg,mean_depth_km\n";
    for (const TrackEvent& e : series.events()) {
        const Feature& x = series.feature(e.step, e.feature);
        fmt::format_to(std::back_inserter(rows), "{},{},{},{},{},{},{:.4f},{:.4f},{:.3f}\n", e.step,
                       dataset.steps()[size_t(e.step)].timeMyr, trackEventName(e.kind), e.track, e.feature,
                       fmt::join(e.others, " "), x.centroidLatDeg, x.centroidLonDeg, x.meanDepthKm);
    }
    return rows;
}

std::string fluxCsv(const dataset::Dataset& dataset, int firstStep, std::span<const std::vector<ShellFlux>> bySteps,
                    std::span<const double> depthsKm, const std::vector<std::vector<size_t>>& avalanches, bool heat,
                    bool mass)
{
    std::vector<std::vector<bool>> avalanche(depthsKm.size(), std::vector<bool>(bySteps.size(), false));
    for (size_t d = 0; d < avalanches.size() && d < depthsKm.size(); ++d)
        for (const size_t i : avalanches[d])
            if (i < bySteps.size())
                avalanche[d][i] = true;
    std::string csv = "step,time_myr,depth_km,radius_km,down_km3_per_yr,up_km3_per_yr,net_km3_per_yr,"
                      "selected_down_km3_per_yr,selected_up_km3_per_yr,selected_percent_of_shell,avalanche";
    if (heat)
        csv += ",heat_flux_w,selected_heat_flux_w";
    if (mass)
        csv += ",mass_down_kg_per_yr,mass_up_kg_per_yr,selected_mass_down_kg_per_yr,selected_mass_up_kg_per_yr";
    csv += '\n';
    for (size_t i = 0; i < bySteps.size(); ++i) {
        const int step = firstStep + int(i);
        for (size_t d = 0; d < depthsKm.size(); ++d) {
            const ShellFlux& f = bySteps[i][d];
            fmt::format_to(std::back_inserter(csv), "{},{},{:g},{:.3f},{:.6e},{:.6e},{:.6e},{:.6e},{:.6e},{:.4f},{}", step,
                           dataset.steps()[size_t(step)].timeMyr, f.depthKm, f.radiusKm, f.downKm3PerYr, f.upKm3PerYr,
                           f.downKm3PerYr + f.upKm3PerYr, f.selectedDownKm3PerYr, f.selectedUpKm3PerYr,
                           100.0 * f.selectedAreaKm2 / f.areaKm2, avalanche[d][i] ? 1 : 0);
            if (heat)
                fmt::format_to(std::back_inserter(csv), ",{:.6e},{:.6e}", f.heatW, f.selectedHeatW);
            if (mass)
                fmt::format_to(std::back_inserter(csv), ",{:.6e},{:.6e},{:.6e},{:.6e}", f.massDownKgPerYr,
                               f.massUpKgPerYr, f.selectedMassDownKgPerYr, f.selectedMassUpKgPerYr);
            csv += '\n';
        }
    }
    return csv;
}

std::string profileCsvHeader(const dataset::VariableInfo* mean)
{
    // The columns as src/grid/names.json names them (Python's Dataset.stats too).
    std::string header = columns::csvHeader(columns::kProfile);
    if (mean)
        for (const char* pattern : columns::kProfileMeans)
            header += "," + fmt::format(fmt::runtime(pattern), fmt::arg("name", mean->name), fmt::arg("units", mean->units));
    return header + '\n';
}

std::string profileCsvRows(std::span<const StepSelection> selections, const grid::SphericalGrid& grid)
{
    std::string rows;
    for (const StepSelection& sel : selections) {
        const SelectionStats& s = sel.stats;
        for (size_t iR = 0; iR < grid.nR(); ++iR) {
            const double shell = s.shellVolumeByRadiusKm3[iR];
            fmt::format_to(std::back_inserter(rows), "{},{},{:.3f},{:.3f},{:.6e},{:.6e},{:.6f}", sel.step, sel.timeMyr,
                           grid.rKm[iR], kSurfaceRadiusKm - grid.rKm[iR], s.volumeByRadiusKm3[iR], shell,
                           100.0 * s.volumeByRadiusKm3[iR] / shell);
            // The mean variable's columns (empty where nothing is selected).
            if (!s.shellMeanByRadius.empty()) {
                const double selected = s.selectedMeanByRadius[iR];
                fmt::format_to(std::back_inserter(rows), ",{},{:.9g}",
                               std::isnan(selected) ? std::string() : fmt::format("{:.9g}", selected), s.shellMeanByRadius[iR]);
            }
            rows += '\n';
        }
    }
    return rows;
}

}  // namespace raypc::analysis
