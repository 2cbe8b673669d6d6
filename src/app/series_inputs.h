// What `raypc serve` and `raypc render` are given: a dataset directory (`raypc preprocess`), or the
// netCDF snapshots themselves, preprocessed into a dataset directory that later runs reuse
// (docs/format.md, "Serving netCDF files").
#pragma once

#include "app/options.h"
#include "preprocess/preprocess.h"

#include <filesystem>
#include <string>
#include <utility>
#include <vector>

namespace raypc::app {

struct SeriesInputs {
    std::filesystem::path dataset;             // given, or where the files are preprocessed to
    std::vector<std::filesystem::path> files;  // in step order; empty when a dataset was given
    std::vector<double> timesMyr;              // the files' own times (a .pvd's), else empty

    bool fromFiles() const { return !files.empty(); }
    // The one-step dataset of the first file, shown while the series is preprocessed.
    std::filesystem::path previewDir() const { return dataset / "preview"; }
};

// `args`: one dataset directory (it holds dataset.json), or the inputs of listSeries (netCDF files
// and directories of *.nc, an ASPECT .pvd collection or its directory, .pvtu / .vtu steps).
// `datasetOption` (--dataset): where a dataset made from files goes; empty: beside the first file
// (beside a .pvd collection), named after the files' common name and ".raypc" (spherical001.nc …
// spherical251.nc -> spherical.raypc). Throws raypc::Error naming an argument that is none of these,
// raypc::NotFoundError (core/error_kinds.h) for one that does not exist.
SeriesInputs resolveSeriesInputs(const std::vector<std::string>& args, const std::string& datasetOption,
                                 const io::ReaderOptions& reader);

// True when `path` is a dataset directory (it holds dataset.json).
bool isDatasetDirectory(const std::filesystem::path& path);

// True when `dir` holds a complete dataset of exactly `files` (by name, in order).
bool datasetOfFiles(const std::filesystem::path& dir, const std::vector<std::filesystem::path>& files);

// The first file alone, without pathlines, as a dataset in inputs.previewDir(): a preview of those
// files made earlier is reused (anything else there is replaced); step 0 of the series in
// inputs.dataset, where it is written with the same settings, is taken by hard links (a preview then
// costs a manifest); else the file is preprocessed. Returns the seconds it took.
// Throws raypc::Error like prepareSeries.
double preparePreview(const SeriesInputs& inputs, preprocess::PreprocessOptions options);

// Preprocesses what is missing of the series into inputs.dataset (progress as `options` say), then
// removes the preview, unless `keepPreview`: a caller that still serves it removes it
// (removePreview) once it no longer does. Throws raypc::Error like preprocess(), and naming the directory and --dataset
// when it cannot be written. A run that fails before finishing a step leaves nothing: besides what
// preprocess() removes itself, the dataset directory (and its parents) go if this run created them
// (preparePreview too).
void prepareSeries(const SeriesInputs& inputs, const preprocess::PreprocessOptions& options, bool keepPreview = false);
// Removes inputs.previewDir(), if any. Never throws.
void removePreview(const SeriesInputs& inputs);

// What serve and render take on the command line: INPUT… (a dataset or netCDF files), --dataset and
// the preprocessing options of `raypc preprocess` (an option group).
struct SeriesFlags {
    std::vector<std::string> inputs;  // the inputs of one series, or of `raypc serve A B` two datasets (pair())
    std::string dataset;
    PreprocessFlags preprocess;

    // `inputsHelp`: what the command does with netCDF files.
    void add(CLI::App& cmd, const std::string& inputsHelp);
    // The inputs and the preprocessing options; under mpirun agreed over the ranks (one message for
    // a bad input, not one per rank). Throws raypc::Error as resolveSeriesInputs and PreprocessFlags.
    std::pair<SeriesInputs, preprocess::PreprocessOptions> resolve() const;
    // `raypc serve A B` (docs/compare.md, "Side by side"): the two dataset directories when the inputs
    // are exactly two of them (never one series: a series is netCDF or VTK inputs); else empty.
    // Throws raypc::Error when --dataset is given with them.
    std::vector<std::filesystem::path> pair() const;

private:
    CLI::App* m_group = nullptr;
};

}  // namespace raypc::app
