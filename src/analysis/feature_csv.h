// The CSV tables of features followed through a series, of the flux across shells and of a
// selection's depth profile over time: what `raypc features --tracks/--events/--stalls`, `raypc flux`
// and `raypc stats --profile` write, and what the UI's Features panel exports (sent by POST
// /api/features and POST /api/time-depth?format=csv), so that the columns and numbers are written in
// one place. docs/features.md describes the columns.
//
// Thread safety: pure functions of their arguments.
#pragma once

#include "dataset/dataset.h"
#include "analysis/feature_series.h"
#include "analysis/flux.h"
#include "analysis/selection.h"

#include <span>
#include <string>
#include <vector>

namespace raypc::analysis {

// A row per track and step: track, step, time_myr, feature, volume_km3, mean_depth_km, centroid.
std::string trackCsv(const FeatureSeries& series);
// A row per event: step, time_myr, event, track, feature, other_features, centroid, mean_depth_km.
std::string eventCsv(const FeatureSeries& series, const dataset::Dataset& dataset);
// A row per stall (FeatureSeries::stalls): track, depth_km, first_step, last_step, duration_myr,
// mean_radial_velocity_cm_per_yr (empty without one), left.
std::string stallCsv(const FeatureSeries& series, std::span<const double> depthsKm, double halfWidthKm,
                     int seriesLastStep, StallMeasure measure);
// A row per step and shell of `bySteps` (steps firstStep, firstStep + 1, …; each with the shells of
// `depthsKm`): step, time_myr, depth_km, radius_km, down/up/net km³/yr, the selection's down and up,
// selected_percent_of_shell, avalanche (1 for the steps of `avalanches`, avalancheStepsPerShell); with
// `heat` the heat flux (W, shell and selection); with `mass` the mass flux (kg/yr, down and up, shell
// and selection).
std::string fluxCsv(const dataset::Dataset& dataset, int firstStep, std::span<const std::vector<ShellFlux>> bySteps,
                    std::span<const double> depthsKm, const std::vector<std::vector<size_t>>& avalanches, bool heat,
                    bool mass);

// The depth profile of a selection in every step (selectionOverTime): the header — step, time_myr,
// radius_km, depth_km, selected_volume_km3, shell_volume_km3, selected_percent_of_shell, and with
// `mean` (the variable whose mean per radius the selections hold) "NAME selected mean [UNITS]" and
// "NAME shell mean [UNITS]" — and the rows, a row per step and radius of `grid` (the selected mean
// empty where nothing is selected). Rows of consecutive blocks of steps concatenate (MPI ranks).
std::string profileCsvHeader(const dataset::VariableInfo* mean);
std::string profileCsvRows(std::span<const StepSelection> selections, const grid::SphericalGrid& grid);

}  // namespace raypc::analysis
