#include "server/render_session.h"

#include "core/clock.h"
#include "core/error.h"
#include "data/selection.h"
#include "server/image_codec.h"
#include "server/rank_pool.h"

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

nlohmann::json cameraJson(const RenderState& state)
{
    return toJson(state)["camera"];
}

// What the UI needs to re-project each eye of a stereo frame (docs/protocol.md): the eyes' size as
// rendered (the depth map holds them side by side) and their cameras' offsets.
nlohmann::json stereoJson(const RenderState& state, int eyeWidth, int eyeHeight)
{
    const StereoLayout layout = stereoLayout(state.stereo.mode, state.width, state.height);
    return {{"mode", std::string(stereoModeName(state.stereo.mode))},
            {"eyeSeparationKm", state.stereo.eyeSeparationKm},
            {"convergenceKm", state.stereo.convergenceOr(state.camera.distanceKm)},
            {"eyeWidth", eyeWidth},
            {"eyeHeight", eyeHeight},
            {"pixelAspect", layout.pixelAspect}};
}

}  // namespace

RenderSession::RenderSession(RenderContext& context, SessionSink sink, std::string name)
    : m_context(context),
      m_sink(std::move(sink)),
      m_name(std::move(name)),
      m_renderer(context.dataset, cacheSources(context.cache, context.pathlines)),
      m_rankSession(context.ranks ? context.ranks->openSession() : 0),
      m_thread([this] { loop(); })
{
}

RenderSession::~RenderSession()
{
    stop();
    if (m_context.ranks)
        m_context.ranks->closeSession(m_rankSession);
}

