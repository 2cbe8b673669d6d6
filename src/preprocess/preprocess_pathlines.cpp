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

// The level-0 arrays of written steps, opened on demand and released when no longer needed. A u16
// variable is decoded when a trace first reads it: the pathlines see the values every reader sees.
class StepArrays {
public:
    StepArrays(fs::path dataset, const grid::SphericalGrid& grid, const std::vector<VariableSpec>& specs,
               const std::vector<json>& stepJsons, const PreprocessOptions& options)
        : m_dir(std::move(dataset)), m_level{grid, grid::BrickLayout::forGrid(grid, options.brickSize)},
          m_encoding(options.encoding)
    {
        for (const auto& v : specs) {
            if (v.computed)
                m_computed.push_back(*v.computed);
            else
                m_stems.push_back(fileSafeName(v.name));
        }
        // Per step and stored variable: whether it has missing values (how its arrays are encoded).
        for (const json& sj : stepJsons) {
            std::vector<char>& missing = m_missing.emplace_back();
            for (size_t v = 0; v < m_stems.size(); ++v)
                missing.push_back(sj.at("stats").at(v).value("missing_points", size_t(0)) > 0);
        }
    }

    const std::shared_ptr<const dataset::StepVolume>& volume(int step)
    {
        auto& v = m_steps[step];
        if (!v)
            v = dataset::StepVolume::open(dataset::format::levelDir(dataset::format::stepDir(m_dir, step), 0), m_level, m_stems, m_encoding, {},
                                          m_missing.at(size_t(step)), m_computed);
        return v;
    }
    // Releases the steps before `step`.
    void releaseBefore(int step) { m_steps.erase(m_steps.begin(), m_steps.lower_bound(step)); }

private:
    fs::path m_dir;
    dataset::LevelInfo m_level;
    dataset::ValueEncoding m_encoding;
    std::vector<std::string> m_stems;
    std::vector<dataset::ShellAnomalyOf> m_computed;
    std::vector<std::vector<char>> m_missing;
    std::map<int, std::shared_ptr<const dataset::StepVolume>> m_steps;
};

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

void writePathlines(const fs::path& outDir, const grid::SphericalGrid& grid, const std::vector<VariableSpec>& specs,
                    const std::vector<json>& stepJsons, const PreprocessOptions& options, PreprocessSummary& summary)
{
    const PathlineOptions& po = options.pathlines;
    checkPathlineOptions(po, specs);  // the field among the variables the dataset has in the end
    const fs::path root = outDir / "pathlines";
    const int nSteps = static_cast<int>(stepJsons.size());
    const json settings = pathlineSettings(po);
    // Rank 0 clears what a killed run left and finds the sets to do; under mpirun the others learn
    // the list from it and the sets are handed out to whichever rank is free (core/mpi.h).
    std::vector<int> todo;
    mpi::together([&] {
        if (!mpi::isRoot())
            return;
        if (!po.enabled) {
            fs::remove_all(root);
            return;
        }
        fs::create_directories(root);
        for (const auto& entry : fs::directory_iterator(root))
            if (entry.path().filename().string().starts_with("."))
                fs::remove_all(entry.path());
        for (int s = 0; s < nSteps; ++s) {
            const int endStep = std::min(s + po.steps, nSteps - 1);
            const fs::path dir = analysis::pathlineDir(outDir, s);
            if (fs::exists(dir / "lines.json")) {
                try {
                    const json old = parseJsonInput(readFile(dir / "lines.json"), (dir / "lines.json").string());
                    // A set of an older version lacks columns (seed persistence): redone.
                    if (old.at("settings") == settings && old.at("end_step").get<int>() == endStep &&
                        old.at("version").get<int>() == analysis::kPathlineSetVersion) {
                        ++summary.pathlineSetsSkipped;
                        continue;
                    }
                } catch (const std::exception&) {  // not JSON (raypc::Error) or not of the expected shape
                    // An unreadable set is redone below.
                }
            }
            todo.push_back(s);
        }
    });
    if (!po.enabled)
        return;
    if (mpi::distributed()) {
        const json found = json::parse(mpi::broadcast(json{{"todo", todo}, {"skipped", summary.pathlineSetsSkipped}}.dump()));
        todo = found.at("todo").get<std::vector<int>>();
        summary.pathlineSetsSkipped = found.at("skipped").get<int>();
    }
    std::vector<std::string> names, units;
    size_t field = 0, vx = 0, vy = 0, vz = 0;
    for (size_t v = 0; v < specs.size(); ++v) {
        names.push_back(specs[v].name);
        units.push_back(specs[v].units);
        field = specs[v].name == po.field ? v : field;
        vx = specs[v].name == "vx" ? v : vx;
        vy = specs[v].name == "vy" ? v : vy;
        vz = specs[v].name == "vz" ? v : vz;
    }
    std::optional<Progress> progress;
    if (!options.quiet && !todo.empty() && mpi::isRoot())
        progress.emplace("pathlines", static_cast<int64_t>(todo.size()), "steps");
    StepArrays arrays(outDir, grid, specs, stepJsons, options);
    int64_t reported = 0, written = 0, lines = 0;
    auto traceStep = [&](int s) {
        throwIfCancelled(options);
        const int endStep = std::min(s + po.steps, nSteps - 1);
        arrays.releaseBefore(s);
        analysis::FieldSeries series;
        series.grid = grid;
        for (int k = s; k <= endStep; ++k) {
            series.timesMyr.push_back(stepJsons[k].at("time_myr").get<double>());
            series.volumes.push_back(arrays.volume(k));
        }
        const std::span<const float> values(series.field(0, field), grid.cellCount());
        const auto all = analysis::findCriticalPoints(grid, values);
        const analysis::SeedSelection selection = analysis::selectSeeds(grid, values, all, po.filter);
        const auto& seeds = selection.seeds;
        const analysis::PathlineTracer tracer(series, vx, vy, vz, po.tracer);
        analysis::PathlineSet set = analysis::tracePathlines(series, tracer, seeds, 0, endStep - s, names, units);
        set.injectionStep = s;
        set.endStep = endStep;
        set.seedField = po.field;
        set.threshold = selection.threshold;
        for (const auto& p : all)
            ++set.criticalCounts[static_cast<size_t>(p.kind)];
        set.settingsJson = settings.dump();

        const fs::path finalDir = analysis::pathlineDir(outDir, s);
        const fs::path tmpDir = temporarySibling(finalDir);
        analysis::writePathlineSet(tmpDir, set);
        if (fs::exists(finalDir))
            fs::remove_all(finalDir);
        renameAtomic(tmpDir, finalDir);
        spdlog::debug("step {}: {} critical points, {} seeds above {:.4g}, {} pathline points", s, all.size(),
                      seeds.size(), set.threshold, set.pointCount());
        ++written;
        lines += int64_t(set.lineCount());
        if (options.onProgress)
            options.onProgress({"pathlines", summary.pathlineSetsSkipped + int(written), nSteps});
    };
    // Items are handed out in increasing order, so a rank's steps increase and releaseBefore holds.
    mpi::forEachDynamic(
        int64_t(todo.size()), [&](int64_t item) { traceStep(todo[size_t(item)]); },
        [&](int64_t handedOut) {
            if (progress)
                progress->advance(handedOut - std::exchange(reported, handedOut));
        });
    if (progress)
        progress->finish();
    std::array<int64_t, 2> counts{written, lines};
    mpi::sum(counts);
    summary.pathlineSetsWritten += int(counts[0]);
    summary.pathlineCount += size_t(counts[1]);
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
