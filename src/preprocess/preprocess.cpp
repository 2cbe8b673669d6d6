#include "preprocess/preprocess.h"
#include "grid/variable_names.h"

#include "core/atomic_file.h"
#include "core/clock.h"
#include "core/error.h"
#include "core/json_input.h"
#include "core/mpi.h"
#include "core/progress.h"
#include "core/strings.h"
#include "core/system_memory.h"
#include "dataset/bricks.h"
#include "dataset/dataset_format.h"
#include "analysis/pathline_storage.h"
#include "preprocess/preprocess_phases.h"
#include "io/series_input.h"

#include <fmt/ranges.h>
#include <spdlog/spdlog.h>
#include <tbb/parallel_for.h>
#include <tbb/parallel_for_each.h>

#include <algorithm>
#include <cerrno>
#include <chrono>
#include <condition_variable>
#include <cstdio>
#include <exception>
#include <fstream>
#include <functional>
#include <future>
#include <map>
#include <memory>
#include <mutex>
#include <set>
#include <optional>
#include <thread>
#include <utility>

#include <sys/resource.h>
#include <unistd.h>

namespace raypc::preprocess {
namespace {

namespace fs = std::filesystem;
using nlohmann::json;
using phases::VariableSpec;

// Runs an action when the scope is left by an exception, unless dismissed first.
class ScopeCleanup {
public:
    explicit ScopeCleanup(std::function<void()> action) : m_action(std::move(action)) {}
    ~ScopeCleanup()
    {
        if (m_action && std::uncaught_exceptions() > m_exceptions)
            m_action();
    }
    ScopeCleanup(const ScopeCleanup&) = delete;
    ScopeCleanup& operator=(const ScopeCleanup&) = delete;
    void dismiss() { m_action = nullptr; }

private:
    std::function<void()> m_action;
    int m_exceptions = std::uncaught_exceptions();
};

template <typename T>
void writeArray(const fs::path& path, std::span<const T> values)
{
    std::FILE* f = std::fopen(path.c_str(), "wb");
    if (!f)
        fail("{}: cannot create", path.string());
    const size_t written = std::fwrite(values.data(), sizeof(T), values.size(), f);
    const bool ok = written == values.size() && std::fclose(f) == 0;
    if (!ok)
        fail("{}: write failed (disk full?)", path.string());
}

// The stored variables of the dataset, in order: the input's as the reader returns them, then the
// derived ones. Units of derived variables are fixed by addStoredDerivedVariables.
std::vector<VariableSpec> variableSpecs(const io::FileHeader& header, const StepSource& source)
{
    std::vector<VariableSpec> specs;
    for (const auto& v : header.variables)
        specs.push_back({v.name, v.units, false, v.fileName, v.longName});
    const auto has = [&](const std::string& name) {
        return std::any_of(header.variables.begin(), header.variables.end(), [&](const auto& v) { return v.name == name; });
    };
    if (varname::hasVelocity(has)) {
        specs.push_back({varname::kRadialVelocity, varname::kRadialVelocityUnits, true,
                         fmt::format("{}", fmt::join(varname::kRadialVelocityFrom, ", ")),
                         source.derivedLongName(varname::kRadialVelocity)});
        specs.push_back({varname::kVelocityMagnitude, varname::kVelocityMagnitudeUnits, true,
                         fmt::format("{}", fmt::join(varname::kVelocityMagnitudeFrom, ", ")),
                         source.derivedLongName(varname::kVelocityMagnitude)});
    }
    return specs;
}

// The shell anomalies the stored variables may have (dataset/shell_anomaly.h), computed when read:
// every "X anomaly" is offered; an "X anomaly %" only where every step's shell means are positive,
// which the steps tell (offeredComputedSpecs).
std::vector<VariableSpec> computedSpecs(const std::vector<VariableSpec>& stored)
{
    std::vector<dataset::BaseVariable> bases;
    for (const VariableSpec& v : stored)
        bases.push_back({v.name, v.units, v.derived});
    std::vector<VariableSpec> specs;
    for (const dataset::ShellAnomalyVariable& v : dataset::shellAnomalyVariables(bases))
        specs.push_back({v.name, v.units, true, stored[v.of.base].name, "", v.of});
    return specs;
}

// dt_myr of the manifest: --dt-myr, or the mean interval of the inputs' own times.
double stepIntervalMyr(const PreprocessOptions& options)
{
    const auto& t = options.timesMyr;
    return t.size() >= 2 ? (t.back() - t.front()) / double(t.size() - 1) : options.dtMyr;
}

// A variable's entry in the manifest (docs/format.md, dataset.json).
json variableJson(const VariableSpec& v)
{
    json j{{"name", v.name}, {"units", v.units}, {"derived", v.derived}, {"source", v.source}, {"stored", !v.computed}};
    if (v.computed)
        j["kind"] = dataset::shellAnomalyKindName(v.computed->kind);
    else
        j["file_stem"] = fileSafeName(v.name);
    if (!v.longName.empty())
        j["long_name"] = v.longName;
    return j;
}

json manifest(const std::vector<grid::SphericalGrid>& levels, const std::vector<VariableSpec>& specs,
              const StepSource& source, const PreprocessOptions& options, size_t sampleRows)
{
    json j;
    j["format"] = dataset::format::kFormatName;
    j["version"] = dataset::format::kVersion;
    j["encoding"] = dataset::encodingName(options.encoding);
    j["status"] = "incomplete";
    j["dt_myr"] = stepIntervalMyr(options);
    j["brick_size"] = options.brickSize;
    j["levels"] = json::array();
    for (const auto& g : levels)
        j["levels"].push_back(dataset::format::toJson(g));
    j["variables"] = json::array();
    for (const auto& v : specs)
        j["variables"].push_back(variableJson(v));
    j["inputs"] = json::array();
    for (size_t s = 0; s < source.stepCount(); ++s)
        j["inputs"].push_back(source.label(s));
    j["sample"] = {{"rows", sampleRows}, {"seed", options.seed}};
    if (const std::string key = source.describeKey(); !key.empty())
        j[key] = source.describe();
    return j;
}

// The time of step s (Myr): the inputs' own (a .pvd's), else s dt_myr.
double stepTimeMyr(const PreprocessOptions& options, int s)
{
    return options.timesMyr.empty() ? s * options.dtMyr : options.timesMyr[size_t(s)];
}

void checkSameGrid(const std::string& input, const grid::SphericalGrid& grid, const grid::SphericalGrid& first,
                   const std::string& firstLabel)
{
    if (!grid.sameAs(first))
        fail("{}: grid {}x{}x{} (lat x r x lon) or its coordinates differ from the first step's {}x{}x{} in {}",
             input, grid.nLat(), grid.nR(), grid.nLon(), first.nLat(), first.nR(), first.nLon(), firstLabel);
}

// The size and modification time of each file step `input` is read from (format::kStepInputs).
json inputFingerprint(const fs::path& input)
{
    return phases::filesFingerprint(io::stepSourceFiles(input));
}

// The series of input files: each step read by its format's reader (io/series_input.h).
class FileSeries final : public StepSource {
public:
    FileSeries(const std::vector<fs::path>& inputs, const io::ReaderOptions& reader) : m_inputs(inputs), m_reader(reader) {}