void RenderSession::submit(const StateMessage& message)
{
    Request request;
    request.received = Clock::now();
    request.id = message.id;
    request.resolved = render::resolveState(message.state, *m_context.dataset);  // throws: the old state stays
    const auto& st = request.resolved.state;
    if (render::stereoLayout(st.stereo.mode, st.width, st.height).renderedPixels() > int64_t(kMaxSessionPixels))
        fail("image: {}x{}{} is over the limit of {} pixels for a session (use /api/screenshot for larger images)",
             st.width, st.height, st.stereo.enabled() ? " (stereo: two eyes)" : "", kMaxSessionPixels);
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

void RenderSession::render(const Request& request)
{
    const auto renderStart = Clock::now();
    const RenderState& state = request.resolved.state;
    const Dataset& dataset = *m_context.dataset;
    const int step = state.step;

    // Interactive: the finest level within the time budget at the measured throughput (until a pass
    // has been measured, an assumed 100 M samples/s per thread), 1/2 or 1/4 of the pixels per axis
    // when even the coarsest misses it. Still: the state's level, else level 0.
    LevelPolicy policy;
    if (request.interactive) {
        const double measured = m_context.samplesPerSecond.load();
        policy.samplesPerSecond = measured > 0 ? measured : 100e6 * tbb::this_task_arena::max_concurrency();
        policy.reduceResolution = measured > 0;
    }
    // The other ranks of a distributed server prepare the frame while this one does, when its level
    // is known before preparing (still frames).
    const uint64_t frameNumber = ++m_frames;
    if (m_context.ranks)
        if (const auto choice = StateRenderer::knownChoice(state, policy))
            m_context.ranks->prepare(m_rankSession, frameNumber, request.resolved, *choice);
    const StateRenderer::Prepared prepared = m_renderer.prepare(request.resolved, policy);
    const int level = prepared.level;
    const RenderParams& params = prepared.views.front().params;  // the first view's (all share brushes)
    VolumeRenderer& renderer = *prepared.views.front().renderer;
    const auto& scene = prepared.scene;
    const double estimatedSamples = prepared.estimatedSamplesPerPass;

    // Playback (step = previous step + 1): load the next step in the background at this level.
    if (m_lastStep >= 0 && step == m_lastStep + 1 && step + 1 < int(dataset.steps().size())) {
        spdlog::debug("{}: playback: prefetching step {} level {}", m_name, step + 1, level);
        m_context.cache->prefetch(step + 1, level);
    }
    m_lastStep = step;

    // Selection statistics of the brushes (exact on a level's grid), recomputed only when they or the
    // volume change. At full resolution they take tens of ms (docs/rendering.md), so interactive frames take them from the
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
        const SelectionStats s = selectedVolume(*volume, params.brushes);
        m_selection = {{"fractionOfMantle", s.fractionOfMantle}, {"volumeKm3", s.volumeKm3}};
        m_selectionKey = selectionKey;
    };
    if (request.interactive)
        updateSelection();

    const double waitedMs = std::chrono::duration<double, std::milli>(renderStart - request.received).count();
    const double preparedMs = millisecondsSince(renderStart);
    const int passes = request.interactive ? 1 : std::max(1, state.passes);
    ViewFrames frames = prepared.frames();
    const int ranks = m_context.ranks ? m_context.ranks->ranks() : 1;
    double renderMsTotal = 0, encodeMsTotal = 0, firstPassMs = 0;
    int done = 0;
    for (int pass = 1; pass <= passes; ++pass) {
        if (m_cancel)
            break;
        const PassStats stats =
            m_context.ranks
                ? m_context.ranks->renderPass(m_rankSession, frameNumber, pass, request.resolved, prepared, frames, &m_cancel)
                : prepared.renderPass(frames, &m_cancel);
        if (stats.cancelled)
            break;
        // Only a pass that rendered every pixel measures the throughput: later ones may render only
        // the blocks that still refine (adaptive refinement) and would overstate it.
        if (stats.seconds > 0 && stats.everyBlock) {
            // Exponential average of the throughput, shared with the other sessions.
            const double measured = estimatedSamples / stats.seconds;
            const double old = m_context.samplesPerSecond.load();
            m_context.samplesPerSecond.store(old > 0 ? 0.7 * old + 0.3 * measured : measured);
        }
        // Adaptive refinement (a still state's convergenceGreyLevels) may have stopped every block:
        // this frame is final, further passes would render nothing.
        const bool refined = std::all_of(frames.begin(), frames.end(), [](const FrameBuffer& f) { return f.converged(); });
        const bool last = pass == passes || refined;
        const auto encodeStart = Clock::now();
        const ImageRgba8 picture = m_renderer.picture(frames, request.resolved, false);  // the UI draws legends
        const std::string jpeg = encodeJpeg(picture.pixels, picture.width, picture.height,
                                            request.interactive ? kJpegQualityInteractive : kJpegQualityStill);
        // A stereo pair's depth is the two eyes' side by side, whatever the picture's layout, each
        // downsampled on its own (so that no block straddles the eyes).
        int depthWidth = 0, depthHeight = 0;
        std::vector<float> depth;
        for (const FrameBuffer& frame : frames) {
            const std::vector<float> eye = downsampleDepth(frame.averagedDepthKm(), frame.width(), frame.height(),
                                                           kDepthDownsample, depthWidth, depthHeight);
            depth = depth.empty() ? eye : sideBySide({depthWidth, depthHeight, 2 * depthWidth, depthHeight, 1.0, 2}, depth, eye);
        }
        depthWidth *= int(frames.size());
        const double passMs = stats.seconds * 1000.0;
        const uint64_t samples = stats.samples + stats.samplesSkipped;
        nlohmann::json header{{"type", "frame"},
                              {"id", request.id},
                              {"step", step},
                              {"level", level},
                              {"pass", pass},
                              {"passes", passes},
                              {"converged", last},
                              {"interactive", request.interactive},
                              {"ranks", ranks},
                              {"width", picture.width},
                              {"height", picture.height},
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
        if (state.stereo.enabled())
            header["stereo"] = stereoJson(state, frames.front().width(), frames.front().height());
        std::string bytes = encodeFrame(std::move(header), {reinterpret_cast<const uint8_t*>(jpeg.data()), jpeg.size()},
                                        depth, depthWidth, depthHeight);
        encodeMsTotal += millisecondsSince(encodeStart);
        renderMsTotal += passMs;
        if (pass == 1)
            firstPassMs = passMs;
        done = pass;
        m_sink.sendBinary(std::move(bytes));
        updateSelection();
        if (last)
            break;
    }
    if (done > 0)
        spdlog::info("{}: state {} step {} level {} {}x{} {}: waited {:.1f} ms, prepared {:.1f} ms, {}/{} passes, "
                     "first {:.1f} ms, mean {:.1f} ms/pass, encode {:.1f} ms/frame",
                     m_name, request.id, step, level, frames.front().width() * int(frames.size()), params.height,
                     request.interactive ? "interactive" : "still", waitedMs, preparedMs, done, passes, firstPassMs,
                     renderMsTotal / done, encodeMsTotal / done);
}

}  // namespace raypc::server
