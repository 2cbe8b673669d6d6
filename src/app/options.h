// Option parsing shared by several subcommands.
#pragma once

#include "dataset/dataset.h"
#include "io/netcdf_reader.h"
#include "preprocess/preprocess.h"
#include "analysis/selection.h"

#include <CLI/CLI.hpp>

#include <string>
#include <vector>

namespace raypc::app {

// Adds to every floating-point option of `app` and its subcommands a check that refuses NaN and
// infinities ("nan", "inf", "1e999"): no command works with a non-finite number (unchecked, `probe
// --lon nan` answered with null values and exit 0). Call once every option is added.
void requireFiniteNumbers(CLI::App& app);

// Options that tell the netCDF reader how the input names things.
struct ReaderFlags {
    std::vector<std::string> variableMap;  // NAME=FILE_NAME
    std::string latName, rName, lonName;
    std::string radiusUnits;  // km | m | nondimensional; empty: the file's units attribute
    std::vector<std::string> velocity;  // --velocity A,B,C: the velocity's three variables in the file
    std::string velocityFrame = "cartesian";
    bool fillMissing = false;
    std::string timeUnits = "years", grid;  // VTK XML series (ASPECT's output)
    // CitcomS output: ΔT (K; 0: temperatures as written), R (km) and κ (m²/s); 0: the run's own.
    double temperatureScaleK = 0, planetRadiusKm = 0, diffusivityM2s = 0;

    void add(CLI::App& app);
    // Throws raypc::Error for a malformed --map.
    io::ReaderOptions toOptions() const;
};

// The options of a preprocessing run (`raypc preprocess`, and `raypc serve`/`render` given netCDF
// files): the sample, the time step, the reader's names and the pathline seeds.
struct PreprocessFlags {
    preprocess::PreprocessOptions options;
    ReaderFlags reader;
    bool noPathlines = false;

    // `withQuiet`: also -q/--quiet (serve and render report their own progress).
    void add(CLI::App& cmd, bool withQuiet = true);
    // The options as given. Throws raypc::Error for a malformed --map, or an option of the seed rule
    // --cp-select does not use (it would be silently ignored); `cmd` is the command they were added to.
    preprocess::PreprocessOptions toOptions(const CLI::App& cmd) const;
};

// A step given as an index ("12") or a time ("24Myr"); throws raypc::Error naming `option` (the
// CLI's flag, or Python's argument) and the dataset's valid steps when it is malformed, and
// raypc::OutOfRangeError (core/error_kinds.h) when no step has that index or time.
int parseStep(const dataset::Dataset& dataset, const std::string& text, const std::string& option = "--time");

// Parses "NAME=MIN:MAX" (names may contain spaces; the last '=' splits) for --range.
// Throws raypc::Error naming the option for a malformed text or min > max.
analysis::NamedRange parseRangeOption(const std::string& text, const std::string& option = "--range");

// Applies --range options over the ranges of a state: a name given on the command line replaces
// that name's ranges, and a name given several times gets them all (OR, analysis/selection.h).
void applyRangeOptions(std::vector<analysis::NamedRange>& ranges, const std::vector<std::string>& options,
                       const std::string& option = "--range");

// Parses "A" or "A:B" (each a step index or a time like 24Myr) into the inclusive step range.
// "1024x768" -> width, height (1..16384 each); throws raypc::Error naming --size otherwise.
std::pair<int, int> parseSize(const std::string& text);

std::pair<int, int> parseStepRange(const dataset::Dataset& dataset, const std::string& text, const std::string& option = "--time");

// The options of a command over a selection in a dataset's steps (stats, features): DATASET,
// --state (whose brushes select), --range (replacing the state's ranges per name), -t/--time and --lod.
struct SeriesSelectionFlags {
    std::string dataset, statePath, time;
    std::vector<std::string> ranges;
    int level = 0;
    std::string levelFrom = "--lod";  // what set `level`, for messages (e.g. a state's features.level)

    void add(CLI::App& cmd);
};
struct SeriesSelection {
    std::shared_ptr<const dataset::Dataset> dataset;
    std::vector<analysis::RangeFilter> filters;
    int first = 0, last = 0;  // the steps, inclusive
};
// Opens the dataset and resolves the flags. Throws raypc::Error for a bad state, range, level or
// step range, naming the option.
SeriesSelection resolveSeriesSelection(const SeriesSelectionFlags& flags);

}  // namespace raypc::app
