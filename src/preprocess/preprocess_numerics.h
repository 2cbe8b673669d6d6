// The numerics of preprocessing (docs/format.md): derived variables, coarser levels by
// volume-weighted averaging, volume-weighted statistics and histograms, and the
// parallel-coordinates sample. Pure functions of their arguments, reproducible bit for bit
// whatever the number of threads; preprocess.cpp runs them, step by step.
#pragma once

#include "dataset/dataset.h"
#include "grid/snapshot.h"

#include <cstdint>
#include <span>
#include <string>
#include <vector>

namespace raypc::preprocess {

// `value` as float32; ±infinity beyond float32's range (where a plain conversion is undefined).
float toFloat32(double value);

// Appends the derived variables a dataset stores: with a velocity (vx, vy, vz in m/s) "radial
// velocity" and "velocity magnitude" (cm/yr). A model without a velocity (a tomography model) gets
// none. Values too large for float32 become infinite (see checkFinite).
void addStoredDerivedVariables(grid::Snapshot& snapshot);

// The snapshot's fields as the shell-anomaly rule sees them (a field with `derivedFrom` is derived).
std::vector<dataset::BaseVariable> baseVariables(const grid::Snapshot& snapshot);

// Appends every variable a dataset of this one snapshot has, in the dataset's order: the stored
// derived ones (addStoredDerivedVariables), then the shell anomalies (dataset/shell_anomaly.h:
// "thermal expansivity anomaly", "temperature anomaly" from ASPECT's T, every "X anomaly" and the
// "X anomaly %" whose shell means are all positive here), computed as the dataset computes them when
// read. For tests and tools that work on snapshots in memory.
void addDerivedVariables(grid::Snapshot& snapshot);

// The next coarser level: each coarse point is the volume-weighted mean of the (up to) 2x2x2
// fine points it merges (grid.coarsened() gives its coordinates).
std::vector<float> coarsenField(const grid::SphericalGrid& fine, std::span<const float> values);

// Exact range, volume-weighted mean and kHistogramBins-bin volume-fraction histogram of the values
// there are: NaN (missing) is left out (an infinity is a broken invariant: checked, aborts). Throws
// raypc::Error when every value is missing.
dataset::VariableStats computeStats(const grid::SphericalGrid& grid, std::span<const float> values);

// One variable over all steps: min and max over the steps, the mean of the step means, and the
// steps' histograms rebinned onto the global range and averaged. `perStep` must not be empty.
dataset::VariableStats statsOverSteps(std::span<const dataset::VariableStats> perStep);

// `rows` grid-point indices drawn independently with probability proportional to each
// point's dual-cell volume (deterministic for `seed`), sorted ascending.
std::vector<uint32_t> drawVolumeWeightedSample(const grid::SphericalGrid& grid, size_t rows, uint64_t seed);

// The sample's coordinate columns (coordinateInfos() order) of every sampled point, row-major.
std::vector<float> sampleCoordinates(const grid::SphericalGrid& grid, std::span<const uint32_t> cells);

// Adds `stats.histogram` (over stats.range) into `histogram` over `range`, spreading each bin's
// mass over the bins it overlaps.
void rebinHistogram(const dataset::VariableStats& stats, dataset::ValueRange range, std::span<double> histogram);

}  // namespace raypc::preprocess
