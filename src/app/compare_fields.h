// What `raypc correlate` and `raypc spectrum` (and Python's raypc.correlate, raypc.spectrum) compare:
// a field named "INPUT[:VARIABLE]" at one step, INPUT a dataset directory or what `raypc serve` takes
// (netCDF files, an ASPECT series: preprocessed once into a dataset beside them, app/series_inputs.h),
// and the second field put on the first one's grid (grid/regrid.h). docs/compare.md.
//
// Thread safety: plain functions.
#pragma once

#include "analysis/shell_compare.h"
#include "dataset/dataset.h"
#include "render/image_io.h"

#include <memory>
#include <string>
#include <vector>

namespace raypc::app {

// "INPUT[:VARIABLE]": the input, and the variable (empty: the dataset's default, varname::anomalyToShow).
// A text that names an existing path is the input alone; otherwise the last ':' splits it.
struct FieldSpec {
    std::string input, variable;
};
FieldSpec parseFieldSpec(const std::string& text);

struct ComparedField {
    std::shared_ptr<const dataset::Dataset> dataset;
    size_t variable = 0;
    int step = 0;
    std::shared_ptr<const dataset::StepVolume> volume;  // level 0 (full resolution)
    const dataset::VariableInfo& info() const { return dataset->variables()[variable]; }
    const float* values() const { return volume->values(variable); }
    // "run1.raypc: temperature anomaly [K], step 3 (6 Myr)"
    std::string title() const;
};

// Opens the field of `spec` at step `stepText` (an index or a time like 24Myr, parseStep); `what`
// names it in messages ("A", "B"), `stepOption` the option the step came from. Inputs that are files
// are preprocessed first (progress unless `quiet`). Throws raypc::Error naming the input, the
// variable (with the dataset's variables) or the step.
ComparedField openComparedField(const FieldSpec& spec, const std::string& stepText, const std::string& what,
                                const std::string& stepOption, bool quiet);

// B's values on A's grid: its own when the grids are the same, else through grid::regrid (NaN where B
// has no data). Throws raypc::Error when the grids do not overlap at all.
std::vector<float> valuesOnGridOf(const ComparedField& b, const ComparedField& a);

// A and B correlated shell by shell on A's grid (analysis/shell_compare.h).
std::vector<analysis::ShellCorrelation> correlateFields(const ComparedField& a, const ComparedField& b,
                                                        const analysis::CorrelationOptions& options);
// The power spectrum of a field per shell to degree `lmax` (< 0: analysis::defaultSpectrumDegree).
analysis::ShellSpectra fieldSpectra(const ComparedField& field, int lmax);
// The per-degree correlation of A and B on A's shell nearest `depthKm`.
analysis::DegreeCorrelation fieldDegreeCorrelation(const ComparedField& a, const ComparedField& b, double depthKm, int lmax);

// The pictures of `raypc correlate --png` (the correlation per depth, depth down, 410 and 660 km
// marked) and `raypc spectrum --png` (log10 of the power per degree 1..lmax and depth: degree 0, the
// shell's mean squared, is left out; six decades below the largest power are shown). Throws
// raypc::Error when the picture has no room for its plot.
render::ImageRgba8 correlationPicture(const std::vector<analysis::ShellCorrelation>& rows, const ComparedField& a,
                                      const ComparedField& b, const analysis::CorrelationOptions& options, int width,
                                      int height);
render::ImageRgba8 spectrumPicture(const analysis::ShellSpectra& spectra, const ComparedField& field, int width, int height);

}  // namespace raypc::app