    size_t stepCount() const override { return m_inputs.size(); }
    std::string path(size_t s) const override { return m_inputs[s].string(); }
    std::string label(size_t s) const override { return m_inputs[s].filename().string(); }
    json fingerprint(size_t s) const override { return inputFingerprint(m_inputs[s]); }
    grid::Snapshot read(size_t s) const override { return io::readStep(m_inputs[s], m_reader); }

    io::FileHeader plan() override
    {
        // The first file fixes the grid and the variables; every other step must match them. A
        // resampled series takes the grid chosen for its first step.
        io::FileHeader header = io::readStepHeader(m_inputs.front(), m_reader);
        if (io::isMeshStep(m_inputs.front())) {
            m_reader.targetGrid = header.grid;
        } else if (m_reader.variables.empty()) {
            // The variables the first file holds are every step's: a step that lacks one is named.
            for (const auto& v : header.variables)
                m_reader.variables.push_back(v.name);
        }
        for (size_t s = 1; s < m_inputs.size(); ++s) {
            const io::FileHeader h = io::readStepHeader(m_inputs[s], m_reader);
            checkSameGrid(path(s), h.grid, header.grid, label(0));
            std::vector<std::string> names, firstNames;
            for (const auto& v : h.variables)
                names.push_back(v.name);
            for (const auto& v : header.variables)
                firstNames.push_back(v.name);
            if (names != firstNames)
                fail("{}: variables {}, the first step's {} has {}", path(s), fmt::join(names, ", "), label(0),
                     fmt::join(firstNames, ", "));
        }
        return header;
    }

private:
    std::vector<fs::path> m_inputs;
    io::ReaderOptions m_reader;  // as given, with a resampled series's grid fixed by plan()
};

// What a run will write, known from the options and the inputs' headers alone.
struct RunPlan {
    io::FileHeader header;                   // of the first input: the grid and the variables
    std::vector<grid::SphericalGrid> levels;   // level 0 first
    std::vector<VariableSpec> specs;     // stored, then derived
    std::vector<VariableSpec> computed;  // the shell anomalies each step's statistics are made for
    json manifest;                       // "incomplete", without steps and computed variables
};

// Phase 1: the options, every input's header, the grid's size and memory. Nothing is written
// yet, so a bad file, a missing variable or a different grid stops the run before it starts.
RunPlan planRun(StepSource& source, PreprocessOptions& options)
{
    if (source.stepCount() == 0)
        fail("preprocess: no input files");
    if (!(options.dtMyr > 0))
        fail("--dt-myr: {} is not a positive time step", options.dtMyr);
    if (options.sampleRows == 0 || options.sampleRows > kMaxSampleRows)
        fail("--sample-rows: {}, expected 1 to {} rows", options.sampleRows, kMaxSampleRows);
    if (!options.timesMyr.empty()) {
        RAYPC_CHECK_EQ(options.timesMyr.size(), source.stepCount());
        for (size_t s = 0; s < source.stepCount(); ++s)
            if (!std::isfinite(options.timesMyr[s]) || (s > 0 && !(options.timesMyr[s] > options.timesMyr[s - 1])))
                fail("{}: time {} Myr, expected a finite time after the step before's", source.path(s),
                     options.timesMyr[s]);
    }
    RunPlan plan;
    plan.header = source.plan();
    plan.levels = {plan.header.grid};
    for (int l = 1; l < dataset::kLevelCount; ++l)
        plan.levels.push_back(plan.levels.back().coarsened());
    plan.specs = variableSpecs(plan.header, source);
    plan.computed = computedSpecs(plan.specs);
    // The variables pathlines may be seeded on: the stored ones and the anomalies (every "X anomaly"
    // is offered; a percentage only where the steps allow).
    std::vector<VariableSpec> seedable = plan.specs;
    for (const VariableSpec& v : plan.computed)
        if (v.computed->kind == dataset::ShellAnomalyKind::Difference)
            seedable.push_back(v);
    const auto hasSpec = [&](const std::string& name) {
        return std::any_of(seedable.begin(), seedable.end(), [&](const VariableSpec& v) { return v.name == name; });
    };
    // Pathlines follow the flow: a model without a velocity (a tomography model) has none. Their
    // seeds default to the temperature anomaly's critical points, else the first variable's anomaly
    // (the first the rule gives), else the first stored variable's.
    if (options.pathlines.enabled && !varname::hasVelocity(hasSpec)) {
        options.pathlines.enabled = false;
        options.pathlines.absentBecause = "the model has no velocity (vx, vy, vz)";
        if (!options.quiet && mpi::isRoot())
            spdlog::info("{}: no velocity (vx, vy, vz): no pathlines", source.path(0));
    }
    if (options.pathlines.enabled && options.pathlines.field == PathlineOptions{}.field && !hasSpec(options.pathlines.field)) {
        std::vector<std::string> names;
        for (const VariableSpec& v : plan.specs)
            names.push_back(v.name);
        for (const VariableSpec& v : plan.computed)
            names.push_back(v.name);
        if (const std::string field = varname::anomalyToShow(names); !field.empty())
            options.pathlines.field = field;
    }
    phases::checkPathlineOptions(options.pathlines, seedable);
    // The stored variables, and one array for the computed ones' statistics. (The pathlines decode
    // no velocity, and between steps only a seed field with the variable it is computed from:
    // phases::PathlineStream.)
    const uint64_t bytes = preprocessMemoryBytes(plan.header.grid, plan.specs.size() + (plan.computed.empty() ? 0 : 1));
    grid::checkGridFitsMemory(plan.header.grid, bytes, source.path(0), "preprocess", availableMemory());
    plan.manifest = manifest(plan.levels, plan.specs, source, options, options.sampleRows);
    return plan;
}

// The first setting that shapes a step's bytes (of those in a manifest) which `old` (a manifest read
// from disk, maybe finished) holds differently from `now` (this run's); empty when none does. A
// finished manifest adds global statistics and the computed variables: not settings.
std::string differingStepSetting(json old, const json& now)
{
    if (old.contains("variables") && old["variables"].is_array()) {
        json stored = json::array();
        for (auto& v : old["variables"])
            if (v.is_object() && v.value("stored", true)) {
                v.erase("global");
                stored.push_back(v);
            }
        old["variables"] = stored;
    }
    for (const char* key : {"difference", "format", "version", "encoding", "levels", "variables", "brick_size", "sample"})
        if (old.value(key, json()) != now.value(key, json()))
            return key;
    return {};
}

// Phase 2: the output directory, locked for this run, checked for resuming, cleared of a killed
// run's leftovers, with the "incomplete" manifest written. Until keep() a fresh run that fails
// leaves nothing: what it created goes (docs/format.md, "What a failed run leaves").
class OutputDirectory {
public:
    OutputDirectory(const fs::path& dir, const json& manifest)
        : m_dir(dir), m_existed(fs::exists(dir)), m_lock(dir), m_fresh(!fs::exists(manifestPath()))
    {
        for (const fs::path name : {dataset::format::kSampleCoords, dataset::format::kSampleCells, "steps", "pathlines"})
            if (!fs::exists(m_dir / name))
                m_created.push_back(m_dir / name);
        if (!m_fresh) {
            keep();
            checkResumable(manifest);
        }
        fs::create_directories(m_dir / "steps");
        removeLeftovers();
        writeManifest(manifest);
    }

