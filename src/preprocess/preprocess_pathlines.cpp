#include "core/atomic_file.h"
#include "core/error.h"
#include "core/error_kinds.h"
#include "core/json_input.h"
#include "core/mpi.h"
#include "core/progress.h"
#include "core/strings.h"
#include "dataset/dataset_format.h"
#include "analysis/pathline_storage.h"
#include "analysis/persistence.h"
#include "preprocess/preprocess_phases.h"

#include <spdlog/spdlog.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <map>
#include <optional>
#include <utility>

namespace raypc::preprocess::phases {
namespace {

namespace fs = std::filesystem;
using nlohmann::json;

// The stored variables' missing-value flags of a step (how its arrays are encoded), from its
// manifest's statistics.
std::vector<char> missingFlags(const json& stepJson, size_t storedCount)
{
    std::vector<char> missing;
    for (size_t v = 0; v < storedCount; ++v)
        missing.push_back(stepJson.at("stats").at(v).value("missing_points", size_t(0)) > 0);
    return missing;
}

}  // namespace

json pathlineSettings(const PathlineOptions& o)
{
    return {{"field", o.field},
            {"steps", o.steps},
            {"filter",
             {{"rule", analysis::seedRuleName(o.filter.rule)},
              {"min_persistence", o.filter.minPersistence},
              {"persistence_is_fraction", o.filter.persistenceIsFraction},
              {"min_abs_value", o.filter.minAbsValue},
              {"min_fraction_of_max_abs", o.filter.minFractionOfMaxAbs},
              {"max_count", o.filter.maxCount},
              {"saddles", o.filter.saddles}}},
            {"tracer",
             {{"tolerance_km", o.tracer.toleranceKm},
              {"max_step_myr", o.tracer.maxStepMyr},
              {"max_segment_km", o.tracer.maxSegmentKm},
              {"max_points", o.tracer.maxPoints}}}};
}

void checkPathlineOptions(const PathlineOptions& o, const std::vector<VariableSpec>& specs)
{
    if (!o.enabled)
        return;
    if (o.steps < 1)
        fail("--pathline-steps: {} is not a positive number of steps", o.steps);
    if (std::none_of(specs.begin(), specs.end(), [&](const VariableSpec& v) { return v.name == o.field; })) {
        std::vector<std::string> names;
        for (const auto& v : specs)
            names.push_back(v.name);
        failUnknownName("--pathline-field: no variable '{}' in the input; variables are {}", o.field,
                        fmt::join(names, ", "));
    }
    analysis::checkCriticalPointFilter(o.filter);
}

std::vector<int> pathlineSetsToDo(const fs::path& outDir, int nSteps, const PathlineOptions& po,
                                  const std::set<int>& madeThisRun, int& skipped)
{
    const fs::path root = outDir / "pathlines";
    fs::create_directories(root);
    for (const auto& entry : fs::directory_iterator(root))
        if (entry.path().filename().string().starts_with("."))
            fs::remove_all(entry.path());
    const json settings = pathlineSettings(po);
    std::vector<int> todo;
    for (int s = 0; s < nSteps; ++s) {
        const int endStep = std::min(s + po.steps, nSteps - 1);
        const fs::path dir = analysis::pathlineDir(outDir, s);
        if (fs::exists(dir / "lines.json")) {
            try {
                const json old = parseJsonInput(readFile(dir / "lines.json"), (dir / "lines.json").string());
                // A set of an older version lacks columns (seed persistence): redone.
                if (old.at("settings") == settings && old.at("end_step").get<int>() == endStep &&
                    old.at("version").get<int>() == analysis::kPathlineSetVersion) {
                    skipped += madeThisRun.contains(s) ? 0 : 1;
                    continue;
                }
            } catch (const std::exception&) {  // not JSON (raypc::Error) or not of the expected shape
                // An unreadable set is redone below.
            }
        }
        todo.push_back(s);
    }
    return todo;
}

// --- The one pass ------------------------------------------------------------------------------

// A step of the window: its time and its written level-0 arrays.
struct PathlineStream::Step {
    int index;
    std::vector<char> missing;                    // per stored variable (how its arrays are encoded)
    std::vector<std::vector<double>> shellMeans;  // per stored variable, as kept (readLevelShellMeans)
    std::shared_ptr<const dataset::StepVolume> volume;
};

// A set whose lines are being traced: they have all reached `atStep` (or ended).
struct PathlineStream::OpenSet {
    int injection, end, atStep;
    double threshold;
    std::vector<size_t> criticalCounts;
    std::vector<analysis::CriticalPoint> seeds;
    std::vector<analysis::PathlineTrace> traces;
    std::vector<std::vector<float>> startValues, endValues;  // per line, each variable
};

PathlineStream::PathlineStream(fs::path outDir, const grid::SphericalGrid& grid, std::vector<VariableSpec> specs,
                               std::vector<int> sets, std::vector<double> stepTimesMyr, const PreprocessOptions& options)
    : m_outDir(std::move(outDir)), m_grid(grid), m_specs(std::move(specs)), m_todo(sets.begin(), sets.end()),
      m_timesMyr(std::move(stepTimesMyr)), m_stepCount(int(m_timesMyr.size())), m_options(options),
      m_settings(pathlineSettings(options.pathlines))
{
    checkPathlineOptions(options.pathlines, m_specs);
    for (size_t v = 0; v < m_specs.size(); ++v) {
        const VariableSpec& spec = m_specs[v];
        m_names.push_back(spec.name);
        m_units.push_back(spec.units);
        dataset::VariableInfo info;
        info.name = spec.name;
        info.computed = spec.computed;
        m_variables.push_back(std::move(info));
        if (spec.computed)
            m_computed.push_back(*spec.computed);
        else
            m_stems.push_back(fileSafeName(spec.name));
        m_field = spec.name == options.pathlines.field ? v : m_field;
        m_v[0] = spec.name == "vx" ? v : m_v[0];
        m_v[1] = spec.name == "vy" ? v : m_v[1];
        m_v[2] = spec.name == "vz" ? v : m_v[2];
    }
    if (!m_todo.empty()) {
        m_firstStep = *m_todo.begin();
        m_lastStep = std::min(*m_todo.rbegin() + options.pathlines.steps, m_stepCount - 1);
    }
    m_next = m_firstStep;
}

PathlineStream::~PathlineStream() = default;

analysis::FieldSeries PathlineStream::window(int first, int last) const
{
    analysis::FieldSeries series;
    series.grid = m_grid;
    for (const auto& step : m_window)
        if (step->index >= first && step->index <= last) {
            series.timesMyr.push_back(m_timesMyr[size_t(step->index)]);
            series.volumes.push_back(step->volume);
        }
    RAYPC_CHECK_EQ(series.timesMyr.size(), size_t(last - first + 1));
    return series;
}

void PathlineStream::noteHeldBytes(size_t extra)
{
    size_t held = extra;
    for (const auto& step : m_window)
        held += step->volume->decodedBytes();
    m_peakHeldBytes = std::max(m_peakHeldBytes, held);
}

void PathlineStream::stepReady(int k, const json& stepJson)
{
    if (m_stopped || k < m_firstStep || k > m_lastStep)
        return;
    RAYPC_CHECK_EQ(k, m_next);
    ++m_next;
    throwIfCancelled(m_options);
    // Pathlines need the flow and their seed field everywhere (the run then leaves them out).
    const std::vector<char> missing = missingFlags(stepJson, m_stems.size());
    const size_t seedBase = m_specs[m_field].computed ? m_specs[m_field].computed->base : m_field;
    if (missing[m_v[0]] || missing[m_v[1]] || missing[m_v[2]] || missing[seedBase]) {
        m_stopped = true;
        m_open.clear();
        m_window.clear();
        return;
    }
    const dataset::LevelInfo level{m_grid, grid::BrickLayout::forGrid(m_grid, m_options.brickSize)};
    // The level-0 shell means the step keeps (writeStep: the bits StepVolume::shellMeansOf would
    // compute from the decoded values), so that a volume of the step decodes no variable whole for
    // them (the seed field's anomaly, the shell anomalies sampled at a line's ends).
    std::vector<std::vector<double>> shellMeans = dataset::readLevelShellMeans(
        stepJson, (dataset::format::stepDir(m_outDir, k) / dataset::format::kStepManifest).string(), m_variables, 0,
        dataset::kLevelCount, m_grid.nR());
    shellMeans.resize(m_stems.size());  // the stored variables'
    auto volume = dataset::StepVolume::open(dataset::format::levelDir(dataset::format::stepDir(m_outDir, k), 0), level,
                                            m_stems, m_options.encoding, {}, missing, m_computed, shellMeans);
    m_window.push_back(std::make_unique<Step>(Step{k, missing, std::move(shellMeans), std::move(volume)}));

    // Lines at step k - 2 go on to k - 1 with step k at hand (a Dormand–Prince step that lands on
    // k - 1 within rounding samples past it, as one trace over the whole series would); then the
    // sets that end at k reach it from k - 1.
    std::vector<OpenSet*> onward, ending;
    for (const auto& set : m_open)
        if (set->atStep == k - 2 && set->end >= k)
            onward.push_back(set.get());
    if (!onward.empty())
        advance(onward, k - 1, window(k - 2, k));
    for (const auto& set : m_open)
        if (set->atStep == k - 1 && set->end == k)
            ending.push_back(set.get());
    if (!ending.empty())
        advance(ending, k, window(k - 1, k));
    noteHeldBytes();
    for (OpenSet* set : ending)
        finish(*set);
    std::erase_if(m_open, [](const auto& set) { return set->atStep == set->end; });
    // Step k - 2 is no longer needed: the next interval is k - 1 .. k with k + 1 at hand.
    std::erase_if(m_window, [&](const auto& step) { return step->index < k - 1; });
    if (m_todo.contains(k))
        open(k);
    // The lines read the window's files at scattered points, each read mapping a 2 MB folio: with
    // every variable sampled at the lines' ends, the three steps' files were 0.66 GB of the process's
    // resident memory at full resolution. Dropped between steps; the next step maps what it reads.
    for (const auto& step : m_window)
        step->volume->dropResidentPages();
}

void PathlineStream::advance(const std::vector<OpenSet*>& sets, int toStep, const analysis::FieldSeries& series)
{
    const analysis::PathlineTracer tracer(series, m_v[0], m_v[1], m_v[2], m_options.pathlines.tracer);
    const double untilMyr = m_timesMyr[size_t(toStep)];
    std::vector<std::pair<OpenSet*, size_t>> lines;
    for (OpenSet* set : sets)
        for (size_t i = 0; i < set->traces.size(); ++i)
            if (!set->traces[i].done)
                lines.emplace_back(set, i);
    tbb::parallel_for(size_t(0), lines.size(), [&](size_t n) {
        auto [set, i] = lines[n];
        analysis::PathlineTrace& tr = set->traces[i];
        tracer.advance(tr, untilMyr, m_timesMyr[size_t(set->end)]);
        if (tr.done)
            set->endValues[i] = analysis::sampleVariables(tracer, m_names.size(), tr.line.pointsKm.back(),
                                                          tr.line.timesMyr.back());
    });
    for (OpenSet* set : sets)
        set->atStep = toStep;
}

void PathlineStream::open(int s)
{
    auto set = std::make_unique<OpenSet>();
    set->injection = set->atStep = s;
    set->end = std::min(s + m_options.pathlines.steps, m_stepCount - 1);
    {
        // The seed field decoded for the critical points only (the window decodes the velocity).
        const auto seedVolume = dataset::StepVolume::open(
            dataset::format::levelDir(dataset::format::stepDir(m_outDir, s), 0),
            dataset::LevelInfo{m_grid, grid::BrickLayout::forGrid(m_grid, m_options.brickSize)}, m_stems,
            m_options.encoding, {}, m_window.back()->missing, m_computed, m_window.back()->shellMeans);
        const std::span<const float> values(seedVolume->values(m_field), m_grid.cellCount());
        noteHeldBytes(seedVolume->decodedBytes());  // the window's, and the seed field's
        const analysis::CriticalStructure structure = analysis::criticalStructure(m_grid, values);
        const std::vector<analysis::CriticalPoint>& all = structure.points;
        analysis::SeedSelection selection = analysis::selectSeedsFrom(m_grid, values, structure, m_options.pathlines.filter);
        set->seeds = std::move(selection.seeds);
        set->threshold = selection.threshold;
        set->criticalCounts.assign(5, 0);
        for (const auto& p : all)
            ++set->criticalCounts[static_cast<size_t>(p.kind)];
        spdlog::debug("step {}: {} critical points, {} seeds above {:.4g}", s, all.size(), set->seeds.size(),
                      set->threshold);
    }
    const analysis::FieldSeries series = window(s, s);
    const analysis::PathlineTracer tracer(series, m_v[0], m_v[1], m_v[2], m_options.pathlines.tracer);
    const size_t n = set->seeds.size();
    set->traces.resize(n);
    set->startValues.resize(n);
    set->endValues.resize(n);
    tbb::parallel_for(size_t(0), n, [&](size_t i) {
        const analysis::CriticalPoint& seed = set->seeds[i];
        analysis::PathlineTrace& tr = set->traces[i];
        tr = tracer.begin(sphericalToCartesianKm(seed.latDeg, seed.lonDeg, seed.rKm), m_timesMyr[size_t(s)]);
        set->startValues[i] = analysis::sampleVariables(tracer, m_names.size(), tr.line.pointsKm.front(),
                                                        tr.line.timesMyr.front());
        if (set->end == s)  // the last step: lines of one point
            tracer.advance(tr, m_timesMyr[size_t(s)], m_timesMyr[size_t(s)]);
        if (tr.done)
            set->endValues[i] = analysis::sampleVariables(tracer, m_names.size(), tr.line.pointsKm.back(),
                                                          tr.line.timesMyr.back());
    });
    noteHeldBytes();
    if (set->end == s)
        finish(*set);
    else
        m_open.push_back(std::move(set));
}

void PathlineStream::finish(OpenSet& open)
{
    throwIfCancelled(m_options);
    analysis::PathlineSet set =
        analysis::emptyPathlineSet(open.injection, m_timesMyr[size_t(open.injection)], open.end, m_names, m_units);
    for (size_t i = 0; i < open.seeds.size(); ++i) {
        RAYPC_CHECK(open.traces[i].done);
        appendPathline(set, open.seeds[i], open.traces[i].line, open.startValues[i], open.endValues[i]);
    }
    set.seedField = m_options.pathlines.field;
    set.threshold = open.threshold;
    set.criticalCounts = open.criticalCounts;
    set.settingsJson = m_settings.dump();

    const fs::path finalDir = analysis::pathlineDir(m_outDir, open.injection);
    const fs::path tmpDir = temporarySibling(finalDir);
    analysis::writePathlineSet(tmpDir, set);
    if (fs::exists(finalDir))
        fs::remove_all(finalDir);
    renameAtomic(tmpDir, finalDir);
    spdlog::debug("step {}: {} pathlines of {} points written", open.injection, set.lineCount(), set.pointCount());
    m_written.insert(open.injection);
    m_lineCount += set.lineCount();
    open.traces.clear();
    if (onSetWritten)
        onSetWritten();
}

void keepPathlineColumns(const fs::path& outDir, const std::set<int>& sets, const std::vector<VariableSpec>& specs)
{
    std::vector<std::string> names;
    for (const auto& v : specs)
        names.push_back(v.name);
    const std::vector<std::string> columns = analysis::pathlineColumns(names);
    for (int s : sets) {
        analysis::PathlineSet set = analysis::loadPathlineSet(outDir, s);
        std::vector<size_t> kept;
        for (const std::string& c : columns) {
            const int at = set.column(c);
            RAYPC_CHECK(at >= 0);
            kept.push_back(size_t(at));
        }
        std::vector<float> attributes;
        std::vector<std::string> units;
        for (size_t c : kept)
            units.push_back(set.units[c]);
        for (size_t line = 0; line < set.lineCount(); ++line)
            for (size_t c : kept)
                attributes.push_back(set.attribute(line, c));
        set.columns = columns;
        set.units = std::move(units);
        set.attributes = std::move(attributes);
        const fs::path finalDir = analysis::pathlineDir(outDir, s);
        const fs::path tmpDir = temporarySibling(finalDir);
        analysis::writePathlineSet(tmpDir, set);
        fs::remove_all(finalDir);
        renameAtomic(tmpDir, finalDir);
    }
}

void writePathlines(const fs::path& outDir, const grid::SphericalGrid& grid, const std::vector<VariableSpec>& specs,
                    const std::vector<json>& stepJsons, const PreprocessOptions& options,
                    const std::set<int>& madeThisRun, PreprocessSummary& summary)
{
    const PathlineOptions& po = options.pathlines;
    checkPathlineOptions(po, specs);  // the field among the variables the dataset has in the end
    const fs::path root = outDir / "pathlines";
    const int nSteps = static_cast<int>(stepJsons.size());
    // Rank 0 clears what a killed run left and finds the sets to do; under mpirun the others learn
    // the list from it and each rank traces a contiguous block of them (mpi::blockOf).
    std::vector<int> todo;
    int skipped = 0;
    mpi::together([&] {
        if (!mpi::isRoot())
            return;
        if (!po.enabled)
            fs::remove_all(root);
        else
            todo = pathlineSetsToDo(outDir, nSteps, po, madeThisRun, skipped);
    });
    if (!po.enabled)
        return;
    if (mpi::distributed()) {
        const json found = json::parse(mpi::broadcast(json{{"todo", todo}, {"skipped", skipped}}.dump()));
        todo = found.at("todo").get<std::vector<int>>();
        skipped = found.at("skipped").get<int>();
    }
    summary.pathlineSetsSkipped += skipped;
    const mpi::Block block = mpi::blockOf(int64_t(todo.size()));
    std::vector<double> times;
    for (const json& sj : stepJsons)
        times.push_back(sj.at("time_myr").get<double>());
    PathlineStream stream(outDir, grid, specs,
                          std::vector<int>(todo.begin() + block.begin, todo.begin() + block.end), times, options);
    std::optional<Progress> progress;
    if (!options.quiet && !todo.empty() && mpi::isRoot())
        progress.emplace("pathlines", static_cast<int64_t>(block.end - block.begin), "steps");
    const int before = summary.pathlineSetsSkipped + summary.pathlineSetsWritten;
    stream.onSetWritten = [&] {
        if (progress)
            progress->advance(1);
        if (options.onProgress)
            options.onProgress({"pathlines", before + int(stream.written().size()), nSteps});
    };
    mpi::together([&] {
        for (int k = stream.firstStep(); k <= stream.lastStep(); ++k)
            stream.stepReady(k, stepJsons[size_t(k)]);
    });
    if (progress)
        progress->finish();
    std::array<int64_t, 2> counts{int64_t(stream.written().size()), int64_t(stream.lineCount())};
    mpi::sum(counts);
    summary.pathlineSetsWritten += int(counts[0]);
    summary.pathlineCount += size_t(counts[1]);
    summary.pathlineWindowPeakBytes = std::max(summary.pathlineWindowPeakBytes, stream.peakHeldBytes());
    // Sets of steps beyond the inputs (a rerun with fewer inputs is refused earlier) never stay.
    mpi::together([&] {
        if (!mpi::isRoot())
            return;
        for (const auto& entry : fs::directory_iterator(root)) {
            const std::string name = entry.path().filename().string();
            if (name.size() == 4 && std::all_of(name.begin(), name.end(), ::isdigit) && std::stoi(name) >= nSteps)
                fs::remove_all(entry.path());
        }
    });
}

}  // namespace raypc::preprocess::phases
