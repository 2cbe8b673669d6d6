// The table of features (docs/features.md, "The output"): its CSV header and rows, one place for
// `raypc features` and Python's Dataset.features.
#pragma once

#include "dataset/dataset.h"
#include "analysis/features.h"

#include <string>

namespace raypc::app {

// The header line: step, time, the feature's measures, each variable's mean/min/max with units, and
// the percent near each band depth of `options`.
std::string featureTableHeader(const dataset::Dataset& dataset, const analysis::FeatureOptions& options);
// A line per feature of `features`, in the header's order.
std::string featureTableRows(int step, double timeMyr, const analysis::StepFeatures& features);

}  // namespace raypc::app