    const fs::path& path() const { return m_dir; }
    fs::path manifestPath() const { return m_dir / dataset::format::kManifest; }
    void writeManifest(const json& j) const { writeFileAtomic(manifestPath(), j.dump(1)); }
    // A step is finished: from now on a failure leaves the finished steps for a rerun.
    void keep() { m_leaveNothing.dismiss(); }

private:
    // Resuming is only safe into a dataset made from the same inputs with the same settings.
    void checkResumable(const json& j) const
    {
        json old;
        try {
            old = parseJsonInput(readFile(manifestPath()), manifestPath().string());
        } catch (const Error& e) {
            fail("{} (it exists already); remove the directory to start over", e.what());
        }
        std::string key = differingStepSetting(old, j);
        if (key.empty() && old.value("dt_myr", json()) != j.value("dt_myr", json()))
            key = "dt_myr";  // the steps' times: a resumed run's and the finished steps' must agree
        if (!key.empty())
            fail("{}: holds a dataset made with a different '{}' (other inputs or options); "
                 "use another output directory or remove it",
                 m_dir.string(), key);
        const auto oldInputs = old.value("inputs", json::array());
        for (size_t i = 0; i < std::min(oldInputs.size(), j["inputs"].size()); ++i)
            if (oldInputs[i] != j["inputs"][i] && fs::exists(dataset::format::stepDir(m_dir, static_cast<int>(i))))
                fail("{}: step {} was made from {}, now the input is {}; use another output directory",
                     m_dir.string(), i, oldInputs[i].get<std::string>(), j["inputs"][i].get<std::string>());
    }

    // Leftovers of a killed run: temporary step directories are never valid.
    void removeLeftovers() const
    {
        for (const auto& entry : fs::directory_iterator(m_dir / "steps"))
            if (entry.path().filename().string().starts_with("."))
                fs::remove_all(entry.path());
        for (const auto& entry : fs::directory_iterator(m_dir))
            if (entry.path().filename().string().starts_with(".") &&
                entry.path().filename().string().find(".tmp-") != std::string::npos)
                fs::remove_all(entry.path());
    }

    void removeCreated()
    {
        std::error_code ec;
        m_lock.removeFile();
        if (!m_existed) {
            fs::remove_all(m_dir, ec);
            return;
        }
        fs::remove(manifestPath(), ec);
        for (const auto& path : m_created)
            fs::remove_all(path, ec);
    }

    fs::path m_dir;
    bool m_existed;
    dataset::DatasetWriteLock m_lock;  // before m_leaveNothing: held while that removes
    bool m_fresh;
    std::vector<fs::path> m_created;
    ScopeCleanup m_leaveNothing{[this] { removeCreated(); }};
};

// Phase 3: the sample's grid points, the same for every step so that lines are comparable over
// time; their coordinates are written once.
// Every rank draws the same cells (the draw is seeded); rank 0 writes them.
std::vector<uint32_t> writeSampleCoordinates(const fs::path& dir, const grid::SphericalGrid& grid,
                                             const PreprocessOptions& options)
{
    auto cells = drawVolumeWeightedSample(grid, options.sampleRows, options.seed);
    if (mpi::isRoot() && !fs::exists(dir / dataset::format::kSampleCoords)) {
        const auto coords = sampleCoordinates(grid, cells);
        writeFileAtomic(dir / dataset::format::kSampleCoords, std::as_bytes(std::span(coords)));
    }
    // The grid points themselves, for the computed variables' sample columns (Dataset::loadSample).
    if (mpi::isRoot() && !fs::exists(dir / dataset::format::kSampleCells))
        writeFileAtomic(dir / dataset::format::kSampleCells, std::as_bytes(std::span(cells)));
    return cells;
}

}  // namespace

json phases::filesFingerprint(const std::vector<fs::path>& sourceFiles)
{
    json files = json::array();
    for (const fs::path& file : sourceFiles) {
        std::error_code ec;
        const auto size = fs::file_size(file, ec);
        const auto mtime = fs::last_write_time(file, ec);
        if (ec)
            fail("{}: cannot read its size and time: {}", file.string(), ec.message());
        files.push_back({{"file", file.filename().string()},
                         {"bytes", size},
                         {"modified_ns", int64_t(std::chrono::duration_cast<std::chrono::nanoseconds>(
                                                     mtime.time_since_epoch())
                                                     .count())}});
    }
    return files;
}

namespace {

// The finished steps of another dataset (PreprocessOptions::stepsFrom) that this run may take
// instead of making them again: those made with the same step settings (differingStepSetting) from
// the same input files, unchanged since (their inputs.json), at the same time and with the same
// source. give() hard-links the step's files into a temporary directory and renames it into place,
// so that the donor keeps its own (a server may be reading them); it leaves nothing when it cannot
// (the donor has no such step, or is on another file system) and the run makes the step.
class StepDonor {
public:
    StepDonor(const fs::path& dir, const json& manifest) : m_dir(dir)
    {
        if (dir.empty())
            return;
        try {
            const json theirs = parseJsonInput(readFile(dir / dataset::format::kManifest), dir.string());
            const std::string key = differingStepSetting(theirs, manifest);
            if (!key.empty()) {
                spdlog::debug("{}: its steps were made with another '{}'; making them again", dir.string(), key);
                return;
            }
            m_usable = true;
        } catch (const Error& e) {
            spdlog::debug("{}: not taking its steps: {}", dir.string(), e.what());
        }
    }

