#include "server/api_views.h"
#include "grid/variable_names.h"

#include "core/error.h"
#include "core/json_input.h"
#include "core/mpi.h"
#include "core/spherical.h"
#include "dataset/shell_anomaly.h"
#include "grid/coordinates.h"
#include "analysis/feature_csv.h"
#include "analysis/feature_run.h"
#include "analysis/feature_series.h"
#include "analysis/flux.h"
#include "analysis/pathline_storage.h"
#include "render/color_map.h"
#include "render/feature_paint.h"
#include "state/render_state.h"
#include "render/transfer_function.h"
#include "server/protocol.h"

#include <spdlog/spdlog.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <fstream>
#include <map>
#include <optional>
#include <sstream>

namespace raypc::server {

namespace fs = std::filesystem;
using nlohmann::json;

namespace {

constexpr const char* kPresetTitlesFile = "titles.tsv";

// The examples directory's titles.tsv: lines "file name without .json<TAB>short human title", `#`
// comments (examples/titles.tsv titles the contest presets, docs/tasks.md). A preset it does not
// list is titled by its name; a line without a tab is left out with a warning.
std::map<std::string, std::string> presetTitles(const fs::path& dir)
{
    std::map<std::string, std::string> titles;
    std::ifstream in(dir / kPresetTitlesFile);
    std::string line;
    for (int number = 1; std::getline(in, line); ++number) {
        if (line.empty() || line[0] == '#')
            continue;
        const size_t tab = line.find('\t');
        if (tab == std::string::npos || tab == 0 || tab + 1 == line.size()) {
            spdlog::warn("presets: {}:{}: expected a name, a tab and a title; left out",
                         (dir / kPresetTitlesFile).string(), number);
            continue;
        }
        titles[line.substr(0, tab)] = line.substr(tab + 1);
    }
    return titles;
}


}  // namespace

json presetsJson(const std::optional<fs::path>& dir, const dataset::Dataset* dataset)
{
    json out = json::array();
    if (!dir)
        return out;
    std::vector<fs::path> files;
    std::error_code ec;
    for (const auto& entry : fs::directory_iterator(*dir, ec))
        if (entry.is_regular_file() && entry.path().extension() == ".json" && entry.path().filename() != "demo.json")
            files.push_back(entry.path());
    std::sort(files.begin(), files.end());
    const auto titles = presetTitles(*dir);
    for (const auto& file : files) {
        std::ifstream in(file, std::ios::binary);
        std::ostringstream text;
        text << in.rdbuf();
        json state;
        try {
            state = parseJsonInput(text.str(), file.string());
        } catch (const Error& e) {
            spdlog::warn("presets: {}, left out", e.what());
            continue;
        }
        const std::string name = file.stem().string();
        std::string title = name;
        if (const auto it = titles.find(name); it != titles.end())
            title = it->second;
        else
            std::replace(title.begin(), title.end(), '-', ' ');
        json entry = {{"name", name}, {"title", title}, {"state", state}};
        if (dataset) {
            json applied = state;
            if (applied.is_object() && applied.contains("step") && applied["step"].is_number_integer())
                applied["step"] = std::min<int64_t>(applied["step"].get<int64_t>(), int64_t(dataset->steps().size()) - 1);
            try {
                render::resolveState(applied, *dataset, name + ".json");
            } catch (const Error& e) {
                entry["unavailable"] = fmt::format("not for this dataset: {}", e.what());
            }
        }
        out.push_back(std::move(entry));
    }
    return out;
}

json selectionStatsJson(const dataset::Dataset& dataset, StepCache& cache, std::span<const analysis::RangeFilter> filters, int level,
                        int profileStep, const std::atomic<bool>* cancel, SelectionCache* selections, bool allProfiles,
                        int* computed)
{
    dataset.checkLevel(level);
    dataset.checkStep(profileStep);
    const int nSteps = int(dataset.steps().size());
    const auto perStep =
        selections ? selections->overTime(dataset, cache, filters, level, 0, nSteps - 1, std::nullopt, cancel, computed)
                   : analysis::selectionOverTime(dataset, filters, level, 0, nSteps - 1, [&](int step, int l) {
                         if (cancel && *cancel)
                             fail("statistics cancelled at step {} of {} (the client went away or the server is stopping)",
                                  step, nSteps);
                         if (computed)
                             ++*computed;
                         return cache.getWithoutEvicting(step, l);
                     });
    json steps = json::array();
    for (const analysis::StepSelection& sel : perStep)
        steps.push_back({{"step", sel.step},
                         {"timeMyr", sel.timeMyr},
                         {"volumeKm3", sel.stats.volumeKm3},
                         {"fractionOfMantle", sel.stats.fractionOfMantle}});
    const grid::SphericalGrid& grid = dataset.levels()[size_t(level)].grid;
    // The selected and the whole volume per radius index, 0 beyond what the statistics hold.
    auto perRadius = [&](const analysis::SelectionStats& stats) {
        json selected = json::array(), shell = json::array();
        for (size_t iR = 0; iR < grid.nR(); ++iR) {
            selected.push_back(iR < stats.volumeByRadiusKm3.size() ? stats.volumeByRadiusKm3[iR] : 0.0);
            shell.push_back(iR < stats.shellVolumeByRadiusKm3.size() ? stats.shellVolumeByRadiusKm3[iR] : 0.0);
        }
        return std::pair{std::move(selected), std::move(shell)};
    };
    json radius = json::array(), depth = json::array();
    for (size_t iR = 0; iR < grid.nR(); ++iR) {
        radius.push_back(grid.rKm[iR]);
        depth.push_back(kSurfaceRadiusKm - grid.rKm[iR]);
    }
    auto [selected, shell] = perRadius(perStep[size_t(profileStep)].stats);
    json out = {{"level", level},
                {"steps", std::move(steps)},
                {"profile",
                 {{"step", profileStep},
                  {"radiusKm", std::move(radius)},
                  {"depthKm", std::move(depth)},
                  {"volumeKm3", std::move(selected)},
                  {"shellVolumeKm3", std::move(shell)}}}};
    if (allProfiles) {
        json profiles = json::array();
        for (const analysis::StepSelection& sel : perStep) {
            auto [v, s] = perRadius(sel.stats);
            profiles.push_back({{"step", sel.step}, {"volumeKm3", std::move(v)}, {"shellVolumeKm3", std::move(s)}});
        }
        out["profiles"] = std::move(profiles);
    }
    return out;
}

namespace {

// A number, or null when it is not finite (a mean of nothing).
json finiteOrNull(double v)
{
    return std::isfinite(v) ? json(v) : json(nullptr);
}

json featurePointJson(const analysis::FeatureSeries::Row& r, std::optional<size_t> radialVelocity)
{
    const analysis::Feature& f = r.feature;
    return {{"step", r.step},
            {"timeMyr", r.timeMyr},
            {"feature", f.id},
            {"volumeKm3", f.volumeKm3},
            {"percentOfMantle", 100.0 * f.fractionOfMantle},
            {"meanDepthKm", f.meanDepthKm},
            {"topDepthKm", f.topDepthKm},
            {"bottomDepthKm", f.bottomDepthKm},
            {"centroidLatDeg", f.centroidLatDeg},
            {"centroidLonDeg", f.centroidLonDeg},
            {"centroidDepthKm", f.centroidDepthKm},
            {"radialVelocityCmPerYr", radialVelocity ? finiteOrNull(f.variables[*radialVelocity].mean) : json(nullptr)},
            {"bandPercent", [&] {
                 json b = json::array();
                 for (const double x : f.bandFractions)
                     b.push_back(100.0 * x);
                 return b;
             }()}};
}

// The index of the variable `name`, if the dataset has it.
std::optional<size_t> variableIfAny(const dataset::Dataset& dataset, const std::string& name)
{
    const int i = dataset.variableIndex(name);
    return i >= 0 ? std::optional<size_t>(size_t(i)) : std::nullopt;
}

// The steps' features through the series: what each step has, its flux across the shells at
// the depths of featureBlockOptions and the features followed through the steps.
struct FeatureSteps {
    json steps = json::array();
    std::vector<std::vector<analysis::ShellFlux>> fluxes;  // [step][depth]
    analysis::FeatureSeries series;
};

// What each step of a features request at `level` adds besides its features, from the dataset (so
// the same on every rank): the links from the previous step's (throws raypc::Error without a
// velocity), and the flux across the shells at the options' depths inside the grid, with the radial
// velocity (and the density, for the mass flux) where the dataset has them.
analysis::FeatureBlockOptions featureBlockOptions(const dataset::Dataset& dataset, const analysis::FeatureOptions& options,
                                                  int level)
{
    analysis::FeatureBlockOptions block;
    block.velocity = analysis::velocityVariables(dataset, "features");
    block.radialVelocity = variableIfAny(dataset, varname::kRadialVelocity);
    block.density = variableIfAny(dataset, analysis::kDensityVariable);
    const grid::SphericalGrid& grid = dataset.levels()[size_t(level)].grid;
    for (const double d : options.bandDepthsKm)
        if (analysis::shellInsideGrid(grid, d))
            block.fluxDepthsKm.push_back(d);
    return block;
}

// A features request's filters, options and level as a job for the other ranks of a distributed
// server, and back (the numbers exact: JSON round-trips doubles); each rank finds the rest from the
// dataset (featureBlockOptions).
json featureJob(std::span<const analysis::RangeFilter> filters, const analysis::FeatureOptions& options, int level)
{
    json jsonFilters = json::array();
    for (const analysis::RangeFilter& f : filters) {
        json ranges = json::array();
        for (const dataset::ValueRange& r : f.ranges)
            ranges.push_back({r.min, r.max});
        jsonFilters.push_back({{"variable", f.variable},
                               {"coordinate", f.coordinate ? json(int(*f.coordinate)) : json(nullptr)},
                               {"ranges", std::move(ranges)}});
    }
    return {{"filters", std::move(jsonFilters)},
            {"minVolumeKm3", options.minVolumeKm3},
            {"bandDepthsKm", options.bandDepthsKm},
            {"bandHalfWidthKm", options.bandHalfWidthKm},
            {"level", level}};
}

struct FeatureJob {
    std::vector<analysis::RangeFilter> filters;
    analysis::FeatureOptions options;
    int level = 0;
    analysis::FeatureBlockOptions block;
};

FeatureJob parseFeatureJob(const json& job)
{
    FeatureJob out;
    for (const json& f : job.at("filters")) {
        analysis::RangeFilter& filter = out.filters.emplace_back();
        filter.variable = f.at("variable").get<int>();
        if (!f.at("coordinate").is_null())
            filter.coordinate = grid::Coordinate(f.at("coordinate").get<int>());
        for (const json& r : f.at("ranges"))
            filter.ranges.push_back({r.at(0).get<float>(), r.at(1).get<float>()});
    }
    out.options.minVolumeKm3 = job.at("minVolumeKm3").get<double>();
    out.options.bandDepthsKm = job.at("bandDepthsKm").get<std::vector<double>>();
    out.options.bandHalfWidthKm = job.at("bandHalfWidthKm").get<double>();
    out.level = job.at("level").get<int>();
    return out;
}

// The steps [first, last] of a features request, through `cache` without evicting.
std::optional<int> featureBlock(const dataset::Dataset& dataset, StepCache& cache, const FeatureJob& job, int first, int last,
                                const std::function<void(const analysis::FeatureBlockStep&)>& onStep,
                                const analysis::FeatureRunControl& control)
{
    return analysis::forEachBlockStep(
        dataset, first, last, [&](int step) { return cache.getWithoutEvicting(step, job.level); }, job.filters, job.options,
        job.block, onStep, control);
}

FeatureSteps featureSteps(const dataset::Dataset& dataset, StepCache& cache, std::span<const analysis::RangeFilter> filters,
                          const analysis::FeatureOptions& options, double minOverlapShare, int level,
                          const analysis::FeatureBlockOptions& block, const std::atomic<bool>* cancel,
                          const std::function<void(int done, int total)>& progress,
                          const std::function<void(int step, const HugePageVector<int32_t>&)>& labels,
                          const FeatureRanks* ranks)
{
    const int nSteps = int(dataset.steps().size());
    FeatureSteps out{json::array(), {}, analysis::FeatureSeries(dataset, minOverlapShare, "features")};
    const FeatureJob job{{filters.begin(), filters.end()}, options, level, block};
    const auto add = [&](const analysis::FeatureBlockStep& s) {
        out.steps.push_back({{"step", s.step},
                             {"timeMyr", dataset.steps()[size_t(s.step)].timeMyr},
                             {"features", s.features.features.size()}});
        if (block.radialVelocity && !block.fluxDepthsKm.empty())
            out.fluxes.push_back(s.fluxes);
        out.series.addLinked(s.step, s.features, s.links);
    };
    // With other ranks, this process takes the first block and they the others (forEachBlockStep
    // links each block's first step to the step before it); their steps follow its own in step order.
    const int nRanks = ranks ? ranks->ranks : 1;
    const mpi::Block mine = mpi::blockOf(nSteps, 0, nRanks);
    std::shared_future<std::vector<std::string>> others;
    if (nRanks > 1)
        others = ranks->shareOut(featureJob(filters, options, level));
    // The ranks' job reads `cancel` until they have all answered: however this block ends, wait.
    struct WaitForOthers {
        const std::shared_future<std::vector<std::string>>& others;
        ~WaitForOthers()
        {
            if (others.valid())
                others.wait();
        }
    } waitForOthers{others};
    analysis::FeatureRunControl control{cancel, {}};
    if (progress)  // with other ranks, this block's share scaled to the series (the blocks are found side by side)
        control.progress = [&](int done, int total) {
            const int scaled = int(int64_t(done) * nSteps / std::max(total, 1));
            progress(nRanks > 1 ? std::min(scaled, nSteps - 1) : scaled, nSteps);
        };
    const auto stopped = featureBlock(dataset, cache, job, int(mine.begin), int(mine.end) - 1, [&](const analysis::FeatureBlockStep& s) {
        add(s);
        if (labels)
            labels(s.step, s.features.labels);
    }, control);
    if (stopped)
        fail("features cancelled at step {} of {} (the client went away or the server is stopping)", *stopped, nSteps);
    if (nRanks > 1) {
        for (const std::string& block : others.get())  // rank order: step order; throws a rank's failure
            for (const analysis::FeatureBlockStep& s : analysis::unpackBlockSteps(block))
                add(s);
        if (progress)
            progress(nSteps, nSteps);
    }
    return out;
}

// Every track with its points (step order), its stalls at the options' depths and a summary for
// the table.
json tracksJson(const analysis::FeatureSeries& series, const analysis::FeatureOptions& options, int lastStep, analysis::StallMeasure stallBy,
                std::optional<size_t> radialVelocity)
{
    std::map<int, std::vector<const analysis::FeatureSeries::Row*>> rowsOf;
    for (const analysis::FeatureSeries::Row& r : series.rows())
        rowsOf[r.track].push_back(&r);
    std::map<int, json> stallsOf;
    for (const auto& [track, s] : series.stalls(options.bandDepthsKm, options.bandHalfWidthKm, lastStep, stallBy))
        stallsOf[track].push_back({{"depthKm", s.depthKm},
                                   {"firstStep", s.firstStep},
                                   {"lastStep", s.lastStep},
                                   {"durationMyr", s.durationMyr},
                                   {"meanRadialVelocityCmPerYr", finiteOrNull(s.meanRadialVelocityCmPerYr)},
                                   {"left", s.left}});
    json tracks = json::array();
    for (const auto& [track, rows] : rowsOf) {
        json points = json::array();
        double maxVolume = 0, depthSum = 0;
        for (const analysis::FeatureSeries::Row* r : rows) {
            points.push_back(featurePointJson(*r, radialVelocity));
            maxVolume = std::max(maxVolume, r->feature.volumeKm3);
            depthSum += r->feature.meanDepthKm;
        }
        tracks.push_back({{"track", track},
                          {"firstStep", rows.front()->step},
                          {"lastStep", rows.back()->step},
                          {"lifetimeMyr", rows.back()->timeMyr - rows.front()->timeMyr},
                          {"maxVolumeKm3", maxVolume},
                          {"meanDepthKm", depthSum / double(rows.size())},
                          {"points", std::move(points)},
                          {"stalls", stallsOf.count(track) ? std::move(stallsOf[track]) : json::array()}});
    }
    return tracks;
}

// The tracks' events in step order.
json eventsJson(const analysis::FeatureSeries& series, const dataset::Dataset& dataset)
{
    json events = json::array();
    for (const analysis::TrackEvent& e : series.events()) {
        const analysis::Feature& x = series.feature(e.step, e.feature);
        events.push_back({{"step", e.step},
                          {"timeMyr", dataset.steps()[size_t(e.step)].timeMyr},
                          {"kind", analysis::trackEventName(e.kind)},
                          {"track", e.track},
                          {"feature", e.feature},
                          {"others", e.others},
                          {"centroidLatDeg", x.centroidLatDeg},
                          {"centroidLonDeg", x.centroidLonDeg},
                          {"meanDepthKm", x.meanDepthKm}});
    }
    std::stable_sort(events.begin(), events.end(),
                     [](const json& a, const json& b) { return a["step"].get<int>() < b["step"].get<int>(); });
    return events;
}

// The flux across the shells at `fluxDepths` per step, with the avalanche steps of each shell
// (`sigmas`); the mass flux too where the dataset has a density.
json fluxJson(const dataset::Dataset& dataset, const std::vector<std::vector<analysis::ShellFlux>>& fluxes,
              const std::vector<double>& fluxDepths, double sigmas, bool density)
{
    json fluxSteps = json::array(), avalanches = json::array();
    for (size_t i = 0; i < fluxes.size(); ++i) {
        json down = json::array(), up = json::array(), selDown = json::array(), selUp = json::array(),
             selShare = json::array(), massDown = json::array(), massUp = json::array();
        for (const analysis::ShellFlux& f : fluxes[i]) {
            down.push_back(f.downKm3PerYr);
            up.push_back(f.upKm3PerYr);
            selDown.push_back(f.selectedDownKm3PerYr);
            selUp.push_back(f.selectedUpKm3PerYr);
            selShare.push_back(100.0 * f.selectedAreaKm2 / f.areaKm2);
            massDown.push_back(f.massDownKgPerYr);
            massUp.push_back(f.massUpKgPerYr);
        }
        json step = {{"step", int(i)},
                     {"timeMyr", dataset.steps()[i].timeMyr},
                     {"downKm3PerYr", std::move(down)},
                     {"upKm3PerYr", std::move(up)},
                     {"selectedDownKm3PerYr", std::move(selDown)},
                     {"selectedUpKm3PerYr", std::move(selUp)},
                     {"selectedPercentOfShell", std::move(selShare)}};
        if (density) {
            step["massDownKgPerYr"] = std::move(massDown);
            step["massUpKgPerYr"] = std::move(massUp);
        }
        fluxSteps.push_back(std::move(step));
    }
    const auto perShell = analysis::avalancheStepsPerShell(fluxes, sigmas);
    for (size_t d = 0; d < perShell.size(); ++d)
        for (const size_t i : perShell[d])
            avalanches.push_back({{"depthKm", fluxDepths[d]}, {"step", int(i)}});
    return {{"depthsKm", fluxDepths}, {"sigmas", sigmas}, {"steps", std::move(fluxSteps)},
            {"avalanches", std::move(avalanches)}};
}

}  // namespace

std::string featureBlockOfJob(const dataset::Dataset& dataset, StepCache& cache, const nlohmann::json& text, int rank,
                              int ranks, const std::atomic<bool>* cancel)
{
    FeatureJob job = parseFeatureJob(text);
    dataset.checkLevel(job.level);
    job.block = featureBlockOptions(dataset, job.options, job.level);
    const mpi::Block block = mpi::blockOf(int64_t(dataset.steps().size()), rank, ranks);
    std::string packed;
    const auto stopped = featureBlock(dataset, cache, job, int(block.begin), int(block.end) - 1,
                                      [&](const analysis::FeatureBlockStep& s) { analysis::packBlockStep(packed, s); },
                                      {cancel, {}});
    if (stopped)
        fail("features cancelled at step {}", *stopped);
    return packed;
}

json featureSeriesJson(const dataset::Dataset& dataset, StepCache& cache, std::span<const analysis::RangeFilter> filters,
                       const analysis::FeatureOptions& options, double minOverlapShare, analysis::StallMeasure stallBy, int level,
                       double sigmas, const std::atomic<bool>* cancel,
                       const std::function<void(int done, int total)>& progress,
                       const std::function<void(int step, const HugePageVector<int32_t>& labels)>& labels,
                       const FeatureRanks* ranks)
{
    dataset.checkLevel(level);
    if (filters.empty())
        fail("features: no selection: brush an axis first (the whole mantle would be one feature)");
    if (!(sigmas >= 0))
        fail("sigmas: {} is negative", sigmas);
    const int nSteps = int(dataset.steps().size());
    const analysis::FeatureBlockOptions block = featureBlockOptions(dataset, options, level);
    const std::optional<size_t> radialVelocity = block.radialVelocity, density = block.density;
    const std::vector<double>& fluxDepths = block.fluxDepthsKm;

    FeatureSteps run = featureSteps(dataset, cache, filters, options, minOverlapShare, level, block, cancel, progress,
                                    labels, ranks);
    const auto& fluxes = run.fluxes;
    // The tables of `raypc features --tracks/--events/--stalls` and `raypc flux`, written by the same
    // code (analysis/feature_csv.h), for the UI's CSV buttons.
    json csv = {{"tracks", analysis::trackCsv(run.series)},
                {"events", analysis::eventCsv(run.series, dataset)},
                {"stalls", analysis::stallCsv(run.series, options.bandDepthsKm, options.bandHalfWidthKm, nSteps - 1, stallBy)},
                {"flux", fluxes.empty() ? json(nullptr)
                                        : json(analysis::fluxCsv(dataset, 0, fluxes, fluxDepths,
                                                       analysis::avalancheStepsPerShell(fluxes, sigmas), false,
                                                       density.has_value()))}};
    return {{"level", level},
            {"minVolumeKm3", options.minVolumeKm3},
            {"depthsKm", options.bandDepthsKm},
            {"bandHalfWidthKm", options.bandHalfWidthKm},
            {"minOverlapShare", minOverlapShare},
            {"stallBy", analysis::stallMeasureName(stallBy)},
            {"steps", std::move(run.steps)},
            {"tracks", tracksJson(run.series, options, nSteps - 1, stallBy, radialVelocity)},
            {"events", eventsJson(run.series, dataset)},
            {"flux", fluxes.empty() ? json(nullptr) : fluxJson(dataset, fluxes, fluxDepths, sigmas, density.has_value())},
            {"csv", std::move(csv)}};
}

json persistenceDiagramJson(const grid::SphericalGrid& grid, const std::vector<analysis::PersistencePair>& pairs, int step,
                            const std::string& variable, const std::string& units, size_t top,
                            const analysis::PathlineSet* stored)
{
    const size_t nLon = grid.nLon(), nR = grid.nR();
    auto position = [&](size_t index) {
        return std::array<double, 3>{grid.latDeg[index / (nLon * nR)], grid.lonDeg[index % nLon],
                                     kSurfaceRadiusKm - grid.rKm[(index / nLon) % nR]};
    };
    json shown = json::array();
    std::array<size_t, 3> counts{};
    double range = 0;
    for (const auto& p : pairs) {
        ++counts[size_t(p.kind)];
        if (p.kind == analysis::PairKind::Global)
            range = p.persistence();
    }
    for (size_t i = 0; i < std::min(top, pairs.size()); ++i) {
        const analysis::PersistencePair& p = pairs[i];
        const auto b = position(p.birthIndex), e = position(p.extremumIndex());
        shown.push_back({{"kind", analysis::pairKindName(p.kind)},
                         {"birth", p.birth},
                         {"death", p.death},
                         {"persistence", p.persistence()},
                         {"birthLat", b[0]},
                         {"birthLon", b[1]},
                         {"birthDepthKm", b[2]},
                         {"lat", e[0]},
                         {"lon", e[1]},
                         {"depthKm", e[2]}});
    }
    const size_t rest = pairs.size() - shown.size();
    const double restMax = rest ? pairs[shown.size()].persistence() : 0.0;
    json storedJson = nullptr;
    if (stored) {
        const json settings = stored->settingsJson.empty() ? json() : json::parse(stored->settingsJson);
        const std::string rule = settings.is_object() && settings.contains("filter")
                                     ? settings["filter"].value("rule", std::string("persistence"))
                                     : std::string("persistence");
        storedJson = {{"threshold", stored->threshold},
                      {"rule", rule},
                      {"lines", stored->lineCount()},
                      {"seedPersistenceColumn", stored->column(columns::pathline::kSeedPersistence) >= 0}};
    }
    return {{"step", step},
            {"variable", variable},
            {"units", units},
            {"range", range},
            {"pairCount", pairs.size()},
            {"counts",
             {{analysis::pairKindName(analysis::PairKind::MinimumSaddle), counts[0]},
              {analysis::pairKindName(analysis::PairKind::SaddleMaximum), counts[1]},
              {analysis::pairKindName(analysis::PairKind::Global), counts[2]}}},
            {"pairs", std::move(shown)},
            {"rest", {{"count", rest}, {"maxPersistence", restMax}}},
            {"stored", std::move(storedJson)}};
}

std::string pathlineAttributesPayload(const PathlineCache::Window& sets, int step, int window)
{
    std::vector<std::string> columns, units;
    if (!sets.empty())
        columns = sets.front().columns, units = sets.front().units;
    size_t lines = 0;
    json setInfo = json::array();
    for (const auto& s : sets) {
        if (s.columns != columns)
            fail("pathlines: the set injected at step {} has other attribute columns than the first of the window",
                 s.injectionStep);
        lines += s.lineCount();
        setInfo.push_back({{"injectionStep", s.injectionStep},
                           {"injectionTimeMyr", s.injectionTimeMyr},
                           {"lines", s.lineCount()}});
    }
    const std::string header = json{{"step", step},
                                    {"window", window},
                                    {"lines", lines},
                                    {"columns", columns},
                                    {"units", units},
                                    {"sets", setInfo}}
                                   .dump(-1, ' ', false, json::error_handler_t::replace);
    std::string out(4, '\0');
    const uint32_t n = uint32_t(header.size());
    for (int i = 0; i < 4; ++i)
        out[size_t(i)] = char((n >> (8 * i)) & 0xff);
    out += header;
    for (const auto& s : sets)  // float32 little-endian (the host order on every supported target)
        out.append(reinterpret_cast<const char*>(s.attributes.data()), s.attributes.size() * sizeof(float));
    return out;
}

namespace {
json rangeJson(dataset::ValueRange r)
{
    return json::array({r.min, r.max});
}

// The dataset by its directory's last two path components ("demo-data/dataset",
// "run42/spherical.raypc"): what a user recognises, without the absolute path (the UI may be remote).
std::string datasetName(const dataset::Dataset& dataset)
{
    std::error_code ec;
    const fs::path dir = fs::weakly_canonical(dataset.dir(), ec);
    const fs::path& known = ec ? dataset.dir() : dir;
    return known.parent_path().filename().empty() ? known.filename().string()
                                                  : (known.parent_path().filename() / known.filename()).string();
}
}  // namespace

json pairJson(int index, const dataset::Dataset& first, const dataset::Dataset& second)
{
    json datasets = json::array();
    for (const dataset::Dataset* d : {&first, &second}) {
        json times = json::array();
        for (const auto& s : d->steps())
            times.push_back(s.timeMyr);
        datasets.push_back({{"name", datasetName(*d)}, {"timesMyr", times}});
    }
    return {{"index", index}, {"datasets", datasets}};
}

json infoJson(const dataset::Dataset& dataset, const ServerLimits& limits)
{
    json variables = json::array();
    for (const auto& v : dataset.variables()) {
        variables.push_back({{"name", v.name},
                             {"units", v.units},
                             {"derived", v.derived},
                             {"source", v.source},
                             {"min", v.global.range.min},
                             {"max", v.global.range.max},
                             {"mean", v.global.mean},
                             {"histogram", v.global.histogram},
                             // The colour range without a chosen one (render::defaultColorRange), for
                             // maps centred on zero and for the others.
                             {"defaultColorRange",
                              {{"centred", rangeJson(render::defaultColorRange(v.global, true))},
                               {"other", rangeJson(render::defaultColorRange(v.global, false))}}}});
        if (v.computed)
            variables.back()["computed"] = {{"from", dataset.variables().at(v.computed->base).name},
                                            {"kind", dataset::shellAnomalyKindName(v.computed->kind)}};
    }
    json coordinates = json::array();
    for (const auto& c : grid::coordinateInfos()) {
        const grid::CoordinateRange r = grid::coordinateRange(dataset.levels().front().grid, c.id);
        coordinates.push_back({{"name", c.name}, {"units", c.units}, {"min", r.min}, {"max", r.max}});
    }
    json steps = json::array();
    for (const auto& s : dataset.steps())
        steps.push_back({{"index", s.index}, {"timeMyr", s.timeMyr}, {"source", s.source}});
    json levels = json::array();
    for (size_t l = 0; l < dataset.levels().size(); ++l) {
        const auto& lg = dataset.levels()[l].grid;
        levels.push_back({{"level", l}, {"nLat", lg.nLat()}, {"nR", lg.nR()}, {"nLon", lg.nLon()}});
    }
    // The sample's shape without reading it: coordinates then variables.
    json columns = json::array(), units = json::array();
    for (const auto& c : grid::coordinateInfos())
        columns.push_back(c.name), units.push_back(c.units);
    for (const auto& v : dataset.variables())
        columns.push_back(v.name), units.push_back(v.units);
    const dataset::SampleTable sample = dataset.loadSample(0);
    json maps = json::array();
    for (const auto m : state::allColorMaps())
        maps.push_back(std::string(state::colorMapName(m)));
    json palette = json::array();
    for (int slot = 0; slot < render::kFeaturePaintSlots; ++slot) {
        const render::Rgb c = render::featurePaintColor(slot);
        palette.push_back({c.r, c.g, c.b});
    }
    const std::string name = datasetName(dataset);
    json info = {{"protocol", kProtocolVersion},
            {"name", name},
            {"variables", variables},
            {"coordinates", coordinates},
            {"steps", steps},
            {"levels", levels},
            {"sample", {{"rows", sample.rows}, {"columns", sample.columns}, {"units", sample.units}}},
            {"colorMaps", maps},
            {"featurePalette", palette},
            {"defaultState", state::toJson(render::defaultState(dataset))},
            // What POST /api/screenshot takes (checkScreenshotLimits), so that the UI states it.
            {"limits",
             {{"screenshotPixels", limits.maxScreenshotPixels},
              {"screenshotPasses", limits.maxScreenshotPasses},
              {"screenshotPixelPasses", limits.maxScreenshotPixelPasses}}}};
    // Why there are no pathlines, for the UI's Pathlines panel (the manifest's word).
    if (!std::filesystem::exists(analysis::pathlineDir(dataset.dir(), 0) / "lines.json"))
        info["noPathlines"] = analysis::noPathlinesReason(dataset.dir());
    return info;
}

// ---------------------------------------------------------------------------------------------
// The route handlers.

}  // namespace raypc::server
