// Preprocessing: snapshots -> a render-ready dataset (docs/format.md).
//
// Per step: derived variables, two coarser levels of detail by volume-weighted averaging,
// per-brick bounds at every level, volume-weighted statistics and histograms, and the values
// of the parallel-coordinates sample. Over all steps: global ranges and histograms, so that
// a transfer function does not jump during an animation.
#pragma once

#include "data/critical_points.h"
#include "data/dataset.h"
#include "data/netcdf_reader.h"
#include "data/pathlines.h"

#include <cstdint>
#include <filesystem>
#include <span>
#include <string>
#include <vector>

namespace raypc {

// The pathline phase (docs/format.md, "Pathlines"): after every step is written, the significant
// critical points of `field` at each step seed pathlines traced through the next `steps` steps.
struct PathlineOptions {
    bool enabled = true;
    std::string field = "temperature anomaly";
    int steps = 10;  // traced from step s to min(s + steps, last step)
    CriticalPointFilter filter;
    TracerOptions tracer;
};

struct PreprocessOptions {
    ReaderOptions reader;
    double dtMyr = 2.0;          // time between consecutive input files
    size_t sampleRows = 100000;  // parallel-coordinates sample size (cells, with replacement)
    uint64_t seed = 1;           // for the sample
    uint32_t brickSize = 8;
    bool quiet = false;          // no progress output
    PathlineOptions pathlines;
};

struct PreprocessSummary {
    int stepsWritten = 0;
    int stepsSkipped = 0;  // already finished by an earlier run
    int pathlineSetsWritten = 0;
    int pathlineSetsSkipped = 0;  // finished by an earlier run with the same settings
    size_t pathlineCount = 0;     // lines in the sets written by this run
    double seconds = 0;
};

// Preprocesses `inputs` (files, in step order) into `outDir`. Resumable: finished steps of an
// earlier run into the same directory are kept; a killed run leaves no corrupt step (each step
// is written under a temporary name and renamed) and the manifest says "incomplete" until the
// last step and then every step's pathlines (a second phase: they need the velocities of later
// steps, read back from the written level-0 arrays) are done. Throws raypc::Error naming the file and the problem on bad input, and when
// `outDir` holds a dataset made from other inputs.
PreprocessSummary preprocess(const std::vector<std::filesystem::path>& inputs, const std::filesystem::path& outDir,
                             const PreprocessOptions& options);

// --- Building blocks, public for tests -----------------------------------------------------

// Bytes of memory preprocessing one step of `grid` takes at its peak: `variableCount` (stored and
// derived) full-resolution float32 arrays and the reader's buffer for one variable.
uint64_t preprocessMemoryBytes(const SphericalGrid& grid, size_t variableCount);

// `value` as float32; ±infinity beyond float32's range (where a plain conversion is undefined).
float toFloat32(double value);

// Appends "radial velocity" and "velocity magnitude" (cm/yr) computed from vx, vy, vz (m/s),
// and, when "thermal expansivity" is present, "thermal expansivity anomaly" (see lateralAnomaly).
// Values too large for float32 become infinite (see checkFinite). Throws raypc::Error if a
// velocity component is missing.
void addDerivedVariables(Snapshot& snapshot);

// `field` minus its area-weighted mean over each radius shell (the lateral mean), named `name`.
Field lateralAnomaly(const SphericalGrid& grid, const Field& field, const std::string& name);

// The next coarser level: each coarse point is the volume-weighted mean of the (up to) 2x2x2
// fine points it merges (grid.coarsened() gives its coordinates).
std::vector<float> coarsenField(const SphericalGrid& fine, std::span<const float> values);

// Exact range, volume-weighted mean and kHistogramBins-bin volume-fraction histogram of finite
// values (a non-finite value is a broken invariant: checked, aborts).
VariableStats computeStats(const SphericalGrid& grid, std::span<const float> values);

// `rows` grid-point indices drawn independently with probability proportional to each
// point's dual-cell volume (deterministic for `seed`), sorted ascending.
std::vector<uint32_t> drawVolumeWeightedSample(const SphericalGrid& grid, size_t rows, uint64_t seed);

// Adds `stats.histogram` (over stats.range) into `histogram` over `range`, spreading each bin's
// mass over the bins it overlaps.
void rebinHistogram(const VariableStats& stats, ValueRange range, std::span<double> histogram);

}  // namespace raypc
