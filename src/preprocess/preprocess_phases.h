// Internal to src/preprocess: what the phases of preprocess() share (preprocess.cpp runs them;
// the pathlines, traced while the steps are written, live in preprocess_pathlines.cpp).
#pragma once

#include "preprocess/preprocess.h"
#include "analysis/pathlines.h"
#include "dataset/dataset.h"

#include <nlohmann/json.hpp>

#include <filesystem>
#include <functional>
#include <memory>
#include <set>
#include <optional>
#include <string>
#include <vector>

namespace raypc::preprocess::phases {

// A variable of the dataset: stored (as the reader returns it, or derived and stored), or computed
// when read (a shell anomaly: `computed`, after the stored ones).
struct VariableSpec {
    std::string name, units;
    bool derived;
    // What it comes from: a stored variable's name in the input, a derived one's inputs.
    std::string source;
    std::string longName;  // the input's long_name, where it has one
    std::optional<dataset::ShellAnomalyOf> computed = {};
};

// The size and modification time of each of `files` (a step's inputs.json, format::kStepInputs).
// Throws raypc::Error naming a file whose size or time cannot be read.
nlohmann::json filesFingerprint(const std::vector<std::filesystem::path>& files);

// Throws raypc::Error "preprocess: cancelled" once options.cancel is set (between steps and sets).
void throwIfCancelled(const PreprocessOptions& options);

// The pathline settings as the manifest and every set's lines.json store them.
nlohmann::json pathlineSettings(const PathlineOptions& options);

// Throws raypc::Error naming the option when the pathline options do not fit the variables.
void checkPathlineOptions(const PathlineOptions& options, const std::vector<VariableSpec>& specs);

// The injection steps whose pathline sets are still to do (rank 0 only: it removes what a killed
// run left under pathlines/): a set is done when its lines.json was made with the same settings,
// reaches the same end step and is of this version; `skipped` counts the done ones not in
// `madeThisRun`.
std::vector<int> pathlineSetsToDo(const std::filesystem::path& outDir, int stepCount, const PathlineOptions& options,
                                  const std::set<int>& madeThisRun, int& skipped);

// Pathline sets traced in one pass over the steps (docs/format.md, "Pathlines"; docs/scaling.md):
// fed the steps in order as they are written (or found written), it finds the seeds of a set at its
// injection step and advances every open line through the interval between the two steps before the
// newest one, each line resumed where the last interval left it (PathlineTracer::advance), so that
// the lines are those of one trace over steps s..end. A set is written atomically (pathlines/NNNN)
// when its lines reach its end step. The velocity is read from the written level-0 arrays of the
// newest three steps only, a u16 variable decoded at the points the lines sample (the values every
// reader sees, with no decoded array of the grid held), and the files' pages are dropped from the
// process's resident memory between steps: memory is flat in the number of steps (1.19 GB for 6 and
// for 24 full-resolution steps, docs/scaling.md) and the work linear in it.
// Not thread-safe; stepReady uses oneTBB over the lines.
class PathlineStream {
public:
    // `specs`: the dataset's variables, stored then computed (the sets' attribute columns); `sets`:
    // the injection steps to trace; `stepTimesMyr`: every step's time (a set ends at
    // min(s + options.pathlines.steps, last step)). Throws raypc::Error as checkPathlineOptions.
    PathlineStream(std::filesystem::path outDir, const grid::SphericalGrid& grid, std::vector<VariableSpec> specs,
                   std::vector<int> sets, std::vector<double> stepTimesMyr, const PreprocessOptions& options);
    ~PathlineStream();

    // The steps the sets read: stepReady ignores the others.
    int firstStep() const { return m_firstStep; }
    int lastStep() const { return m_lastStep; }
    // Step k is written; `stepJson`: its manifest (time, statistics of the stored variables). Steps
    // firstStep()..lastStep() come in increasing order, each once. A step whose flow or seed field has
    // missing values stops the stream (stopped(): no further set is written; the run leaves pathlines
    // out). Throws raypc::Error as the dataset's readers do (a file cut short) and when cancelled.
    void stepReady(int k, const nlohmann::json& stepJson);
    bool stopped() const { return m_stopped; }

    // The injection steps of the sets written so far, and their lines.
    const std::set<int>& written() const { return m_written; }
    size_t lineCount() const { return m_lineCount; }
    // The most bytes of decoded values (StepVolume::decodedBytes) the stream held at once: the seed
    // field of the newest step and the variable it is computed from (the velocity is not decoded).
    size_t peakHeldBytes() const { return m_peakHeldBytes; }
    // Called after each set is written (progress).
    std::function<void()> onSetWritten;

private:
    struct Step;
    struct OpenSet;
    analysis::FieldSeries window(int first, int last) const;
    void advance(const std::vector<OpenSet*>& sets, int toStep, const analysis::FieldSeries& series);
    void open(int s);
    void finish(OpenSet& set);
    void noteHeldBytes(size_t extra = 0);

    std::filesystem::path m_outDir;
    grid::SphericalGrid m_grid;
    std::vector<VariableSpec> m_specs;
    std::vector<std::string> m_names, m_units, m_stems;
    std::vector<dataset::VariableInfo> m_variables;  // names, and what a computed one is made from
    std::vector<dataset::ShellAnomalyOf> m_computed;
    size_t m_field = 0, m_v[3] = {0, 0, 0};
    std::set<int> m_todo;
    std::vector<double> m_timesMyr;
    int m_stepCount, m_firstStep = 0, m_lastStep = -1, m_next = 0;
    const PreprocessOptions& m_options;
    nlohmann::json m_settings;
    std::vector<std::unique_ptr<Step>> m_window;  // the newest steps, oldest first
    std::vector<std::unique_ptr<OpenSet>> m_open;
    std::set<int> m_written;
    size_t m_lineCount = 0, m_peakHeldBytes = 0;
    bool m_stopped = false;
};

// Rewrites the sets `sets` (written by a PathlineStream with more variables) with the attribute
// columns of `specs` only (a computed variable some step left undefined is not the dataset's).
// Throws raypc::Error as loadPathlineSet and writePathlineSet.
void keepPathlineColumns(const std::filesystem::path& outDir, const std::set<int>& sets,
                         const std::vector<VariableSpec>& specs);

// The pathline phase after the steps: the sets still to do (those the one pass did not write: a
// distributed run, a run that resumed, a run whose computed variables changed), each rank tracing a
// contiguous block of them with a PathlineStream fed from the written steps. `madeThisRun`: the sets
// the one pass wrote (counted by the caller). `specs` are the dataset's variables, stored then
// computed; `stepJsons` are the steps' manifests.
void writePathlines(const std::filesystem::path& outDir, const grid::SphericalGrid& grid,
                    const std::vector<VariableSpec>& specs, const std::vector<nlohmann::json>& stepJsons,
                    const PreprocessOptions& options, const std::set<int>& madeThisRun, PreprocessSummary& summary);

}  // namespace raypc::preprocess::phases
