#include "render/state_renderer.h"
#include "grid/variable_names.h"

#include "core/clock.h"
#include "core/error.h"
#include "core/mpi.h"
#include "core/spherical.h"
#include "analysis/features.h"
#include "render/feature_paint.h"
#include "render/legend.h"
#include "render/reference_geometry.h"
#include "render/slice_view.h"

#include <fmt/format.h>
#include <fmt/ranges.h>
#include <spdlog/spdlog.h>
#include <tbb/task_arena.h>

#include <algorithm>
#include <chrono>
#include <cmath>

namespace raypc::render {
namespace {

// A variable as legends and titles name it: "temperature anomaly [K]".
std::string variableTitle(const dataset::VariableInfo& info)
{
    return info.units.empty() ? info.name : fmt::format("{} [{}]", info.name, displayUnits(info.units));
}

}  // namespace

float tubeRadiusKm(const state::RenderState& s)
{
    const double kmPerPixel =
        2.0 * s.camera.distanceKm * std::tan(s.camera.fovYDeg * M_PI / 360.0) / double(std::max(1, s.height));
    return std::max(s.pathlines.radiusKm, float(0.5 * s.pathlines.minWidthPx * kmPerPixel));
}

std::vector<float> averagedDepthKm(const ViewFrames& frames, int& width, int& height, const DepthTransform& eachView)
{
    RAYPC_CHECK(!frames.empty() && frames.size() <= 2);
    std::vector<float> views[2];
    for (size_t v = 0; v < frames.size(); ++v) {
        width = frames[v].width();
        height = frames[v].height();
        views[v] = frames[v].averagedDepthKm();
        if (eachView)
            views[v] = eachView(std::move(views[v]), width, height);
    }
    if (frames.size() == 1)
        return std::move(views[0]);
    const StereoLayout eyes{width, height, 2 * width, height, 1.0, 2};
    width = eyes.width;
    return sideBySide(eyes, views[0], views[1]);
}

StateRenderer::StateRenderer(std::shared_ptr<const dataset::Dataset> dataset, StateSources sources)
    : m_dataset(std::move(dataset)), m_sources(std::move(sources))
{
    if (!m_sources.volume)
        m_sources.volume = [d = m_dataset](int step, int level) { return d->load(step, level); };
    if (!m_sources.pathlines)
        m_sources.pathlines = [d = m_dataset](int step, int window) {
            return std::make_shared<const std::vector<analysis::PathlineSet>>(analysis::loadPathlineWindow(d->dir(), step, window));
        };
}

StateRenderer::~StateRenderer() = default;

VolumeRenderer& StateRenderer::rendererFor(int step, int level, int view)
{
    // Reload class: a new step drops every level's renderer of the old one.
    if (step != m_rendererStep) {
        m_renderers.clear();
        m_rendererStep = step;
    }
    auto& slot = m_renderers[{level, view}];
    if (!slot)
        slot = std::make_unique<VolumeRenderer>(volumeFor(step, level));
    return *slot;
}

bool StateRenderer::usePaint(const ResolvedState& resolved)
{
    const state::RenderState& state = resolved.state;
    std::string key;
    if (paintsFeatures(state)) {
        const state::FeatureSettings& f = state.features;
        key = fmt::format("{}|{}|{}|{}|{}", state.step, f.level, f.minVolumeKm3, f.colorById, fmt::join(f.highlight, ","));
        for (const analysis::RangeFilter& b : resolved.params.brushes) {
            key += fmt::format("|{}/{}", b.variable, b.coordinate ? int(*b.coordinate) : -1);
            for (const dataset::ValueRange& r : b.ranges)
                key += fmt::format(":{},{}", r.min, r.max);
        }
        m_paintFilters = resolved.params.brushes;
        m_paintSettings = f;
    }
    if (key != m_paintKey) {
        m_renderers.clear();  // their volumes hold the old paint
        m_paintLabels.reset();
        m_paintedVolumes.clear();
        m_paintKey = key;
    }
    return !key.empty();
}

std::shared_ptr<const dataset::StepVolume> StateRenderer::volumeFor(int step, int level)
{
    auto volume = m_sources.volume(step, level);
    if (m_paintKey.empty())
        return volume;
    if (const auto it = m_paintedVolumes.find(level); it != m_paintedVolumes.end())
        return it->second;
    const auto start = std::chrono::steady_clock::now();
    const int labelLevel = std::min(m_paintSettings.level, int(m_dataset->levels().size()) - 1);
    const grid::SphericalGrid& labelGrid = m_dataset->levels()[size_t(labelLevel)].grid;
    if (!m_paintLabels && m_sources.featureLabels) {
        m_paintLabels = m_sources.featureLabels(step, labelLevel, m_paintFilters, state::featureOptions(m_paintSettings));
    } else if (!m_paintLabels) {
        const auto labelVolume = labelLevel == level ? volume : m_sources.volume(step, labelLevel);
        m_paintLabels = std::make_shared<const HugePageVector<int32_t>>(
            analysis::extractFeatures(*labelVolume, m_paintFilters, state::featureOptions(m_paintSettings)).labels);
    }
    auto painted = dataset::StepVolume::withVariable(
        volume, featurePaintField(volume->grid(), labelGrid, *m_paintLabels, m_paintSettings));
    spdlog::debug("features painted on step {} level {} in {:.0f} ms", step, level, millisecondsSince(start));
    m_paintedVolumes[level] = painted;
    return painted;
}

std::shared_ptr<const PathlineScene> StateRenderer::pathlinesFor(const state::RenderState& state)
{
    if (!state.pathlines.visible)
        return nullptr;
    // Reload class: a new step or window loads that window and builds a new BVH.
    if (!m_scene || m_sceneStep != state.step || m_sceneWindow != state.pathlines.window) {
        std::shared_ptr<const std::vector<analysis::PathlineSet>> window;
        try {
            window = m_sources.pathlines(state.step, state.pathlines.window);
        } catch (const Error& e) {
            fail("pathlines: {}", e.what());
        }
        const auto start = std::chrono::steady_clock::now();
        m_scene.reset();
        m_scene = std::make_shared<PathlineScene>(window, state.pathlines.radiusKm);
        m_sceneStep = state.step;
        m_sceneWindow = state.pathlines.window;
        spdlog::debug("pathline scene of step {} window {}: {} lines in {:.0f} ms", state.step, state.pathlines.window,
                      m_scene->lineCount(),
                      millisecondsSince(start));
    }
    // Restart class: radius, style and the visibility mask (attribute filters, brushes).
    state::RenderState shown = state;
    shown.pathlines.radiusKm = tubeRadiusKm(state);
    m_scene->applyState(shown);
    return m_scene;
}

std::optional<LevelChoice> StateRenderer::knownChoice(const state::RenderState& state, const LevelPolicy& policy)
{
    if (policy.chosen)
        return policy.chosen;
    if (state.level)
        return LevelChoice{*state.level, 1};
    if (policy.samplesPerSecond > 0)
        return std::nullopt;
    return LevelChoice{0, 1};
}

LevelPolicy interactiveLevelPolicy(double measuredSamplesPerSecond, double overheadSeconds)
{
    LevelPolicy policy;
    policy.overheadSeconds = overheadSeconds;
    policy.samplesPerSecond =
        measuredSamplesPerSecond > 0 ? measuredSamplesPerSecond : 100e6 * tbb::this_task_arena::max_concurrency();
    policy.reduceResolution = measuredSamplesPerSecond > 0;
    return policy;
}

StateRenderer::Prepared StateRenderer::prepare(const ResolvedState& resolved, const LevelPolicy& policy)
{
    const state::RenderState& state = resolved.state;
    const std::vector<ResolvedState> views = stereoViews(resolved);
    Prepared p;
    p.refinement.errorGreyLevels = state.convergenceGreyLevels;
    const bool paint = usePaint(resolved);
    for (const ResolvedState& v : views) {
        p.views.push_back({v.params, nullptr});
        if (paint)
            applyFeaturePaint(p.views.back().params, int(m_dataset->variables().size()));
    }
    const int step = state.step;
    const int levels = int(m_dataset->levels().size());
    // The views share the budget: each eye of a stereo pair gets half.
    const double budget = passBudgetSeconds(state.timeBudgetMs, policy.overheadSeconds, int(views.size()));
    const double rate = policy.samplesPerSecond;

    if (const auto known = knownChoice(state, policy)) {
        p.level = known->level;
        p.divisor = known->divisor;
    } else {
        // Coarse to fine (finestLevelWithin): while only the coarse levels fit, the finer ones of a
        // new step are neither loaded nor prepared. Reload class when the level changes. The first
        // view stands for all (the eyes differ by a small shift).
        const LevelChoice c = chooseLevel(levels, budget, rate, policy.reduceResolution, [&](int l) {
            VolumeRenderer& r = rendererFor(step, l, 0);
            r.setParams(p.views[0].params);
            return r.estimateSamplesPerPass();
        });
        p.level = c.level;
        p.divisor = c.divisor;
    }
    for (View& v : p.views) {
        v.params.width = std::max(1, (v.params.width + p.divisor - 1) / p.divisor);
        v.params.height = std::max(1, (v.params.height + p.divisor - 1) / p.divisor);
    }

    for (size_t i = 0; i < p.views.size(); ++i) {
        const auto start = std::chrono::steady_clock::now();
        p.views[i].renderer = &rendererFor(step, p.level, int(i));
        const double loadedMs = millisecondsSince(start);
        p.views[i].renderer->setParams(p.views[i].params);  // restart class: camera, transfer function, brushes, size
        spdlog::debug("step {} level {} view {}: volume {:.1f} ms, parameters {:.1f} ms", step, p.level, i, loadedMs,
                      millisecondsSince(start) - loadedMs);
    }
    p.scene = pathlinesFor(state);  // before any pass reads it
    for (auto& entry : m_renderers) {
        VolumeRenderer* r = entry.second.get();  // not a structured binding: clang 14 cannot capture one
        const bool used = std::any_of(p.views.begin(), p.views.end(), [&](const View& v) { return v.renderer == r; });
        if (!used)
            r->setPathlines(nullptr);  // no other renderer keeps a scene that changes
    }
    for (View& v : p.views) {
        v.renderer->setPathlines(p.scene);
        p.estimatedSamplesPerPass += v.renderer->estimateSamplesPerPass();
    }
    return p;
}

ViewFrames StateRenderer::Prepared::frames() const
{
    ViewFrames out;
    for (const View& v : views) {
        out.emplace_back(v.params.width, v.params.height);
        out.back().setRefinement(refinement);
    }
    return out;
}

PassStats StateRenderer::Prepared::renderPass(ViewFrames& frames, const std::atomic<bool>* cancel,
                                              TileShare share) const
{
    RAYPC_CHECK_EQ(frames.size(), views.size());
    PassStats total;
    for (size_t i = 0; i < views.size(); ++i) {
        const PassStats s = views[i].renderer->renderPass(frames[i], cancel, share);
        if (s.cancelled) {
            total.cancelled = true;
            return total;
        }
        total += s;
    }
    return total;
}

TileShare rankTileShare()
{
    return {mpi::rank(), mpi::size()};
}

void gatherTilesToRoot(FrameBuffer& frame)
{
    if (!mpi::distributed())
        return;
    const std::vector<float> all = mpi::gatherToRoot(frame.packTiles(rankTileShare()));
    if (!mpi::isRoot())
        return;
    // Rank order: rank r's block holds its tiles in tile order.
    size_t offset = 0;
    for (int r = 0; r < mpi::size(); ++r)
        offset += frame.unpackTiles(std::span(all).subspan(offset), {r, mpi::size()});
    RAYPC_CHECK_EQ(offset, all.size());
}

StateRenderer::Still StateRenderer::renderStill(const ResolvedState& resolved, int passes,
                                                const std::atomic<bool>* cancel, TileShare share,
                                                const std::function<void(int done, int total)>& onPass)
{
    const Prepared p = prepare(resolved);
    Still still{p.frames(), p.level, p.scene ? p.scene->visibleCount() : 0, {}};
    const int n = passes > 0 ? passes : std::max(1, resolved.state.passes);
    for (int pass = 0; pass < n; ++pass) {
        if (cancel && cancel->load())
            break;
        const PassStats s = p.renderPass(still.frames, cancel, share);
        if (s.cancelled)
            break;
        still.passes.push_back(s);
        if (onPass)
            onPass(pass + 1, n);
    }
    return still;
}

uint64_t pictureMemoryBytes(const state::RenderState& state, bool withDepth)
{
    const StereoLayout layout = stereoLayout(state.stereo.mode, state.width, state.height);
    const uint64_t eyePixels = uint64_t(layout.renderedPixels());
    // Each view: its frame buffer, then its picture (averaged RGBA and depth for the reference
    // geometry, 8-bit RGBA); the composed image; the depth map (each view's, side by side, the file).
    uint64_t perEyePixel = FrameBuffer::bytesPerPixel() + 4 * sizeof(float) + sizeof(float) + 4;
    if (withDepth)
        perEyePixel += 3 * sizeof(float);
    return eyePixels * perEyePixel + uint64_t(layout.width) * uint64_t(layout.height) * 4;
}

void checkPictureFitsMemory(const state::RenderState& state, bool withDepth, const AvailableMemory& available)
{
    const uint64_t needed = pictureMemoryBytes(state, withDepth);
    if (needed > available.bytes)
        fail("a picture of {}x{} pixels{} needs {} of memory to render, {} available ({}); choose a smaller --size",
             state.width, state.height,
             state.stereo.mode == StereoMode::Off ? "" : fmt::format(" ({} stereo)", state::stereoModeName(state.stereo.mode)),
             formatBytes(needed), formatBytes(available.bytes), available.limitedBy);
}

ImageRgba8 StateRenderer::picture(const ViewFrames& frames, const ResolvedState& resolved, bool withLegends,
                                  bool withShellLabels) const
{
    const std::vector<ResolvedState> views = stereoViews(resolved);
    RAYPC_CHECK_EQ(frames.size(), views.size());
    const FrameBuffer& first = frames.front();
    if (views.size() == 1)
        return {first.width(), first.height(), viewPicture(first, resolved, withLegends, withShellLabels)};
    // Each eye is a whole picture (its own reference geometry and legends), then the pair is composed.
    const StereoMode mode = resolved.state.stereo.mode;
    const StereoLayout eyes = stereoLayout(mode == StereoMode::Anaglyph ? mode : StereoMode::SideBySide, first.width(),
                                     first.height());
    return {eyes.width, eyes.height,
            composeStereo(mode, eyes, viewPicture(first, views[0], withLegends, withShellLabels),
                          viewPicture(frames[1], views[1], withLegends, withShellLabels))};
}

std::shared_ptr<const ReferenceLayer> StateRenderer::referenceLayer(const state::RenderState& state, int width,
                                                                    int height) const
{
    const nlohmann::json document = state::toJson(state);
    const bool marked = state.map.showInView;
    const std::string key = nlohmann::json{{"reference", document["reference"]},
                                           {"camera", document["camera"]},
                                           {"marks", marked ? nlohmann::json{document["map"]["depthKm"], document["section"]}
                                                            : nlohmann::json()},
                                           {"size", {width, height}}}
                                .dump();
    std::lock_guard lock(m_referenceMutex);
    for (const auto& [k, layer] : m_referenceLayers)
        if (k == key)
            return layer;
    const grid::SphericalGrid& grid = m_dataset->levels().front().grid;
    const auto coastlines = state.reference.coastlines.visible ? defaultCoastlines() : nullptr;
    const SliceMarks marks{state.map.depthKm, state.section.from, state.section.to};
    auto layer = std::make_shared<const ReferenceLayer>(state.reference, state.camera, width, height,
                                                        float(grid.rKm.back()), float(grid.rKm.front()),
                                                        coastlines.get(), marked ? &marks : nullptr);
    spdlog::debug("reference geometry of {}x{} pixels made: {} kept", width, height, formatBytes(layer->bytes()));
    if (m_referenceLayers.size() >= 2)
        m_referenceLayers.erase(m_referenceLayers.begin());
    m_referenceLayers.emplace_back(key, layer);
    return layer;
}

std::vector<uint8_t> StateRenderer::viewPicture(const FrameBuffer& frame, const ResolvedState& resolved,
                                                bool withLegends, bool withShellLabels) const
{
    const state::RenderState& state = resolved.state;
    const auto& ref = state.reference;
    std::vector<uint8_t> out;
    if (ref.shells.visible || ref.graticule.visible || ref.coastlines.visible || state.map.showInView) {
        std::vector<float> rgba = frame.averagedRgba();
        const grid::SphericalGrid& grid = m_dataset->levels().front().grid;
        referenceLayer(state, frame.width(), frame.height())->composite(rgba, frame.averagedDepthKm());
        out = toRgba8(rgba, state.background);
        // Each shell's depth on its ring (the UI writes them itself over a mono frame, crisp at any
        // frame size).
        if (withShellLabels)
            drawTextLabels(out, frame.width(), frame.height(),
                           shellLabels(ref, state.camera, frame.width(), frame.height(), float(grid.rKm.back()),
                                       float(grid.rKm.front())));
    } else {
        out = frame.resolveRgba8(state.background);
    }
    if (withLegends && state.legend) {
        std::vector<LegendSpec> legends;
        if (paintsFeatures(state)) {
            legends.push_back(featurePaintLegend(state.features));
        } else {
            legends.push_back({variableTitle(m_dataset->variables().at(size_t(resolved.params.colorVariable))),
                               resolved.params.transfer, {}});
        }
        if (state.pathlines.visible && m_scene && m_sceneStep == state.step) {
            legends.push_back(pathlineLegend(m_scene->style(), m_scene->columns()));
        }
        const grid::SphericalGrid& grid = m_dataset->levels().front().grid;
        drawLegends(out, frame.width(), frame.height(), legends,
                    shellKey(ref, float(grid.rKm.back()), float(grid.rKm.front())));
    }
    return out;
}

ImageRgba8 StateRenderer::slicePicture(const ResolvedState& resolved, Slice slice) const
{
    const state::RenderState& state = resolved.state;
    const int level = state.level.value_or(0);
    const auto volume = m_sources.volume ? m_sources.volume(state.step, level) : m_dataset->load(state.step, level);
    const auto coastlines = slice == Slice::Map && state.reference.coastlines.visible ? defaultCoastlines() : nullptr;
    std::optional<PathlineLines> pathlines;
    if (state.pathlines.visible) {
        try {
            pathlines.emplace(m_sources.pathlines(state.step, state.pathlines.window));
        } catch (const Error& e) {
            fail("pathlines: {}", e.what());
        }
    }
    SliceInputs inputs{.volume = volume.get(),
                       .resolved = &resolved,
                       .variableNames = m_dataset->variableNames(),
                       .colorTitle = variableTitle(m_dataset->variables().at(size_t(resolved.params.colorVariable))),
                       .when = fmt::format("step {}, {:.1f} Myr", state.step, m_dataset->steps().at(size_t(state.step)).timeMyr),
                       .coastlines = coastlines.get(),
                       .pathlines = pathlines ? &*pathlines : nullptr};
    return slice == Slice::Map ? mapPicture(inputs) : sectionPicture(inputs);
}

double StateRenderer::measureSamplesPerSecond(int step, const RenderParams& params)
{
    VolumeRenderer& calibration = rendererFor(step, int(m_dataset->levels().size()) - 1, 0);
    calibration.setParams(params);
    FrameBuffer scratch(params.width, params.height);
    calibration.renderPass(scratch);  // the first pass also starts the worker threads
    const PassStats s = calibration.renderPass(scratch);
    return s.seconds > 0 ? calibration.estimateSamplesPerPass() / s.seconds : 0;
}

}  // namespace raypc::render