    bool give(const fs::path& outDir, const StepSource& source, const PreprocessOptions& options, int s) const
    {
        if (!m_usable)
            return false;
        const fs::path from = dataset::format::stepDir(m_dir, s);
        const fs::path to = dataset::format::stepDir(outDir, s);
        const fs::path tmp = temporarySibling(to);
        try {
            const json inputs = parseJsonInput(readFile(from / dataset::format::kStepInputs), from.string());
            const json step = parseJsonInput(readFile(from / dataset::format::kStepManifest), from.string());
            if (inputs != source.fingerprint(size_t(s)) || step.value("source", json()) != source.label(size_t(s)) ||
                step.value("time_myr", json()) != json(stepTimeMyr(options, s)))
                return false;
            fs::create_directories(tmp);
            for (const auto& entry : fs::recursive_directory_iterator(from)) {
                const fs::path target = tmp / fs::relative(entry.path(), from);
                if (entry.is_directory())
                    fs::create_directory(target);
                else if (entry.is_regular_file())
                    fs::create_hard_link(entry.path(), target);
                else
                    fail("{}: neither a file nor a directory", entry.path().string());
            }
            renameAtomic(tmp, to);
        } catch (const std::exception& e) {  // raypc::Error or fs::filesystem_error: the run makes the step
            std::error_code ec;
            fs::remove_all(tmp, ec);
            spdlog::debug("{}: making step {} again rather than taking it from {}: {}", outDir.string(), s,
                          m_dir.string(), e.what());
            return false;
        }
        spdlog::debug("{}: step {} taken from {}", outDir.string(), s, m_dir.string());
        return true;
    }

private:
    fs::path m_dir;
    bool m_usable = false;
};

// Phase 4: the steps an earlier run finished (their step.json, kept), those taken from
// options.stepsFrom (StepDonor), and the ones to do (a step directory without step.json is removed,
// and so is a finished step whose input files changed since that run: their size or modification
// time differs from its inputs.json).
std::vector<int> findStepsToDo(const OutputDirectory& out, const StepSource& source, const RunPlan& plan,
                               const PreprocessOptions& options, std::vector<json>& stepJsons,
                               PreprocessSummary& summary)
{
    std::vector<int> todo;
    const StepDonor donor(options.stepsFrom, plan.manifest);
    for (size_t s = 0; s < source.stepCount(); ++s) {
        const fs::path stepPath = dataset::format::stepDir(out.path(), static_cast<int>(s));
        const fs::path fingerprint = stepPath / dataset::format::kStepInputs;
        if (fs::exists(stepPath / dataset::format::kStepManifest) && fs::exists(fingerprint) &&
            parseJsonInput(readFile(fingerprint), fingerprint.string()) != source.fingerprint(s)) {
            spdlog::warn("{}: changed since an earlier run made step {} from it (size or modification time); "
                         "making the step again",
                         source.path(s), s);
            fs::remove_all(stepPath);
        }
        if (!fs::exists(stepPath / dataset::format::kStepManifest)) {
            if (fs::exists(stepPath))
                fs::remove_all(stepPath);
            if (donor.give(out.path(), source, options, static_cast<int>(s)))
                ++summary.stepsTaken;
        }
        if (fs::exists(stepPath / dataset::format::kStepManifest)) {
            stepJsons[s] = parseJsonInput(readFile(stepPath / dataset::format::kStepManifest),
                                          (stepPath / dataset::format::kStepManifest).string());
            ++summary.stepsSkipped;
        } else {
            todo.push_back(static_cast<int>(s));
        }
    }
    return todo;
}

// Shell means as a step's manifest keeps them: null for a shell without a value.
json shellMeansJson(const std::vector<double>& means)
{
    json out = json::array();
    for (double mean : means)
        out.push_back(std::isnan(mean) ? json() : json(mean));
    return out;
}

// The step's level-0 shell means of every variable a shell anomaly is computed from
// (step["shell_means"][name], null for a shell without a value) and each shell anomaly's statistics
// (step["computed_stats"][name]), from the exact values: null where the step does not define it (a
// percentage of a shell mean not positive) or it overflows float32. Made with the functions the
// readers compute the values with (dataset/shell_anomaly.h).
void addComputedStats(json& stepJson, const RunPlan& plan, const std::vector<std::vector<float>>& values)
{
    const grid::SphericalGrid& g = plan.header.grid;
    std::map<size_t, std::vector<double>> means;
    for (const VariableSpec& v : plan.computed)
        means.try_emplace(v.computed->base);
    tbb::parallel_for_each(means.begin(), means.end(), [&](auto& m) { m.second = dataset::shellMeans(g, values[m.first]); });
    stepJson["shell_means"] = json::object();
    for (const auto& [base, m] : means)
        stepJson["shell_means"][plan.specs[base].name] = shellMeansJson(m);
    // One variable at a time (each computed in parallel): one more array of the grid in memory.
    std::vector<json> stats(plan.computed.size());
    std::vector<float> anomaly(plan.computed.empty() ? 0 : g.cellCount());
    for (size_t c = 0; c < plan.computed.size(); ++c) {
        const dataset::ShellAnomalyOf of = *plan.computed[c].computed;
        const std::vector<double>& m = means.at(of.base);
        if (of.kind == dataset::ShellAnomalyKind::Percent && !dataset::shellMeansPositive(m))
            continue;
        dataset::computeShellAnomaly(g, values[of.base], m, of.kind, anomaly);
        if (std::any_of(anomaly.begin(), anomaly.end(), [](float x) { return std::isinf(x); }))
            continue;
        stats[c] = dataset::format::toJson(computeStats(g, anomaly));
    }
    stepJson["computed_stats"] = json::object();
    for (size_t c = 0; c < plan.computed.size(); ++c)
        stepJson["computed_stats"][plan.computed[c].name] = stats[c];
}

// A step read, derived and checked, ready to be written (writeStep).
struct ReadStep {
    int index = 0;
    json fingerprint;
    grid::Snapshot snap;
};

// Phase 5, reading one step: the input's values, the stored derived variables, checked.
ReadStep readStep(const RunPlan& plan, const StepSource& source, int s)
{
    const std::string input = source.path(size_t(s));
    const auto start = std::chrono::steady_clock::now();
    ReadStep step;
    step.index = s;
    step.fingerprint = source.fingerprint(size_t(s));  // before reading: a change while reading is seen next time
    step.snap = source.read(size_t(s));
    spdlog::debug("{}: read in {:.2f} s", source.label(size_t(s)), secondsSince(start));
    checkSameGrid(input, step.snap.grid, plan.header.grid, source.label(0));
    addStoredDerivedVariables(step.snap);
    RAYPC_CHECK_EQ(step.snap.fields.size(), plan.specs.size());
    // The reader refused non-finite inputs; a finite input can still derive an infinity.
    for (const auto& field : step.snap.fields)
        grid::checkFinite(step.snap, field, input);
    return step;
}

// Reads the steps one ahead, on a thread of its own, while the caller works on the one before:
// reading a netCDF step is one thread's work (the library decodes serially), and writing a step or
// tracing its pathlines keeps the other cores busy. Holds at most one step read and not yet taken.
// take(i) must be called for i = 0, 1, … in order, and readNext() after each take() to start
// reading step i + 1 (when the caller has room for it in memory); a read's failure is thrown by the
// take() of its step, after every step before it was taken, as a serial run would. One thread reads
// every step, started here: it keeps the priority of the thread that made this object, whatever that
// thread's priority later becomes (PreprocessOptions::niceIncrement). The destructor waits for a read
// under way (a run that fails or is cancelled leaves no thread behind).
class StepsReadAhead {
public:
    StepsReadAhead(const RunPlan& plan, const StepSource& source, std::vector<int> order, const PreprocessOptions& options)
        : m_plan(plan), m_source(source), m_order(std::move(order)), m_options(options), m_reads(m_order.size())
    {
        for (auto& read : m_reads)
            m_taken.push_back(read.get_future());
        m_thread = std::thread([this] { readInOrder(); });
    }
    ~StepsReadAhead()
    {
        {
            std::lock_guard lock(m_mutex);
            m_stopping = true;
        }
        m_wake.notify_one();
        m_thread.join();
    }
    StepsReadAhead(const StepsReadAhead&) = delete;
    StepsReadAhead& operator=(const StepsReadAhead&) = delete;

