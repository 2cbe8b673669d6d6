// Preprocessing: snapshots -> a render-ready dataset (docs/format.md).
//
// Per step: derived variables, two coarser levels of detail by volume-weighted averaging,
// per-brick bounds at every level, volume-weighted statistics and histograms, and the values
// of the parallel-coordinates sample. Over all steps: global ranges and histograms, so that
// a transfer function does not jump during an animation.
#pragma once

#include "analysis/critical_points.h"
#include "grid/variable_names.h"
#include "dataset/dataset.h"
#include "io/netcdf_reader.h"
#include "analysis/pathlines.h"
#include "preprocess/preprocess_numerics.h"

#include <atomic>
#include <cstdint>
#include <filesystem>
#include <functional>
#include <span>
#include <string>
#include <vector>

namespace raypc::preprocess {

// The pathlines (docs/format.md, "Pathlines"): the significant critical points of `field` at each
// step seed pathlines traced through the next `steps` steps, while the steps are written.
struct PathlineOptions {
    bool enabled = true;
    // Why a run traces none (the manifest's `no_pathlines`), set where they are left out: the model
    // has no velocity, its flow or seed field has missing values; empty: they were not asked for.
    std::string absentBecause;
    std::string field = varname::kTemperatureAnomaly;
    int steps = 10;  // traced from step s to min(s + steps, last step)
    analysis::CriticalPointFilter filter;
    analysis::TracerOptions tracer;
};

// Where a run is: `phase` "steps" (done of total steps, counting those an earlier run finished)
// or "pathlines" (done of total pathline sets).
struct PreprocessProgress {
    std::string phase;
    int done = 0, total = 0;
};

// The largest parallel-coordinates sample: 10⁸ rows of 8 variables are 3.2 GB in memory.
inline constexpr size_t kMaxSampleRows = 100'000'000;

struct PreprocessOptions {
    io::ReaderOptions reader;
    double dtMyr = 2.0;          // time between consecutive input files
    // Each input's time (Myr) when the inputs give it (SeriesListing::timesMyr); dt_myr is then their
    // mean interval. Empty: step s is at s dtMyr.
    std::vector<double> timesMyr;
    size_t sampleRows = 100000;  // parallel-coordinates sample size (cells, with replacement)
    uint64_t seed = 1;           // for the sample
    uint32_t brickSize = 8;
    // Level arrays as u16 quantised per brick (half the size; docs/format.md) or exact float32.
    dataset::ValueEncoding encoding = dataset::ValueEncoding::Uint16;
    bool quiet = false;          // no progress output
    PathlineOptions pathlines;
    // One process reads step k + 1 (on a thread of its own) while it traces step k's pathlines
    // (without pathlines: while it writes step k), holding one step more in memory; false: one step
    // at a time, as each rank does under mpirun. The dataset's bytes are the same either way.
    bool readAhead = true;
    // For a run in the background (`raypc serve FILES`, app/series_inputs.h), one process only:
    // `onProgress` is called once the steps an earlier run finished are known (phase "steps", done:
    // those), then after each step or pathline set this run finishes; `cancel`, once set,
    // stops the run before its next step or pathline set with raypc::Error "cancelled" (what was
    // finished stays, as after any failure: a rerun resumes).
    std::function<void(const PreprocessProgress&)> onProgress;
    const std::atomic<bool>* cancel = nullptr;
    // A dataset whose finished steps this run takes (hard links, the donor keeps its own) instead of
    // making them again, where they were made with the same settings from the same unchanged input
    // files at the same times: the one-step preview `raypc serve FILES` shows while the series is
    // made (app/series_inputs.h). Empty: none. A step it cannot take is made as usual.
    std::filesystem::path stepsFrom;
    // For a run beside an interactive user (`raypc serve FILES`): once its reading thread is started,
    // the calling thread (which works on the steps with oneTBB's threads) lowers its priority by this
    // nice increment for good (Linux's per-thread priority, which an unprivileged thread cannot raise
    // again). The reading thread keeps the caller's priority: reading a step is one thread's work on
    // the run's critical path. 0: unchanged.
    int niceIncrement = 0;
};


struct PreprocessSummary {
    int stepsWritten = 0;
    int stepsSkipped = 0;  // already finished by an earlier run, or taken from PreprocessOptions::stepsFrom
    int stepsTaken = 0;    // of stepsSkipped: taken from PreprocessOptions::stepsFrom
    int pathlineSetsWritten = 0;
    int pathlineSetsSkipped = 0;  // finished by an earlier run with the same settings
    size_t pathlineCount = 0;     // lines in the sets written by this run
    // The most bytes of decoded values the pathline tracing held at once (a seed field and its base;
    // phases::PathlineStream::peakHeldBytes), this process.
    size_t pathlineWindowPeakBytes = 0;
    double seconds = 0;
};

// Where preprocess() reads its steps from: a series of input files (their readers, io/), or any
// other series of snapshots on one grid, such as the difference of two datasets
// (preprocess/difference.h). Everything after reading is the one pipeline.
class StepSource {
public:
    virtual ~StepSource() = default;
    virtual size_t stepCount() const = 0;
    // Step s for messages (an input's path) and in the manifest (its "inputs", a step's "source").
    virtual std::string path(size_t s) const = 0;
    virtual std::string label(size_t s) const = 0;
    // What every step shares, read and checked before anything is written: the grid and the stored
    // variables in order. Called once, before read(). Throws raypc::Error naming the step at fault.
    virtual io::FileHeader plan() = 0;
    // Step s on the plan's grid with the plan's variables in order (preprocess adds the derived ones).
    virtual grid::Snapshot read(size_t s) const = 0;
    // What step s is made from (the size and modification time of its files), so that a rerun makes
    // a step again whose sources changed since.
    virtual nlohmann::json fingerprint(size_t s) const = 0;
    // What the dataset is, for its manifest under `key` (a difference: "difference"); null for files.
    virtual std::string describeKey() const { return {}; }
    virtual nlohmann::json describe() const { return nullptr; }
    // The long_name of a derived variable (`name`: "radial velocity", …), where the source has one.
    virtual std::string derivedLongName(const std::string& /*name*/) const { return {}; }
};

// Preprocesses `inputs` (files, in step order) into `outDir`, in phases (preprocess.cpp):
// 1. plan: options and every input's header, the grid's size and the memory a step needs,
//    before anything is written; 2. the output directory: locked (DatasetWriteLock), checked
//    for resuming, the "incomplete" manifest written; 3. the sample's coordinates; 4. the steps
//    an earlier run finished; 5. each remaining step (preprocess_numerics.h), written under a
//    temporary name and renamed, and (one process) the pathlines traced in one pass as the steps
//    are written (preprocess_pathlines.cpp: from the written level-0 arrays of the newest three
//    steps); 6. statistics over all steps in the manifest; 7. the pathline sets still to do
//    (under mpirun: all), from the written steps; 8. the manifest says "complete".
// Resumable: finished steps of an earlier run into the same directory are kept. What a failed
// or killed run leaves is in docs/format.md. Throws raypc::Error naming the file and the
// problem on bad input, when another run holds `outDir`, and when `outDir` holds a dataset
// made from other inputs.
PreprocessSummary preprocess(const std::vector<std::filesystem::path>& inputs, const std::filesystem::path& outDir,
                             const PreprocessOptions& options);
// The same pipeline over any source of steps (options.reader is the file source's only).
PreprocessSummary preprocess(StepSource& source, const std::filesystem::path& outDir, const PreprocessOptions& options);

// Bytes of memory preprocessing one step of `grid` takes at its peak: `variableCount` (stored and
// derived) full-resolution float32 arrays and the reader's buffer for one variable.
uint64_t preprocessMemoryBytes(const grid::SphericalGrid& grid, size_t variableCount);

}  // namespace raypc::preprocess
