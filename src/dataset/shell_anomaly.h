// Shell anomalies: variables computed when read, never stored (docs/format.md, "Variables";
// src/grid/names.json, `shellAnomaly`). For a stored scalar X, "X anomaly" is X minus the
// area-weighted mean of X over its radius shell (each grid point weighted by its dual cell's lat x lon
// area factor, SphericalGrid::volumeFactors), in X's units; "X anomaly %" is 100 (X - mean) / mean.
// The one definition: preprocessing computes their statistics with it, StepVolume their values on
// every level, Dataset::loadSample their sample columns.
#pragma once

#include "grid/grid.h"

#include <cstddef>
#include <optional>
#include <span>
#include <string>
#include <string_view>
#include <vector>

namespace raypc::dataset {

enum class ShellAnomalyKind {
    Difference,  // X - mean, X's units
    Percent,     // 100 (X - mean) / mean, %
};

// A variable computed from variable `base` (its index in the dataset's variables) when read.
struct ShellAnomalyOf {
    size_t base = 0;
    ShellAnomalyKind kind = ShellAnomalyKind::Difference;
    bool operator==(const ShellAnomalyOf&) const = default;
};

// The manifest's names of the kinds ("anomaly", "anomaly %"); parseShellAnomalyKind returns nothing
// for another text.
std::string_view shellAnomalyKindName(ShellAnomalyKind kind);
std::optional<ShellAnomalyKind> parseShellAnomalyKind(std::string_view text);

// A variable the rule may give: its name, units and what it is computed from.
struct ShellAnomalyVariable {
    std::string name, units;
    ShellAnomalyOf of;
};

// A variable as the rule sees it: stored in the input, or derived (radial velocity, …).
struct BaseVariable {
    std::string name, units;
    bool derived = false;
};

// The shell anomalies of `variables` (a dataset's stored and stored-derived variables, in order),
// in the order the dataset lists them after its stored ones: first every "X anomaly" (in the order
// of X), then every "X anomaly %". Left out: the velocity's components, derived variables, names
// that hold "anomaly", and an "X anomaly" whose name exists already (its "%" stays). A model with a
// temperature (names.json: temperatureAnomaly's `from`, the first the model has) and no temperature
// anomaly gets "temperature anomaly" and "temperature anomaly %" instead of "T anomaly" and
// "T anomaly %". Whether a "%" is offered depends on the values (shellMeansPositive): callers drop
// those that are not.
std::vector<ShellAnomalyVariable> shellAnomalyVariables(std::span<const BaseVariable> variables);

// Per radius shell (grid.nR() of them) the area-weighted mean of the finite values of `values`
// (grid.cellCount(), canonical order); NaN for a shell without a finite value. Parallel over shells,
// each summed in one order: the same numbers whatever the number of threads.
std::vector<double> shellMeans(const grid::SphericalGrid& grid, std::span<const float> values);

// The mean shellMeans gives one shell, from that shell's values alone: row iLat (w.lon.size() values)
// at shell + iLat * rowStride, `w` the grid's volumeFactors. The same sums in the same order, so the
// same bits: a reader of a few shells (Python's lazy xarray arrays) computes the anomalies the whole
// step's StepVolume would.
double shellMean(const grid::SphericalGrid::VolumeFactors& w, const float* shell, size_t rowStride);

// shellMean of each of `count` shells (shells[k], rows rowStride apart) into means[k], the same bits;
// up to kShellsAtOnce of them summed side by side, so that their chains of dependent additions overlap.
inline constexpr size_t kShellsAtOnce = 4;
void shellMeansSideBySide(const grid::SphericalGrid::VolumeFactors& w, const float* const* shells, size_t count,
                          size_t rowStride, double* means);

// Whether every shell mean that exists (is not NaN) is positive: where "X anomaly %" is defined.
bool shellMeansPositive(std::span<const double> means);

// One value of a shell anomaly: x - mean, or 100 (x - mean) / mean, in float32 (±infinity beyond
// its range; NaN where x or the mean is NaN).
float shellAnomalyValue(float x, double mean, ShellAnomalyKind kind);

// Per brick of `layout` bounds (min, max) on every value of a shell anomaly at the points the brick
// covers (computeBrickBounds' rule), from its base's brick bounds `baseBounds` (as computeBrickBounds
// writes them) and the shells' `means`: shellAnomalyValue is monotone in x on each shell, so its
// values at the base's bounds bound it. Wider than the anomaly's own bounds, never narrower: a brick
// whose bounds meet no range has no point in it. (+inf, -inf) for a brick with no finite value.
void shellAnomalyBrickBounds(const grid::SphericalGrid& grid, const grid::BrickLayout& layout,
                             std::span<const float> baseBounds, std::span<const double> means, ShellAnomalyKind kind,
                             std::span<float> out);

// Every value of a shell anomaly of `values` with the shells' `means` into `out` (both
// grid.cellCount()). Parallel.
void computeShellAnomaly(const grid::SphericalGrid& grid, std::span<const float> values, std::span<const double> means,
                         ShellAnomalyKind kind, std::span<float> out);

}  // namespace raypc::dataset
