#include "server/render_session.h"

#include "core/error.h"
#include "data/selection.h"
#include "server/image_codec.h"

#include <spdlog/spdlog.h>
#include <tbb/task_arena.h>

#include <algorithm>
#include <chrono>

namespace raypc::server {

using namespace raypc::render;
using Clock = std::chrono::steady_clock;

namespace {

constexpr int kDepthDownsample = 4;
constexpr int kMaxSessionPixels = 4096 * 4096;  // a frame buffer of 4096² takes ~0.7 GB with its scratch
constexpr int kJpegQualityInteractive = 75, kJpegQualityStill = 90;

double millisecondsSince(Clock::time_point start)
{
    return std::chrono::duration<double, std::milli>(Clock::now() - start).count();
}

nlohmann::json cameraJson(const RenderState& state)
{
    return toJson(state)["camera"];
}

}  // namespace

RenderSession::RenderSession(RenderContext& context, SessionSink sink, std::string name)
    : m_context(context), m_sink(std::move(sink)), m_name(std::move(name)), m_thread([this] { loop(); })
{
}

RenderSession::~RenderSession()
{
    stop();
}

void RenderSession::submit(const StateMessage& message)
{
    Request request;
    request.received = Clock::now();
    request.id = message.id;
    request.resolved = resolveState(message.state, *m_context.dataset);  // throws: the old state stays
    const auto& st = request.resolved.state;
    if (int64_t(st.width) * st.height > int64_t(kMaxSessionPixels))
        fail("image: {}x{} is over the limit of {} pixels for a session (use /api/screenshot for larger images)",
             st.width, st.height, kMaxSessionPixels);
    request.interactive = message.interactive;
    {
        std::lock_guard lock(m_mutex);
        m_pending = std::move(request);  // drops a state that has not started
        m_cancel = true;                 // and stops the pass in flight
    }
    m_cv.notify_all();
}

void RenderSession::cancel()
{
    std::lock_guard lock(m_mutex);
    m_pending.reset();
    m_cancel = true;
}

void RenderSession::stop()
{
    {
        std::lock_guard lock(m_mutex);
        m_stopping = true;
        m_pending.reset();
        m_cancel = true;
    }
    m_cv.notify_all();
    if (m_thread.joinable())
        m_thread.join();
}

void RenderSession::loop()
{
    for (;;) {
        Request request;
        {
            std::unique_lock lock(m_mutex);
            m_cv.wait(lock, [&] { return m_stopping || m_pending; });
            if (m_stopping)
                return;
            request = std::move(*m_pending);
            m_pending.reset();
            m_cancel = false;
        }
        // Catch at the edge of the worker: log and report to the client, keep the session.
        try {
            render(request);
        } catch (const std::exception& e) {
            spdlog::warn("{}: state {}: {}", m_name, request.id, e.what());
            m_sink.sendText(errorReply(e.what(), request.id));
        }
    }
}

VolumeRenderer& RenderSession::rendererFor(int step, int level)
{
    // Reload class: a new step drops every level's renderer of the old one.
    if (step != m_rendererStep) {
        m_renderers.clear();
        m_rendererStep = step;
    }
    auto& slot = m_renderers[level];
    if (!slot)
        slot = std::make_unique<VolumeRenderer>(m_context.cache->get(step, level));
    return *slot;
}

int RenderSession::chooseInteractiveLevel(int step, const RenderParams& params, double budgetSeconds)
{
    double rate = m_context.samplesPerSecond.load();
    if (rate <= 0)
        rate = 100e6 * tbb::this_task_arena::max_concurrency();  // until a pass has been measured
    // Coarse to fine (render::finestLevelWithin): while only the coarse levels fit, the finer ones of
    // a new step are neither loaded nor prepared.
    const int levels = int(m_context.dataset->levels().size());
    const int level = finestLevelWithin(levels, kInteractiveBudgetShare * budgetSeconds, [&](int l) {
        VolumeRenderer& r = rendererFor(step, l);
        r.setParams(params);
        return r.estimateSamplesPerPass() / rate;
    });
    return level >= 0 ? level : levels - 1;
}

std::shared_ptr<const PathlineScene> RenderSession::pathlinesFor(const RenderState& state)
{
    if (!state.pathlines.visible || !m_context.pathlines)
        return nullptr;
    // Reload class: a new step or window loads that window (shared cache) and builds a new BVH.
    if (!m_scene || m_sceneStep != state.step || m_sceneWindow != state.pathlines.window) {
        const auto window = m_context.pathlines->get(state.step, state.pathlines.window);
        const auto start = Clock::now();
        m_scene.reset();
        m_scene = std::make_shared<PathlineScene>(*window, state.pathlines.radiusKm);
        m_sceneStep = state.step;
        m_sceneWindow = state.pathlines.window;
        spdlog::info("{}: pathline scene of step {} window {}: {} lines in {:.0f} ms", m_name, state.step,
                     state.pathlines.window, m_scene->lineCount(), millisecondsSince(start));
    }
    // Restart class: radius, style and the visibility mask (attribute filters, brushes).
    m_scene->applyState(state);
    return m_scene;
}

void RenderSession::render(const Request& request)
{
    const auto renderStart = Clock::now();
    const RenderState& state = request.resolved.state;
    RenderParams params = request.resolved.params;
    const Dataset& dataset = *m_context.dataset;
    const int step = state.step;
    const double budgetSeconds = state.timeBudgetMs / 1000.0;

    int level;
    if (state.level)
        level = *state.level;
    else if (request.interactive)
        level = chooseInteractiveLevel(step, params, budgetSeconds);  // reload class when it changes
    else
        level = 0;

    // Interactive resolution: when even the coarsest level misses the budget, render 1/2 or 1/4 of the
    // pixels per axis (the UI scales the frame up; same aspect when the size divides).
    if (request.interactive && !state.level && level == int(dataset.levels().size()) - 1) {
        const double rate = m_context.samplesPerSecond.load();
        if (rate > 0) {
            const double seconds = rendererFor(step, level).estimateSamplesPerPass() / rate;
            const double budget = kInteractiveBudgetShare * budgetSeconds;
            const int divisor = seconds <= budget ? 1 : seconds / 4 <= budget ? 2 : 4;
            params.width = std::max(1, (params.width + divisor - 1) / divisor);
            params.height = std::max(1, (params.height + divisor - 1) / divisor);
        }
    }

    // Playback (step = previous step + 1): load the next step in the background at this level.
    if (m_lastStep >= 0 && step == m_lastStep + 1 && step + 1 < int(dataset.steps().size())) {
        spdlog::debug("{}: playback: prefetching step {} level {}", m_name, step + 1, level);
        m_context.cache->prefetch(step + 1, level);
    }
    m_lastStep = step;

    VolumeRenderer& renderer = rendererFor(step, level);
    renderer.setParams(params);  // restart class: camera, transfer function, brushes, size
    const auto scene = pathlinesFor(state);  // before any pass reads it
    for (auto& [l, r] : m_renderers)
        if (r.get() != &renderer)
            r->setPathlines(nullptr);  // no other renderer of this session keeps a scene that changes
    renderer.setPathlines(scene);
    const double estimatedSamples = renderer.estimateSamplesPerPass();

    // Selection statistics of the brushes (exact on a level's grid), recomputed only when they or the
    // volume change. At full resolution they take 12-80 ms, so interactive frames take them from the
    // coarsest level (under a millisecond), and a still state computes them on its own level after
    // its first frame is sent (that frame says null; the UI asks POST /api/selection for final
    // states anyway).
    const int selectionLevel = request.interactive ? int(dataset.levels().size()) - 1 : level;
    const std::string selectionKey =
        fmt::format("{}/{}/{}", step, selectionLevel, nlohmann::json(toJson(state)["brushes"]).dump());
    auto updateSelection = [&] {
        if (selectionKey == m_selectionKey)
            return;
        const auto volume = selectionLevel == level ? renderer.volume() : m_context.cache->get(step, selectionLevel);
        const SelectionStats s = selectedVolume(*volume, selectionFilters(params));
        m_selection = {{"fractionOfMantle", s.fractionOfMantle}, {"volumeKm3", s.volumeKm3}};
        m_selectionKey = selectionKey;
    };
    if (request.interactive)
        updateSelection();

    const double waitedMs = std::chrono::duration<double, std::milli>(renderStart - request.received).count();
    const double preparedMs = millisecondsSince(renderStart);
    const int passes = request.interactive ? 1 : std::max(1, state.passes);
    FrameBuffer frame(params.width, params.height);
    double renderMsTotal = 0, encodeMsTotal = 0, firstPassMs = 0;
    int done = 0;
    for (int pass = 1; pass <= passes; ++pass) {
        if (m_cancel)
            break;
        const PassStats stats = renderer.renderPass(frame, &m_cancel);
        if (stats.cancelled)
            break;
        if (stats.seconds > 0) {
            // Exponential average of the throughput, shared with the other sessions.
            const double measured = estimatedSamples / stats.seconds;
            const double old = m_context.samplesPerSecond.load();
            m_context.samplesPerSecond.store(old > 0 ? 0.7 * old + 0.3 * measured : measured);
        }
        const auto encodeStart = Clock::now();
        const std::vector<uint8_t> rgba = frame.resolveRgba8(state.background);
        const std::string jpeg = encodeJpeg(rgba, params.width, params.height,
                                            request.interactive ? kJpegQualityInteractive : kJpegQualityStill);
        int depthWidth = 0, depthHeight = 0;
        const std::vector<float> depth =
            downsampleDepth(frame.averagedDepthKm(), params.width, params.height, kDepthDownsample, depthWidth, depthHeight);
        const double passMs = stats.seconds * 1000.0;
        const uint64_t samples = stats.samples + stats.samplesSkipped;
        nlohmann::json header{{"type", "frame"},
                              {"id", request.id},
                              {"step", step},
                              {"level", level},
                              {"pass", pass},
                              {"passes", passes},
                              {"converged", pass == passes},
                              {"interactive", request.interactive},
                              {"width", params.width},
                              {"height", params.height},
                              {"camera", cameraJson(state)},
                              {"stats",
                               {{"passMs", passMs},
                                {"samples", samples},
                                {"samplesPerSecond", stats.seconds > 0 ? double(samples) / stats.seconds : 0.0},
                                {"bricksSkipped", stats.bricksSkipped},
                                {"bricksTotal", stats.bricksTotal}}},
                              {"selection", selectionKey == m_selectionKey ? m_selection : nlohmann::json()}};
        if (scene)
            header["pathlines"] = {{"lines", scene->lineCount()}, {"visible", scene->visibleCount()}};
        std::string bytes = encodeFrame(std::move(header), {reinterpret_cast<const uint8_t*>(jpeg.data()), jpeg.size()},
                                        depth, depthWidth, depthHeight);
        encodeMsTotal += millisecondsSince(encodeStart);
        renderMsTotal += passMs;
        if (pass == 1)
            firstPassMs = passMs;
        done = pass;
        m_sink.sendBinary(std::move(bytes));
        updateSelection();
    }
    if (done > 0)
        spdlog::info("{}: state {} step {} level {} {}x{} {}: waited {:.1f} ms, prepared {:.1f} ms, {}/{} passes, "
                     "first {:.1f} ms, mean {:.1f} ms/pass, encode {:.1f} ms/frame",
                     m_name, request.id, step, level, params.width, params.height,
                     request.interactive ? "interactive" : "still", waitedMs, preparedMs, done, passes, firstPassMs,
                     renderMsTotal / done, encodeMsTotal / done);
}

}  // namespace raypc::server
