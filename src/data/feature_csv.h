// The CSV tables of features followed through a series and of the flux across shells: what `raypc
// features --tracks/--events/--stalls` and `raypc flux` write, and what the UI's Features panel
// exports (sent by POST /api/features), so that the columns and numbers are written in one place.
// docs/features.md describes the columns.
//
// Thread safety: pure functions of their arguments.
#pragma once

#include "data/dataset.h"
#include "data/feature_series.h"
#include "data/flux.h"

#include <span>
#include <string>
#include <vector>

namespace raypc {

// A row per track and step: track, step, time_myr, feature, volume_km3, mean_depth_km, centroid.
std::string trackCsv(const FeatureSeries& series);
// A row per event: step, time_myr, event, track, feature, other_features, centroid, mean_depth_km.
std::string eventCsv(const FeatureSeries& series, const Dataset& dataset);
// A row per stall (FeatureSeries::stalls): track, depth_km, first_step, last_step, duration_myr,
// mean_radial_velocity_cm_per_yr (empty without one), left.
std::string stallCsv(const FeatureSeries& series, std::span<const double> depthsKm, double halfWidthKm,
                     int seriesLastStep, StallMeasure measure);
// A row per step and shell of `bySteps` (steps firstStep, firstStep + 1, …; each with the shells of
// `depthsKm`): step, time_myr, depth_km, radius_km, down/up/net km³/yr, the selection's down and up,
// selected_percent_of_shell, avalanche (1 for the steps of `avalanches`, avalancheStepsPerShell); with
// `heat` the heat flux (W, shell and selection); with `mass` the mass flux (kg/yr, down and up, shell
// and selection).
std::string fluxCsv(const Dataset& dataset, int firstStep, std::span<const std::vector<ShellFlux>> bySteps,
                    std::span<const double> depthsKm, const std::vector<std::vector<size_t>>& avalanches, bool heat,
                    bool mass);

}  // namespace raypc
