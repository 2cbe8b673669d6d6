#include "server/dataset_api.h"
#include "grid/variable_names.h"

#include "analysis/feature_csv.h"

#include "core/clock.h"
#include "core/error.h"
#include "core/install_paths.h"
#include "core/json_input.h"
#include "core/spherical.h"
#include "analysis/feature_csv.h"
#include "analysis/probe.h"
#include "analysis/shell_compare.h"
#include "grid/regrid.h"
#include "render/color_map.h"
#include "render/pair_state.h"
#include "render/pathline_scene.h"
#include "render/reference_geometry.h"
#include "render/slice_view.h"
#include "render/state_renderer.h"
#include "render/time_depth_view.h"
#include "render/volume_renderer.h"
#include "server/access.h"
#include "server/image_codec.h"
#include "server/protocol.h"
#include "server/rank_pool.h"
#include "server/render_session.h"

#include <spdlog/spdlog.h>

#include <algorithm>
#include <array>
#include <chrono>
#include <cmath>
#include <cstdlib>
#include <cstring>
#include <fstream>
#include <map>
#include <sstream>
#include <type_traits>

namespace raypc::server {

namespace fs = std::filesystem;
using nlohmann::json;

namespace {

// A query parameter as an integer or a finite number; throws raypc::Error naming it when missing or
// malformed.
template <class T>
T parseParameter(std::string_view query, const char* name)
{
    const auto text = queryParameter(query, name);
    if (!text)
        fail("missing parameter '{}'", name);
    try {
        size_t used = 0;
        const T v = std::is_integral_v<T> ? T(std::stoi(*text, &used)) : T(std::stod(*text, &used));
        if (used == text->size() && std::isfinite(double(v)))
            return v;
    } catch (const std::exception&) {
    }
    fail("{}: expected {}, found '{}'", name, std::is_integral_v<T> ? "an integer" : "a finite number", text->substr(0, 40));
}
int parseIntParameter(std::string_view query, const char* name) { return parseParameter<int>(query, name); }
double parseNumberParameter(std::string_view query, const char* name) { return parseParameter<double>(query, name); }

int checkedStep(const dataset::Dataset& dataset, std::string_view query)
{
    const int step = parseIntParameter(query, "step");
    dataset.checkStep(step);
    return step;
}

json parseBody(std::string_view body) { return parseJsonInput(body, "body"); }

// The body's state resolved against the request's dataset: a pair's second takes the first's state
// as its sessions do (render::secondOfPair).
render::ResolvedState resolveBody(const ApiContext& api, std::string_view body)
{
    if (!api.pairFirst)
        return render::resolveState(parseBody(body), *api.dataset);
    render::PairedState paired = render::secondOfPair(state::parseRenderState(parseBody(body)), *api.pairFirst, *api.dataset);
    return render::resolveState(std::move(paired.state), *api.dataset);
}

ApiAnswer jsonAnswer(const json& j)
{
    return {j.dump(-1, ' ', false, json::error_handler_t::replace), "application/json"};
}

ApiAnswer info(const ApiContext& api, const ApiRequest&)
{
    return {api.infoJson, "application/json"};
}

ApiAnswer progress(const ApiContext& api, const ApiRequest&)
{
    return jsonAnswer(api.series ? api.series->toJson() : json{{"state", "complete"}});
}

ApiAnswer histogram(const ApiContext& api, const ApiRequest& request)
{
    const dataset::Dataset& dataset = *api.dataset;
    const int step = checkedStep(dataset, request.query);
    const auto name = queryParameter(request.query, "var");
    if (!name)
        fail("missing parameter 'var'");
    const int var = dataset.variableIndex(*name);
    if (var < 0)
        fail("var: unknown variable '{}'", name->substr(0, 80));
    const dataset::VariableStats& s = dataset.steps()[size_t(step)].stats[size_t(var)];
    const auto& v = dataset.variables()[size_t(var)];
    return jsonAnswer(
        {{"name", v.name}, {"units", v.units}, {"min", s.range.min}, {"max", s.range.max}, {"histogram", s.histogram}});
}

ApiAnswer sample(const ApiContext& api, const ApiRequest& request)
{
    const int step = checkedStep(*api.dataset, request.query);
    dataset::SampleColumns which = dataset::SampleColumns::All;
    if (const auto columns = queryParameter(request.query, "columns")) {
        if (*columns == "variables")
            which = dataset::SampleColumns::Variables;
        else if (*columns != "all")
            fail("columns: expected 'all' or 'variables', found '{}'", columns->substr(0, 40));
    }
    const dataset::SampleTable t = api.dataset->loadSample(step, which);
    return {std::string(reinterpret_cast<const char*>(t.values.data()), t.values.size() * sizeof(float)),
            "application/octet-stream"};
}

ApiAnswer selection(const ApiContext& api, const ApiRequest& request)
{
    const render::ResolvedState resolved = resolveBody(api, request.body);
    const int step = resolved.state.step;
    const auto& filters = resolved.params.brushes;
    analysis::SelectionStats s;
    if (api.selections) {
        const dataset::Dataset& dataset = *api.dataset;
        s = api.selections->overTime(dataset, *api.cache, filters, 0, step, step)[0].stats;
    } else {
        s = analysis::selectedVolume(*api.cache->get(step, 0), filters);
    }
    json answer{{"fractionOfMantle", s.fractionOfMantle}, {"volumeKm3", s.volumeKm3}, {"step", step}};
    // An empty selection says why: what each brushed axis selects alone and what the others select
    // without it (a brush that selects nothing alone, or whose removal selects something, is the one
    // that excluded everything). Only then: 2 passes per brushed axis.
    if (s.volumeKm3 == 0 && !filters.empty()) {
        const auto volume = api.cache->get(step, 0);
        const auto names = analysis::groupRanges(resolved.state.brushes);
        json axes = json::array();
        for (size_t i = 0; i < filters.size() && i < names.size(); ++i) {
            std::vector<analysis::RangeFilter> others;
            for (size_t j = 0; j < filters.size(); ++j)
                if (j != i)
                    others.push_back(filters[j]);
            const double alone = analysis::selectedVolume(*volume, std::span(&filters[i], 1)).fractionOfMantle;
            const double withoutIt = others.empty() ? 1.0 : analysis::selectedVolume(*volume, others).fractionOfMantle;
            axes.push_back({{"name", names[i].name}, {"alone", alone}, {"withoutIt", withoutIt}});
        }
        answer["empty"] = std::move(axes);
    }
    return jsonAnswer(answer);
}

// The bounds of limits.h, checked before anything is allocated.
void checkScreenshotLimits(const state::RenderState& state, const ServerLimits& limits)
{
    // A stereo pair renders two eyes.
    const render::StereoLayout layout = render::stereoLayout(state.stereo.mode, state.width, state.height);
    const int64_t pixels = layout.renderedPixels();
    const int passes = std::max(1, state.passes);
    if (pixels > limits.maxScreenshotPixels)
        fail("screenshot: image {}x{}{} is over the limit of {} pixels (e.g. 4096x4096)", state.width, state.height,
             layout.eyes == 2 ? " (stereo: two eyes)" : "", limits.maxScreenshotPixels);
    if (passes > limits.maxScreenshotPasses)
        fail("screenshot: passes {} is over the limit of {}", passes, limits.maxScreenshotPasses);
    if (pixels * passes > limits.maxScreenshotPixelPasses)
        fail("screenshot: {}x{} at {} passes is over the limit of {} pixel-passes (e.g. 1024x1024 at 256 passes, "
             "4096x4096 at 16); use fewer passes or a smaller image",
             state.width, state.height, passes, limits.maxScreenshotPixelPasses);
}

// A state with `pair` on a server of a pair: both datasets' halves (render::pairHalves), each drawn
// as a screenshot is, side by side in one PNG (what `raypc render --state` writes).
ApiAnswer pairScreenshot(const ApiContext& api, const render::ResolvedState& resolved, const std::atomic<bool>* cancel)
{
    if (resolved.state.stereo.enabled())
        fail("screenshot: a pair is drawn as two views side by side; not in stereo");
    const ApiContext& second = *api.pairSecond;
    const auto start = std::chrono::steady_clock::now();
    const render::PairHalves halves = render::pairHalves(resolved.state, *api.dataset, *second.dataset);
    auto draw = [&](const ApiContext& side, const state::RenderState& state) {
        const render::ResolvedState view = render::resolveState(state, *side.dataset);
        render::StateRenderer renderer(side.dataset, cacheSources(side.cache, side.pathlines));
        const auto still = renderer.renderStill(view, 0, cancel);
        if (still.frames.back().passes() < std::max(1, view.state.passes))
            fail("screenshot cancelled (the client went away or the server is stopping)");
        return renderer.picture(still.frames, view, true);
    };
    const render::ImageRgba8 picture = render::sideBySide(draw(api, halves.left), draw(second, halves.right.state));
    std::string png = encodePng(picture.pixels, picture.width, picture.height);
    spdlog::info("screenshot of the pair: steps {} and {} {}x{} in {:.0f} ms", halves.left.step,
                 halves.right.state.step, picture.width, picture.height, millisecondsSince(start));
    return {std::move(png), "image/png"};
}

ApiAnswer screenshot(const ApiContext& api, const ApiRequest& request)
{
    const render::ResolvedState resolved = resolveBody(api, request.body);
    checkScreenshotLimits(resolved.state, api.limits);
    if (resolved.state.pair && api.pairSecond)
        return pairScreenshot(api, resolved, request.cancel);
    const auto start = std::chrono::steady_clock::now();
    render::StateRenderer renderer(api.dataset, cacheSources(api.cache, api.pathlines, api.featureLabels));
    const auto still = renderer.renderStill(resolved, 0, request.cancel);
    const int done = still.frames.back().passes();  // the last view's: a stereo pass renders the left eye first
    if (done < std::max(1, resolved.state.passes))
        fail("screenshot cancelled after {} of {} passes (the client went away or the server is stopping)", done,
             std::max(1, resolved.state.passes));
    const render::ImageRgba8 picture = renderer.picture(still.frames, resolved, true);
    std::string png = encodePng(picture.pixels, picture.width, picture.height);
    spdlog::info("screenshot: step {} {}x{} {} passes at level 0 in {:.0f} ms", resolved.state.step, picture.width,
                 picture.height, done, millisecondsSince(start));
    return {std::move(png), "image/png"};
}

// POST /api/slice?view=map|section with a state: the state's map or section picture
// (render/slice_view.h) at its size, and where the picture puts the sphere or the section, so that
// the UI finds the point under the pointer: [u32 little-endian n][n bytes of JSON][PNG].
ApiAnswer slice(const ApiContext& api, const ApiRequest& request)
{
    const auto view = queryParameter(request.query, "view");
    if (!view || (*view != "map" && *view != "section"))
        fail("view: expected 'map' or 'section', found '{}'", view ? view->substr(0, 40) : "nothing");
    const render::ResolvedState resolved = resolveBody(api, request.body);
    const state::RenderState& state = resolved.state;
    if (int64_t(state.width) * state.height > api.limits.maxScreenshotPixels)
        fail("slice: image {}x{} is over the limit of {} pixels", state.width, state.height, api.limits.maxScreenshotPixels);
    const auto start = std::chrono::steady_clock::now();
    const bool map = *view == "map";
    render::StateRenderer renderer(api.dataset, cacheSources(api.cache, api.pathlines, api.featureLabels));
    const render::ImageRgba8 picture =
        renderer.slicePicture(resolved, map ? render::StateRenderer::Slice::Map : render::StateRenderer::Slice::Section);
    json header{{"view", *view}, {"width", picture.width}, {"height", picture.height}, {"step", state.step}};
    if (map) {
        const render::MapFrame frame = render::mapFrameOf(state);
        header["projection"] = std::string(state::mapProjectionName(state.map.projection));
        header["centralMeridianDeg"] = state.map.centralMeridianDeg;
        header["centralLatitudeDeg"] = state.map.projection == render::MapProjection::Orthographic ? state.map.centralLatitudeDeg : 0.0f;
        header["scale"] = frame.scale();
        header["centre"] = frame.centrePx();
        header["depthKm"] = state.map.depthKm;
    } else {
        const render::SectionLayout l = render::sectionLayoutOf(state, api.cache->get(state.step, state.level.value_or(0))->grid());
        header["plot"] = {{"left", l.left}, {"right", l.right}, {"top", l.top}, {"bottom", l.bottom}};
        header["depthSpanKm"] = l.depthSpanKm;
        header["from"] = {state.section.from.latDeg, state.section.from.lonDeg};
        header["to"] = {state.section.to.latDeg, state.section.to.lonDeg};
        const render::GreatCircle circle(state.section.from, state.section.to);
        header["azimuthDeg"] = circle.azimuthDeg();
        header["lengthDeg"] = circle.lengthDeg();
        header["lengthKm"] = circle.lengthKm();
    }
    const std::string text = header.dump();
    const std::string png = encodePng(picture.pixels, picture.width, picture.height, 1);
    std::string body(4, '\0');
    const uint32_t n = uint32_t(text.size());
    for (int i = 0; i < 4; ++i)
        body[size_t(i)] = char((n >> (8 * i)) & 0xff);
    body += text;
    body += png;
    spdlog::debug("slice: {} of step {} {}x{} in {:.0f} ms", *view, state.step, picture.width, picture.height,
                  millisecondsSince(start));
    return {std::move(body), "application/octet-stream"};
}

// GET /api/probe?step=S&lat=A&lon=B&depthKm=D[&var=NAME][&level=L]: the values at a point (analysis/probe.h).
ApiAnswer probe(const ApiContext& api, const ApiRequest& request)
{
    const dataset::Dataset& dataset = *api.dataset;
    const int step = checkedStep(dataset, request.query);
    const int level = queryParameter(request.query, "level") ? parseIntParameter(request.query, "level") : 0;
    dataset.checkLevel(level, "level");
    const double lat = parseNumberParameter(request.query, "lat"), lon = parseNumberParameter(request.query, "lon");
    const double depth = parseNumberParameter(request.query, "depthKm");
    if (!(lat >= -90 && lat <= 90))
        fail("lat: {} is outside [-90, 90] degrees", lat);
    const auto volume = api.cache->get(step, level);
    const double top = kSurfaceRadiusKm - volume->grid().rKm.back(), bottom = kSurfaceRadiusKm - volume->grid().rKm.front();
    if (!(depth >= top - 1e-6 && depth <= bottom + 1e-6))
        fail("depthKm: {} is outside the grid's depths, {:g} to {:g} km", depth, top, bottom);
    std::string var;
    if (const auto name = queryParameter(request.query, "var")) {
        var = *name;
        if (dataset.variableIndex(var) < 0)
            fail("var: unknown variable '{}'", var.substr(0, 80));
    }
    return jsonAnswer(analysis::probeJson(dataset, *volume, step, level, lat, lon,
                                std::clamp(kSurfaceRadiusKm - depth, volume->grid().rKm.front(), volume->grid().rKm.back()), var));
}

ApiAnswer presets(const ApiContext& api, const ApiRequest&)
{
    return jsonAnswer(presetsJson(api.examples, api.dataset.get()));
}

ApiAnswer stats(const ApiContext& api, const ApiRequest& request)
{
    const dataset::Dataset& dataset = *api.dataset;
    // Level 1 by default (quick); 0 is exact on the full grid.
    const int levels = int(dataset.levels().size());
    const int level =
        queryParameter(request.query, "level") ? parseIntParameter(request.query, "level") : std::min(1, levels - 1);
    dataset.checkLevel(level);
    bool allProfiles = false;
    if (const auto profiles = queryParameter(request.query, "profiles")) {
        if (*profiles != "all")
            fail("profiles: expected 'all' (every step's depth profile), found '{}'", profiles->substr(0, 40));
        allProfiles = true;
    }
    const render::ResolvedState resolved = resolveBody(api, request.body);
    const auto start = std::chrono::steady_clock::now();
    int computed = 0;
    json result = selectionStatsJson(dataset, *api.cache, resolved.params.brushes, level, resolved.state.step,
                                     request.cancel, api.selections, allProfiles, &computed);
    spdlog::info("stats: {} steps ({} computed) at level {} in {:.0f} ms", result["steps"].size(), computed, level,
                 millisecondsSince(start));
    return {result.dump(), "application/json", computed};
}

// The level of a features or time–depth request: ?level=, else the state's features.level.
int featureLevel(const dataset::Dataset& dataset, const ApiRequest& request, const state::RenderState& state)
{
    const int level = queryParameter(request.query, "level") ? parseIntParameter(request.query, "level")
                                                             : state.features.level;
    dataset.checkLevel(level);
    return level;
}

// The features of the state's selection through the series, with the state's feature settings.
ApiAnswer features(const ApiContext& api, const ApiRequest& request)
{
    const dataset::Dataset& dataset = *api.dataset;
    const render::ResolvedState resolved = resolveBody(api, request.body);
    const state::FeatureSettings& settings = resolved.state.features;
    const int level = featureLevel(dataset, request, resolved.state);
    const double sigmas = queryParameter(request.query, "sigmas") ? parseNumberParameter(request.query, "sigmas") : 2.0;
    const analysis::FeatureOptions options = state::featureOptions(settings);
    const std::optional<std::string> job = queryParameter(request.query, "job");
    if (job)
        JobProgress::checkId(*job);
    const auto start = std::chrono::steady_clock::now();
    std::function<void(int, int)> progress;
    if (job && api.jobs)
        progress = [&](int done, int total) { api.jobs->running(*job, done, total); };
    const int nSteps = int(dataset.steps().size());
    // The labels of the state's step are kept for its painting (what the UI shows next). A step
    // another rank found has none here: the painting extracts them (FeatureLabelsCache::get).
    std::function<void(int, const HugePageVector<int32_t>&)> keepLabels;
    if (api.featureLabels)
        keepLabels = [&](int step, const HugePageVector<int32_t>& labels) {
            if (step == resolved.state.step)
                api.featureLabels->put(step, level, resolved.params.brushes, options,
                                       std::make_shared<const HugePageVector<int32_t>>(labels));
        };
    // A distributed server shares the steps out over its ranks.
    std::optional<FeatureRanks> ranks;
    if (api.ranks)
        ranks = FeatureRanks{api.ranks->ranks(), [&](nlohmann::json job) { return api.ranks->shareOut(std::move(job), request.cancel); }};
    auto compute = [&] {
        return jsonAnswer(featureSeriesJson(dataset, *api.cache, resolved.params.brushes, options, settings.minOverlapShare,
                                            settings.stallBy, level, sigmas, request.cancel, progress, keepLabels,
                                            ranks ? &*ranks : nullptr))
            .body;
    };
    std::shared_ptr<const std::string> body;
    int how = FeatureSeriesCache::kMade;
    try {
        if (!api.featureSeries) {
            body = std::make_shared<const std::string>(compute());
        } else {
            const std::string key = featureSeriesKey(resolved.params.brushes, options, settings.minOverlapShare,
                                                     settings.stallBy, level, sigmas);
            try {
                body = api.featureSeries->get(key, compute, &how);
            } catch (const Error&) {
                // Another request's computation we waited for failed: when it was cancelled (its
                // client went away) and this one was not, compute for this one.
                if (how != FeatureSeriesCache::kShared || (request.cancel && *request.cancel))
                    throw;
                body = api.featureSeries->get(key, compute, &how);
            }
        }
    } catch (...) {
        if (progress)
            api.jobs->ended(*job, false);
        throw;
    }
    if (progress) {
        if (how != FeatureSeriesCache::kMade)
            progress(nSteps, nSteps);
        api.jobs->ended(*job, true);
    }
    spdlog::info("features: {} steps at level {} {} in {:.0f} ms", nSteps, level,
                 how != FeatureSeriesCache::kMade ? "kept"
                 : ranks                          ? fmt::format("computed on {} ranks", ranks->ranks)
                                                  : "computed",
                 millisecondsSince(start));
    return {*body, "application/json", how == FeatureSeriesCache::kMade ? nSteps : 0};
}

// The time–depth picture (PNG) of the state's selection over the series: ?of=share (default),
// selected-mean or shell-mean of ?var=NAME; ?width, ?height (default 960 x 540); the state's
// feature depths marked.
ApiAnswer timeDepth(const ApiContext& api, const ApiRequest& request)
{
    const dataset::Dataset& dataset = *api.dataset;
    const render::ResolvedState resolved = resolveBody(api, request.body);
    const int level = featureLevel(dataset, request, resolved.state);
    const auto ofText = queryParameter(request.query, "of");
    const render::TimeDepthOf of = render::parseTimeDepthOf(ofText ? std::string(*ofText) : "share", "of");
    std::optional<size_t> mean;
    if (const auto var = queryParameter(request.query, "var")) {
        const int index = dataset.variableIndex(*var);
        if (index < 0)
            fail("var: unknown variable '{}'", var->substr(0, 80));
        mean = size_t(index);
    } else if (of != render::TimeDepthOf::Share) {
        fail("of={}: needs var=NAME (the variable whose mean it shows)", *ofText);
    }
    const auto format = queryParameter(request.query, "format");
    if (format && *format != "png" && *format != "csv")
        fail("format: '{}', expected png or csv", format->substr(0, 40));
    const bool csv = format && *format == "csv";
    const int width = queryParameter(request.query, "width") ? parseIntParameter(request.query, "width") : 960;
    const int height = queryParameter(request.query, "height") ? parseIntParameter(request.query, "height") : 540;
    if (int64_t(width) * height > api.limits.maxScreenshotPixels)
        fail("time-depth: image {}x{} is over the limit of {} pixels", width, height, api.limits.maxScreenshotPixels);
    render::checkTimeDepthPictureSize(width, height);
    const int last = int(dataset.steps().size()) - 1;
    const std::vector<analysis::StepSelection> selections =
        api.selections ? api.selections->overTime(dataset, *api.cache, resolved.params.brushes, level, 0, last, mean, request.cancel)
                       : analysis::selectionOverTime(
                             dataset, resolved.params.brushes, level, 0, last,
                             [&](int step, int l) {
                                 if (request.cancel && *request.cancel)
                                     fail("time-depth cancelled at step {} (the client went away or the server is stopping)", step);
                                 return api.cache->getWithoutEvicting(step, l);
                             },
                             {}, mean);
    if (csv)  // the values behind the picture: `raypc stats --profile [--profile-var]`'s table
        return {analysis::profileCsvHeader(mean ? &dataset.variables()[*mean] : nullptr) +
                    analysis::profileCsvRows(selections, dataset.levels()[size_t(level)].grid),
                "text/csv"};
    std::vector<float> values;
    render::appendTimeDepthValues(selections, of, values);
    render::TimeDepthInputs in = render::timeDepthInputs(dataset, 0, last, level, std::move(values), of,
                                                         mean ? &dataset.variables()[*mean] : nullptr,
                                                         resolved.params.brushes.size());
    in.width = width;
    in.height = height;
    in.background = resolved.state.background;
    in.marks = resolved.state.reference.shells;
    in.marks.visible = true;
    in.marks.depthsKm = resolved.state.features.depthsKm;
    const render::ImageRgba8 picture = render::timeDepthPicture(in);
    return {encodePng(picture.pixels, picture.width, picture.height, 1), "image/png"};
}

// The spherical-harmonic power per degree of the state's colour variable (?var=NAME instead) at its
// step on the shell nearest the map's depth (?depthKm= instead), to degree ?lmax= (default the grid's
// largest, at most 60): what the UI plots for the shown depth (docs/compare.md, "Spectra"). A grid or a
// shell the transform refuses (regional, missing values) is an error naming the reason.
ApiAnswer spectrum(const ApiContext& api, const ApiRequest& request)
{
    const dataset::Dataset& dataset = *api.dataset;
    const render::ResolvedState resolved = resolveBody(api, request.body);
    std::string name = resolved.state.colorVariable.empty() ? dataset.variables().front().name : resolved.state.colorVariable;
    if (const auto var = queryParameter(request.query, "var"))
        name = *var;
    const int var = dataset.variableIndex(name);
    if (var < 0)
        fail("var: unknown variable '{}'", name.substr(0, 80));
    double depthKm = resolved.state.map.depthKm;
    if (queryParameter(request.query, "depthKm"))
        depthKm = parseNumberParameter(request.query, "depthKm");
    const grid::SphericalGrid& grid = dataset.levels().front().grid;
    const int lmax = queryParameter(request.query, "lmax") ? parseIntParameter(request.query, "lmax")
                                                           : analysis::defaultSpectrumDegree(grid);
    const size_t shell = analysis::nearestShell(grid, depthKm);
    const auto volume = api.cache->getWithoutEvicting(resolved.state.step, 0);
    const dataset::VariableInfo& v = dataset.variables()[size_t(var)];
    const std::vector<double> power = analysis::shellSpectrumAt(grid, volume->values(size_t(var)), shell, lmax, v.name);
    return jsonAnswer({{"variable", v.name},
                       {"units", v.units},
                       {"step", resolved.state.step},
                       {"depthKm", kSurfaceRadiusKm - grid.rKm[shell]},
                       {"radiusKm", grid.rKm[shell]},
                       {"lmax", lmax},
                       {"quadrature", analysis::quadratureName(analysis::quadratureOf(grid))},
                       {"power", power}});
}

// A pair's two datasets correlated shell by shell (docs/compare.md, "Correlation"): the state's
// colour variable (or `var`) of the first at the state's step against the same variable of the second
// at its matched step (render::secondOfPair), put on the first's grid (grid::regrid); `lmax` filters
// both first. Asked of the first dataset's endpoint; refused without a pair.
ApiAnswer correlate(const ApiContext& api, const ApiRequest& request)
{
    if (!api.pairSecond)
        fail("correlate: needs a pair of datasets (raypc serve A B) asked through the first (dataset 0)");
    const dataset::Dataset& first = *api.dataset;
    const dataset::Dataset& second = *api.pairSecond->dataset;
    const state::RenderState state = state::parseRenderState(parseBody(request.body));
    const render::ResolvedState resolved = render::resolveState(state, first);
    std::string name = resolved.state.colorVariable.empty() ? first.variables().front().name : resolved.state.colorVariable;
    if (const auto var = queryParameter(request.query, "var"))
        name = *var;
    const int varA = first.variableIndex(name), varB = second.variableIndex(name);
    if (varA < 0)
        fail("var: the first dataset has no variable '{}'", name.substr(0, 80));
    if (varB < 0)
        fail("var: the second dataset has no variable '{}' to correlate with the first's", name.substr(0, 80));
    analysis::CorrelationOptions options;
    if (queryParameter(request.query, "lmax"))
        options.lmax = parseIntParameter(request.query, "lmax");
    const int stepA = resolved.state.step;
    const int stepB = render::secondOfPair(state, first, second).state.step;
    const auto a = api.cache->getWithoutEvicting(stepA, 0);
    const auto b = api.pairSecond->cache->getWithoutEvicting(stepB, 0);
    const grid::SphericalGrid& gridA = first.levels().front().grid;
    const grid::SphericalGrid& gridB = second.levels().front().grid;
    if (grid::coveredFraction(gridB, gridA) == 0)
        fail("correlate: the second dataset's grid covers none of the first's");
    const std::vector<float> bOnA = grid::regrid(gridB, b->values(size_t(varB)), gridA);
    const auto rows = analysis::correlateShells(gridA, a->values(size_t(varA)), bOnA.data(), options, name);
    json out = json::array();
    for (const auto& r : rows)
        out.push_back({{"depthKm", r.depthKm}, {"correlation", r.correlation}, {"rmsA", r.rmsA}, {"rmsB", r.rmsB},
                       {"rmsRatio", r.rmsRatio}, {"areaFraction", r.areaFraction}, {"note", r.note}});
    return jsonAnswer({{"variable", name},
                       {"units", first.variables()[size_t(varA)].units},
                       {"steps", {stepA, stepB}},
                       {"lmax", options.lmax ? json(*options.lmax) : json(nullptr)},
                       {"shells", std::move(out)}});
}

ApiAnswer pathlines(const ApiContext& api, const ApiRequest& request)
{
    const int step = checkedStep(*api.dataset, request.query);
    const int window = queryParameter(request.query, "window") ? parseIntParameter(request.query, "window") : 10;
    analysis::checkPathlineWindow(window);  // before the cache is asked
    const auto sets = api.pathlines->get(step, window);
    return {pathlineAttributesPayload(*sets, step, window), "application/octet-stream"};
}

// The diagram of the seed field of the step's stored pathlines (else `var`, default the temperature
// anomaly): `top` pairs (default 500, at most 20000) and the stored seeds' threshold.
ApiAnswer persistence(const ApiContext& api, const ApiRequest& request)
{
    const dataset::Dataset& dataset = *api.dataset;
    const int step = checkedStep(dataset, request.query);
    int top = 500;
    if (queryParameter(request.query, "top")) {
        top = parseIntParameter(request.query, "top");
        if (top < 0 || top > 20000)
            fail("top: {} out of range 0..20000", top);
    }
    // The step's set read directly (one set, small), not through the pathline cache, whose few
    // entries hold the renderers' windows.
    std::optional<analysis::PathlineSet> set;
    if (fs::exists(analysis::pathlineDir(dataset.dir(), step) / "lines.json"))
        set = analysis::loadPathlineSet(dataset.dir(), step);
    const analysis::PathlineSet* stored = set ? &*set : nullptr;
    std::string name = stored ? stored->seedField : varname::anomalyToShow(dataset.variableNames());
    if (const auto var = queryParameter(request.query, "var"))
        name = *var;
    const int var = dataset.variableIndex(name);
    if (var < 0)
        fail("var: unknown variable '{}'", name.substr(0, 80));
    if (stored && stored->seedField != name)
        stored = nullptr;  // seeded on another variable: its threshold means nothing here
    if (!api.persistence)
        fail("this server has no persistence cache");
    const auto start = std::chrono::steady_clock::now();
    const auto pairs = api.persistence->get(step, var);
    const grid::SphericalGrid& grid = dataset.levels().front().grid;
    json result = persistenceDiagramJson(grid, *pairs, step, name, dataset.variables()[size_t(var)].units,
                                         size_t(top), stored);
    spdlog::debug("persistence: step {} '{}': {} pairs in {:.0f} ms", step, name, pairs->size(),
                  millisecondsSince(start));
    return jsonAnswer(result);
}

LinkedState& linkedState(const ApiContext& api)
{
    if (!api.link)
        fail("this server has no linked state");
    return *api.link;
}

// Where POST /api/features?job=ID is.
ApiAnswer jobProgress(const ApiContext& api, const ApiRequest& request)
{
    const std::optional<std::string> job = queryParameter(request.query, "job");
    if (!job)
        fail("job: missing (GET /api/job-progress?job=ID, the id given to POST /api/features?job=ID)");
    JobProgress::checkId(*job);
    if (!api.jobs)
        fail("job-progress: this server keeps no job progress");
    return jsonAnswer(api.jobs->toJson(*job));
}

ApiAnswer linkGet(const ApiContext& api, const ApiRequest&)
{
    return jsonAnswer(linkedState(api).toJson());
}

// A program sets the state the UI shows: checked as a WebSocket `state` message's state is (the
// same parser and resolver, the same messages), then pushed to every session.
ApiAnswer linkPost(const ApiContext& api, const ApiRequest& request)
{
    const json body = parseBody(request.body);
    if (!body.is_object() || !body.contains("state"))
        fail("body: expected {{\"state\": {{…state document…}}}}, found {}", jsonExcerpt(body));
    for (const auto& [key, value] : body.items())
        if (key != "state")
            fail("body: unknown field '{}', expected only 'state'", key.substr(0, 60));
    const json& state = body["state"];
    const render::ResolvedState resolved = render::resolveState(state, *api.dataset, "state");
    checkSessionImage(resolved.state);
    const LinkedState::Pushed pushed = linkedState(api).setFromApi(state);
    return jsonAnswer({{"version", pushed.version}, {"sessions", pushed.sessions}});
}

const Route kRoutes[] = {
    {HttpMethod::Get, "/api/info", Lane::Network, info, ""},
    {HttpMethod::Get, "/api/progress", Lane::Network, progress, "", false},
    {HttpMethod::Get, "/api/histogram", Lane::Network, histogram, "step,var"},
    {HttpMethod::Get, "/api/sample", Lane::Worker, sample, "step,columns"},
    {HttpMethod::Post, "/api/selection", Lane::Worker, selection, ""},
    {HttpMethod::Post, "/api/screenshot", Lane::Screenshot, screenshot, ""},
    {HttpMethod::Post, "/api/slice", Lane::Slice, slice, "view"},
    {HttpMethod::Get, "/api/probe", Lane::Worker, probe, "step,lat,lon,depthKm,var,level"},
    {HttpMethod::Get, "/api/presets", Lane::Worker, presets, ""},
    {HttpMethod::Post, "/api/stats", Lane::Statistics, stats, "level,profiles"},
    {HttpMethod::Post, "/api/features", Lane::Statistics, features, "level,sigmas,job"},
    {HttpMethod::Get, "/api/job-progress", Lane::Network, jobProgress, "job", false},
    {HttpMethod::Post, "/api/time-depth", Lane::Statistics, timeDepth, "level,of,var,format,width,height"},
    {HttpMethod::Post, "/api/spectrum", Lane::Statistics, spectrum, "var,depthKm,lmax"},
    {HttpMethod::Post, "/api/correlate", Lane::Statistics, correlate, "var,lmax", false},
    {HttpMethod::Get, "/api/pathlines", Lane::Worker, pathlines, "step,window"},
    {HttpMethod::Get, "/api/persistence", Lane::Worker, persistence, "step,top,var"},
    {HttpMethod::Get, "/api/link", Lane::Worker, linkGet, "", false},
    {HttpMethod::Post, "/api/link", Lane::Worker, linkPost, "", false},
};

}  // namespace

std::span<const Route> apiRoutes()
{
    return kRoutes;
}

void checkQueryParameters(const Route& route, std::string_view query)
{
    std::vector<std::string> seen;
    while (!query.empty()) {
        const size_t amp = query.find('&');
        const std::string_view pair = query.substr(0, amp);
        query.remove_prefix(amp == std::string_view::npos ? query.size() : amp + 1);
        if (pair.empty())
            continue;
        const std::string key = percentDecode(pair.substr(0, pair.find('=')), true).value_or(std::string(pair));
        const std::string shown = key.substr(0, 60);
        if (std::find(seen.begin(), seen.end(), key) != seen.end())
            fail("query: parameter '{}' is given twice", shown);
        seen.push_back(key);
        if (key == "token" || (key == "dataset" && route.perDataset))
            continue;
        bool known = false;
        for (std::string_view rest = route.parameters; !rest.empty() && !known;) {
            const size_t comma = rest.find(',');
            known = rest.substr(0, comma) == key;
            rest.remove_prefix(comma == std::string_view::npos ? rest.size() : comma + 1);
        }
        if (!known)
            fail("query: unknown parameter '{}' for {} ({})", shown, route.path,
                 route.parameters.empty() ? std::string("it takes none")
                                          : fmt::format("it takes {}", route.parameters));
    }
}

int datasetOfQuery(const Route* route, std::string_view query, int datasets)
{
    const auto text = queryParameter(query, "dataset");
    if (!text)
        return 0;
    const std::string where = route ? std::string(route->path) : std::string("/ws");
    const std::string serves = datasets == 1 ? std::string("this server serves one dataset, 0 (`raypc serve A B` serves a pair)")
                                             : fmt::format("this server serves a pair, 0 and 1");
    if (*text == "0")
        return 0;
    if (*text == "1" && datasets == 2)
        return 1;
    fail("dataset: {} for {}: expected an index of the datasets served; {}", text->substr(0, 40), where, serves);
}

}  // namespace raypc::server