    ReadStep take(size_t i)
    {
        RAYPC_CHECK_EQ(i, m_next);
        ++m_next;
        const auto start = std::chrono::steady_clock::now();
        ReadStep step = m_taken[i].get();
        spdlog::debug("{}: waited {:.2f} s for its reading", m_source.label(size_t(step.index)), secondsSince(start));
        return step;
    }

    void readNext()
    {
        {
            std::lock_guard lock(m_mutex);
            m_allowed = m_next + 1;
        }
        m_wake.notify_one();
    }

private:
    void readInOrder()
    {
        for (size_t i = 0; i < m_order.size(); ++i) {
            {
                std::unique_lock lock(m_mutex);
                m_wake.wait(lock, [&] { return m_stopping || m_allowed > i; });
                if (m_stopping)
                    return;
            }
            try {
                phases::throwIfCancelled(m_options);
                m_reads[i].set_value(readStep(m_plan, m_source, m_order[i]));
            } catch (...) {
                m_reads[i].set_exception(std::current_exception());
                return;  // the steps after a failed one are never taken
            }
        }
    }

    const RunPlan& m_plan;
    const StepSource& m_source;
    std::vector<int> m_order;
    const PreprocessOptions& m_options;
    std::vector<std::promise<ReadStep>> m_reads;  // set by the reading thread, in order
    std::vector<std::future<ReadStep>> m_taken;   // m_reads' futures
    size_t m_next = 0;                            // the next take(); the caller's thread only
    std::mutex m_mutex;                           // guards m_allowed and m_stopping
    std::condition_variable m_wake;
    size_t m_allowed = 1;  // steps the reading thread may read: m_order[0, m_allowed)
    bool m_stopping = false;
    std::thread m_thread;  // last: started once the members above exist
};

// The calling thread's nice value raised by `increment` (Linux's per-thread priority; an
// unprivileged thread cannot lower it again), at most to 19. 0: unchanged.
void lowerThreadPriority(int increment)
{
    if (increment <= 0)
        return;
    errno = 0;
    const int nice = ::getpriority(PRIO_PROCESS, static_cast<id_t>(::gettid()));
    if (errno == 0)
        ::setpriority(PRIO_PROCESS, static_cast<id_t>(::gettid()), std::min(nice + increment, 19));
}

// Phase 5, writing one step: statistics and sample values at full resolution, then level by level
// values and brick bounds of every variable, written into a temporary directory renamed when whole
// (removed if anything fails). Returns the step's manifest.
json writeStep(const fs::path& outDir, const RunPlan& plan, const StepSource& source, ReadStep&& read,
               std::span<const uint32_t> cells, const PreprocessOptions& options)
{
    const int s = read.index;
    const std::string label = source.label(size_t(s));
    const auto& specs = plan.specs;
    const auto stepStart = std::chrono::steady_clock::now();
    auto elapsed = [&] { return secondsSince(stepStart); };
    const json fingerprint = std::move(read.fingerprint);
    grid::Snapshot snap = std::move(read.snap);

    const fs::path finalDir = dataset::format::stepDir(outDir, s);
    const fs::path tmpDir = temporarySibling(finalDir);
    ScopeCleanup removeTmp([&] {
        std::error_code ec;
        fs::remove_all(tmpDir, ec);
    });
    json stepJson = {{"index", s}, {"time_myr", stepTimeMyr(options, s)}, {"source", label}};
    if (!snap.origin.is_null())
        stepJson["origin"] = snap.origin;
    stepJson["stats"] = json::array();
    std::vector<std::vector<float>> current(snap.fields.size());
    for (size_t v = 0; v < snap.fields.size(); ++v)
        current[v] = std::move(snap.fields[v].values);
    std::vector<float> sample(cells.size() * specs.size());
    std::vector<dataset::VariableStats> stats(specs.size());
    tbb::parallel_for(size_t(0), specs.size(), [&](size_t v) {
        stats[v] = computeStats(plan.header.grid, current[v]);
        for (size_t i = 0; i < cells.size(); ++i)
            sample[i * specs.size() + v] = current[v][cells[i]];
    });
    for (const auto& st : stats)
        stepJson["stats"].push_back(dataset::format::toJson(st));
    addComputedStats(stepJson, plan, current);
    spdlog::debug("{}: derived, stats and sample done at {:.2f} s", label, elapsed());
    for (int level = 0; level < dataset::kLevelCount; ++level)
        fs::create_directories(dataset::format::levelDir(tmpDir, level));
    // The shell means a reader's StepVolume::shellMeansOf gives on each level of every variable a
    // shell anomaly is computed from (dataset::StepInfo::levelShellMeans): of the level's values as
    // stored (for u16 decoded again), the same bits, so that a reader need not decode a base whole.
    std::vector<std::vector<std::vector<double>>> levelMeans(specs.size());  // [variable][level][shell]
    for (const VariableSpec& c : plan.computed)
        levelMeans[c.computed->base].resize(dataset::kLevelCount);
    // Variables in parallel: writing into the page cache costs as much CPU as computing,
    // so both cores write while they compute bounds and coarser levels.
    tbb::parallel_for(size_t(0), specs.size(), [&](size_t v) {
        const auto stem = fileSafeName(specs[v].name);
        const bool keepMeans = !levelMeans[v].empty();
        for (int level = 0; level < dataset::kLevelCount; ++level) {
            const grid::SphericalGrid& grid = plan.levels[level];
            const grid::BrickLayout layout = grid::BrickLayout::forGrid(grid, options.brickSize);
            const fs::path dir = dataset::format::levelDir(tmpDir, level);
            std::vector<float> bounds(2 * layout.brickCount());
            dataset::computeBrickBounds(grid, layout, current[v], bounds);
            if (options.encoding == dataset::ValueEncoding::Uint16) {
                // Quantised from the exact values; coarser levels are computed from the exact ones too.
                const bool missing = stats[v].missingPoints > 0;
                // Not value-initialised: encodeUint16 writes every code (a zeroing pass saved).
                const auto codes = std::make_unique_for_overwrite<uint16_t[]>(current[v].size());
                const std::span<uint16_t> encoded(codes.get(), current[v].size());
                dataset::encodeUint16(grid, layout, current[v], bounds, encoded, missing);
                writeArray<uint16_t>(dataset::format::encodedValuesFile(dir, stem), encoded);
                if (keepMeans)
                    levelMeans[v][size_t(level)] = dataset::shellMeansOfUint16(grid, layout, encoded, bounds, missing);
            } else {
                writeArray<float>(dataset::format::valuesFile(dir, stem), current[v]);
                if (keepMeans)
                    levelMeans[v][size_t(level)] = dataset::shellMeans(grid, current[v]);
            }
            writeArray<float>(dataset::format::boundsFile(dir, stem), bounds);
            if (level + 1 < dataset::kLevelCount)
                current[v] = coarsenField(grid, current[v]);
        }
    });
    // step["level_shell_means"][level][name].
    stepJson["level_shell_means"] = json::array();
    for (int level = 0; level < dataset::kLevelCount; ++level) {
        json& byName = stepJson["level_shell_means"].emplace_back(json::object());
        for (size_t v = 0; v < specs.size(); ++v)
            if (!levelMeans[v].empty())
                byName[specs[v].name] = shellMeansJson(levelMeans[v][size_t(level)]);
    }
    writeArray<float>(tmpDir / dataset::format::kStepSample, sample);
    writeFileAtomic(tmpDir / dataset::format::kStepInputs, fingerprint.dump(1));
    {
        std::ofstream file(tmpDir / dataset::format::kStepManifest);
        file << stepJson.dump(1);
        if (!file)
            fail("{}: write failed", (tmpDir / dataset::format::kStepManifest).string());
    }
    renameAtomic(tmpDir, finalDir);
    removeTmp.dismiss();
    spdlog::debug("{}: levels, bricks and files done at {:.2f} s", label, elapsed());
    return stepJson;
}

// The computed variables every step defines (its statistics in every step's "computed_stats"; a
// step made before they existed has none), in the plan's order.
std::vector<VariableSpec> offeredComputedSpecs(const RunPlan& plan, const std::vector<json>& stepJsons)
{
    std::vector<VariableSpec> offered;
    for (const VariableSpec& v : plan.computed)
        if (std::all_of(stepJsons.begin(), stepJsons.end(), [&](const json& sj) {
                const auto stats = sj.find("computed_stats");
                return stats != sj.end() && stats->contains(v.name) && !stats->at(v.name).is_null();
            }))
            offered.push_back(v);
    return offered;
}

// Phase 6: every step's statistics and the global ranges and histograms in the manifest, the
// computed variables the steps define appended to its variables (their statistics to the steps').
void addStepsToManifest(json& j, const std::vector<json>& stepJsons, const std::vector<VariableSpec>& computed)
{
    j["steps"] = json::array();
    for (json sj : stepJsons) {
        for (const VariableSpec& v : computed)
            sj["stats"].push_back(sj.at("computed_stats").at(v.name));
        sj.erase("computed_stats");
        if (computed.empty()) {
            sj.erase("shell_means");
            sj.erase("level_shell_means");
        }
        j["steps"].push_back(std::move(sj));
    }
    for (const VariableSpec& v : computed)
        j["variables"].push_back(variableJson(v));
    for (size_t v = 0; v < j["variables"].size(); ++v) {
        std::vector<dataset::VariableStats> perStep;
        for (const auto& sj : j["steps"])
            perStep.push_back(dataset::format::statsFromJson(sj.at("stats").at(v)));
        j["variables"][v]["global"] = dataset::format::toJson(statsOverSteps(perStep));
    }
}

// The one pass of pathlines (phases::PathlineStream) for one process, over the sets still to do,
// with the variables the plan expects; none under mpirun (phase 7 shares the sets out), without
// pathlines, or when the seed field is not among the variables (phase 7 then says so).
std::unique_ptr<phases::PathlineStream> startPathlines(const fs::path& outDir, const RunPlan& plan,
                                                       const PreprocessOptions& options, const std::vector<json>& stepJsons)
{
    const PathlineOptions& po = options.pathlines;
    if (mpi::distributed() || !po.enabled || po.steps < 1)
        return nullptr;
    std::vector<VariableSpec> specs = plan.specs;
    specs.insert(specs.end(), plan.computed.begin(), plan.computed.end());
    if (std::none_of(specs.begin(), specs.end(), [&](const VariableSpec& v) { return v.name == po.field; }))
        return nullptr;
    std::vector<double> times;
    for (size_t s = 0; s < stepJsons.size(); ++s)
        times.push_back(stepJsons[s].is_null() ? stepTimeMyr(options, int(s)) : stepJsons[s].at("time_myr").get<double>());
    int skipped = 0;
    std::vector<int> sets = phases::pathlineSetsToDo(outDir, int(stepJsons.size()), po, {}, skipped);
    auto stream = std::make_unique<phases::PathlineStream>(outDir, plan.header.grid, std::move(specs), std::move(sets),
                                                            std::move(times), options);
    const int total = int(stepJsons.size());
    stream->onSetWritten = [&options, &stream = *stream, skipped, total] {
        if (options.onProgress)
            options.onProgress({"pathlines", skipped + int(stream.written().size()), total});
    };
    return stream;
}

}  // namespace

void phases::throwIfCancelled(const PreprocessOptions& options)
{
    if (options.cancel && options.cancel->load())
        fail("preprocess: cancelled");
}

uint64_t preprocessMemoryBytes(const grid::SphericalGrid& grid, size_t variableCount)
{
    return (variableCount + 1) * uint64_t(grid.nLat()) * grid.nR() * grid.nLon() * sizeof(float);
}

PreprocessSummary preprocess(const std::vector<fs::path>& inputs, const fs::path& outDir,
                             const PreprocessOptions& options)
{
    FileSeries files(inputs, options.reader);
    return preprocess(files, outDir, options);
}

PreprocessSummary preprocess(StepSource& source, const fs::path& outDir, const PreprocessOptions& given)
{
    // What the inputs allow: planRun turns pathlines off for a model without a velocity.
    PreprocessOptions options = given;
    // Under mpirun (core/mpi.h, docs/scaling.md) every rank plans the run; rank 0 owns the output
    // directory (lock, manifest, cleanup of a failed fresh run); the steps are handed out one at a
    // time to whichever rank is free, each written atomically by it; the steps' manifests are then
    // gathered, and rank 0 writes the global statistics. Each phase ends with every rank agreeing.
    const auto start = std::chrono::steady_clock::now();
    RunPlan plan;
    mpi::together([&] { plan = planRun(source, options); });
    // From here on the run writes; one run at a time per directory.
    std::optional<OutputDirectory> out;
    mpi::together([&] {
        if (mpi::isRoot())
            out.emplace(outDir, plan.manifest);
    });
    std::vector<uint32_t> cells;
    mpi::together([&] { cells = writeSampleCoordinates(outDir, plan.header.grid, options); });

    PreprocessSummary summary;
    std::vector<json> stepJsons(source.stepCount());
    std::vector<int> todo;
    mpi::together([&] {
        if (mpi::isRoot())
            todo = findStepsToDo(*out, source, plan, options, stepJsons, summary);
    });
    if (mpi::distributed()) {
        // Rank 0 found what an earlier run left; every rank needs the list and the finished steps.
        const json found = json::parse(mpi::broadcast(
            json{{"todo", todo}, {"skipped", summary.stepsSkipped}, {"steps", stepJsons}}.dump()));
        todo = found.at("todo").get<std::vector<int>>();
        summary.stepsSkipped = found.at("skipped").get<int>();
        stepJsons = found.at("steps").get<std::vector<json>>();
    }
    if (summary.stepsSkipped > 0 && !options.quiet && mpi::isRoot())
        spdlog::info("{}: {} of {} steps already done by an earlier run{}, skipping them", outDir.string(),
                     summary.stepsSkipped, source.stepCount(),
                     summary.stepsTaken > 0 ? fmt::format(" or in {}", options.stepsFrom.string()) : "");
    if (options.onProgress && mpi::isRoot())
        options.onProgress({"steps", summary.stepsSkipped, int(source.stepCount())});
    std::optional<Progress> progress;
    if (!options.quiet && !todo.empty() && mpi::isRoot())
        progress.emplace("preprocess", static_cast<int64_t>(todo.size()), "steps");
    // One process traces the pathlines while it writes the steps (phases::PathlineStream), fed each
    // step in order once it and every step before it are written; with the variables the plan
    // expects (a computed variable some step leaves undefined loses its columns afterwards).
    std::unique_ptr<phases::PathlineStream> pathlines = startPathlines(outDir, plan, options, stepJsons);
    int fed = 0;
    auto feedPathlines = [&] {
        for (; pathlines && fed < int(stepJsons.size()) && !stepJsons[size_t(fed)].is_null(); ++fed)
            pathlines->stepReady(fed, stepJsons[size_t(fed)]);
    };
    int64_t reported = 0;
    json written = json::object();  // this rank's steps: index -> step manifest
    try {
        feedPathlines();
        // One process reads the next step while it works on this one; under mpirun each rank takes
        // whichever step is next when it is free (mpi::forEachDynamic), so it cannot read ahead. A
        // run with every step taken or written before starts no reading thread.
        std::optional<StepsReadAhead> ahead;
        if (!mpi::distributed() && options.readAhead && !todo.empty())
            ahead.emplace(plan, source, todo, options);
        lowerThreadPriority(options.niceIncrement);
        mpi::forEachDynamic(
            int64_t(todo.size()),
            [&](int64_t item) {
                phases::throwIfCancelled(options);
                const int s = todo[size_t(item)];
                ReadStep read = ahead ? ahead->take(size_t(item)) : readStep(plan, source, s);
                // The next step is read while this one's pathlines are traced, once its arrays are
                // written and freed (a step read while another is written would add a step's
                // arrays to the peak: 0.5 GB at full resolution) and onProgress has returned (what
                // it does with the step, such as `raypc serve`'s preview, is not kept waiting for
                // a read: reading a netCDF file is one call at a time); without pathlines, at once.
                if (ahead && !pathlines)
                    ahead->readNext();
                const json& stepJson = written[std::to_string(s)] =
                    writeStep(outDir, plan, source, std::move(read), cells, options);
                if (out)
                    out->keep();
                ++summary.stepsWritten;
                if (options.onProgress)
                    options.onProgress({"steps", summary.stepsSkipped + summary.stepsWritten, int(source.stepCount())});
                if (ahead && pathlines)
                    ahead->readNext();
                mpi::dieHook("preprocess-step");
                if (pathlines) {
                    stepJsons[size_t(s)] = stepJson;
                    feedPathlines();
                }
            },
            [&](int64_t handedOut) {
                if (progress)
                    progress->advance(handedOut - std::exchange(reported, handedOut));
            });
    } catch (const Error& e) {
        // What the run finished stays (the failed step's temporary directory does not), whichever
        // rank finished it.
        const int64_t kept = mpi::sum(int64_t(summary.stepsWritten)) + summary.stepsSkipped;
        if (kept == 0)
            throw;
        if (out)
            out->keep();
        throw mpi::AgreedError(fmt::format("{} ({} finished steps stay in {}: a rerun resumes from them)", e.what(),
                                           kept, outDir.string()));
    }
    if (progress)
        progress->finish();
    summary.stepsWritten = int(mpi::sum(int64_t(summary.stepsWritten)));
    if (out && summary.stepsWritten > 0)
        out->keep();
    for (const std::string& part : mpi::allgather(written.dump())) {
        const json steps = json::parse(part);
        for (const auto& [index, stepJson] : steps.items())
            stepJsons[size_t(std::stoi(index))] = stepJson;
    }

    // The dataset's variables: the stored ones, then the computed ones every step defines.
    std::vector<VariableSpec> variables = plan.specs;
    const std::vector<VariableSpec> computed = offeredComputedSpecs(plan, stepJsons);
    variables.insert(variables.end(), computed.begin(), computed.end());
    std::set<int> pathlinesMade;  // by the one pass, with the columns of `variables`
    if (pathlines) {
        if (!pathlines->stopped()) {
            // A computed variable some step leaves undefined is not the dataset's: its columns go.
            if (computed.size() != plan.computed.size())
                phases::keepPathlineColumns(outDir, pathlines->written(), variables);
            pathlinesMade = pathlines->written();
            summary.pathlineSetsWritten += int(pathlinesMade.size());
            summary.pathlineCount += pathlines->lineCount();
        }
        summary.pathlineWindowPeakBytes = pathlines->peakHeldBytes();
        pathlines.reset();
    }
    mpi::together([&] {
        addStepsToManifest(plan.manifest, stepJsons, computed);
        // Phase 7 reads the finished steps back: the manifest says "complete" only after it.
        if (out)
            out->writeManifest(plan.manifest);
    });
    mpi::dieHook("preprocess-pathlines");
    // Pathlines need the flow and their seed field everywhere: missing values in either (a regional
    // model's padding, a model's holes) leave them out, said once. A computed field has gaps where
    // the variable it is computed from has.
    if (options.pathlines.enabled) {
        std::vector<std::string> gaps;
        for (size_t v = 0; v < variables.size(); ++v) {
            const std::string& name = variables[v].name;
            if (!varname::isVelocityComponent(name) && name != options.pathlines.field)
                continue;
            const size_t stored = variables[v].computed ? variables[v].computed->base : v;
            for (const json& sj : stepJsons)
                if (sj.at("stats").at(stored).value("missing_points", size_t(0)) > 0) {
                    gaps.push_back(name);
                    break;
                }
        }
        if (!gaps.empty()) {
            options.pathlines.enabled = false;
            options.pathlines.absentBecause = fmt::format("{} {} missing values", fmt::join(gaps, ", "),
                                                          gaps.size() == 1 ? "has" : "have");
            if (!options.quiet && mpi::isRoot())
                spdlog::info("{}: {} {} missing values: no pathlines", source.path(0), fmt::join(gaps, ", "),
                             gaps.size() == 1 ? "has" : "have");
        }
    }
    phases::writePathlines(outDir, plan.header.grid, variables, stepJsons, options, pathlinesMade, summary);
    mpi::together([&] {
        plan.manifest["pathlines"] =
            options.pathlines.enabled ? phases::pathlineSettings(options.pathlines) : json();
        if (!options.pathlines.enabled)
            plan.manifest["no_pathlines"] = options.pathlines.absentBecause.empty()
                                                ? std::string("preprocessed with --no-pathlines")
                                                : options.pathlines.absentBecause;
        plan.manifest["status"] = "complete";
        if (out)
            out->writeManifest(plan.manifest);
    });
    summary.seconds = secondsSince(start);
    return summary;
}

}  // namespace raypc::preprocess
