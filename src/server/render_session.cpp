#include "server/render_session.h"

#include "render/pair_state.h"

#include "core/clock.h"
#include "core/error.h"
#include "core/system_memory.h"
#include "analysis/selection.h"
#include "render/reference_geometry.h"
#include "server/image_codec.h"
#include "server/rank_pool.h"

#include <spdlog/spdlog.h>
#include <tbb/task_arena.h>

#include <sys/resource.h>
#include <sys/syscall.h>
#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <limits>

namespace raypc::server {

using namespace raypc::render;
using Clock = std::chrono::steady_clock;

namespace {

constexpr int kDepthDownsample = 4;
constexpr int kJpegQualityInteractive = 75, kJpegQualityStill = 90;

// What the UI needs to re-project each eye of a stereo frame (docs/protocol.md): the eyes' size as
// rendered (the depth map holds them side by side) and their cameras' offsets.
nlohmann::json stereoJson(const state::RenderState& state, int eyeWidth, int eyeHeight)
{
    const StereoLayout layout = stereoLayout(state.stereo.mode, state.width, state.height);
    return {{"mode", std::string(state::stereoModeName(state.stereo.mode))},
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
      m_renderer(context.dataset, cacheSources(context.cache, context.pathlines, context.featureLabels)),
      m_rankSession(context.ranks ? context.ranks->openSession() : 0),
      m_frameCache(context.frameCacheBytes, context.frameBudget),
      m_aheadRenderer(context.dataset, cacheSources(context.cache, context.pathlines, context.featureLabels)),
      m_aheadThread([this] { aheadLoop(); }),
      m_thread([this] { loop(); })
{
}

RenderSession::~RenderSession()
{
    stop();
    if (m_context.ranks)
        m_context.ranks->closeSession(m_rankSession);
}

void checkSessionImage(const state::RenderState& state)
{
    if (stereoLayout(state.stereo.mode, state.width, state.height).renderedPixels() > kMaxSessionPixels)
        fail("image: {}x{}{} is over the limit of {} pixels for a session (use /api/screenshot for larger images)",
             state.width, state.height, state.stereo.enabled() ? " (stereo: two eyes)" : "", kMaxSessionPixels);
}

void RenderSession::submit(int64_t id, state::RenderState state, FrameMode mode)
{
    Request request;
    request.received = Clock::now();
    request.id = id;
    if (m_context.pairFirst) {
        render::PairedState paired = render::secondOfPair(std::move(state), *m_context.pairFirst, *m_context.dataset);
        state = std::move(paired.state);
        request.pair = {{"notes", paired.notes}};
    }
    request.resolved = render::resolveState(std::move(state), *m_context.dataset);  // throws: the old state stays
    checkSessionImage(request.resolved.state);
    request.mode = mode;
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
    {
        std::lock_guard lock(m_aheadMutex);
        m_ahead.reset();
        m_aheadStop = true;
        m_aheadCancel = true;
    }
    m_aheadCv.notify_all();
    if (m_aheadThread.joinable())
        m_aheadThread.join();
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
            m_sink.sendText(errorReply(e.what(), request.id), request.id);
        }
    }
}

nlohmann::json shellKeyJson(const state::RenderState& state, const dataset::Dataset& dataset)
{
    nlohmann::json key = nlohmann::json::array();
    const grid::SphericalGrid& grid = dataset.levels().front().grid;
    for (const TextLabel& k : render::shellKey(state.reference, float(grid.rKm.back()), float(grid.rKm.front())))
        key.push_back({{"label", k.text}, {"color", {k.color.r, k.color.g, k.color.b}}});
    return key;
}

std::shared_ptr<EncodedFrame> RenderSession::makeFrame(const StateRenderer& renderer, Job& job, const ViewFrames& frames,
                                                       const StateRenderer::Prepared& prepared, const PassStats& stats,
                                                       int pass, bool last, bool preview,
                                                       const nlohmann::json& selection) const
{
    const Request& request = job.request;
    const state::RenderState& state = request.resolved.state;
    // The UI draws the legends, and over a mono frame the shells' depth labels (shellLabels below).
    const bool labelsByUi = !state.stereo.enabled();
    const ImageRgba8 picture = renderer.picture(frames, request.resolved, false, !labelsByUi);
    auto frame = std::make_shared<EncodedFrame>();
    frame->jpeg = encodeJpeg(picture.pixels, picture.width, picture.height,
                                        job.interactive || preview ? kJpegQualityInteractive : kJpegQualityStill);
    // A stereo pair's depth is the two eyes' side by side, whatever the picture's layout, each
    // downsampled on its own.
    int& depthWidth = frame->depthWidth;
    int& depthHeight = frame->depthHeight;
    frame->depth =
        averagedDepthKm(frames, depthWidth, depthHeight, [](std::vector<float> eye, int& width, int& height) {
            int w = 0, h = 0;
            std::vector<float> out = downsampleDepth(eye, width, height, kDepthDownsample, w, h);
            width = w;
            height = h;
            return out;
        });
    nlohmann::json header{{"type", "frame"},
                          {"id", request.id},
                          {"step", state.step},
                          {"level", prepared.level},
                          {"pass", pass},
                          {"passes", job.passes},
                          {"converged", last},
                          {"interactive", job.interactive},
                          {"playback", request.mode == FrameMode::playback},
                          {"preview", preview},
                          {"cached", false},
                          {"ranks", job.ranks},
                          {"width", picture.width},
                          {"height", picture.height},
                          {"camera", job.document["camera"]},
                          {"stats", toJson(stats, PassStatsJson::frameHeader)},
                          {"selection", selection}};
    if (prepared.scene)
        header["pathlines"] = {{"lines", prepared.scene->lineCount()}, {"visible", prepared.scene->visibleCount()}};
    if (state.stereo.enabled())
        header["stereo"] = stereoJson(state, frames.front().width(), frames.front().height());
    // The reference shells drawn, as the pictures' legend names them (render::shellKey): the UI's
    // legend key.
    if (!job.shellKey.empty())
        header["shellKey"] = job.shellKey;
    // Where each shell's depth goes on a mono frame (render::shellLabels) and the surface's outline
    // (render::sphereOutline), as fractions of its width and height: the UI draws them, crisp
    // whatever the frame's size or level.
    if (labelsByUi) {
        const grid::SphericalGrid& grid = m_context.dataset->levels().front().grid;
        nlohmann::json labels = nlohmann::json::array();
        for (const TextLabel& l : render::shellLabels(state.reference, state.camera, picture.width, picture.height,
                                                      float(grid.rKm.back()), float(grid.rKm.front())))
            labels.push_back({{"label", l.text},
                              {"color", {l.color.r, l.color.g, l.color.b}},
                              {"x", l.x / float(picture.width)},
                              {"y", l.y / float(picture.height)}});
        if (!labels.empty())
            header["shellLabels"] = std::move(labels);
        // The surface's outline, which the UI draws so that material near the surface is seen inside it.
        nlohmann::json outline = nlohmann::json::array();
        for (const auto& [x, y] : render::sphereOutline(state.camera, picture.width, picture.height,
                                                        float(grid.rKm.back())))
            outline.push_back({x / float(picture.width), y / float(picture.height)});
        if (!outline.empty())
            header["surfaceOutline"] = std::move(outline);
    }
    if (!request.pair.is_null())
        header["pair"] = request.pair;
    frame->header = std::move(header);
    return frame;
}

void RenderSession::send(const EncodedFrame& frame, int64_t id)
{
    std::string bytes =
        encodeFrame(frame.header, {reinterpret_cast<const uint8_t*>(frame.jpeg.data()), frame.jpeg.size()}, frame.depth,
                    frame.depthWidth, frame.depthHeight);
    m_sink.sendBinary(std::move(bytes), id);
}

std::shared_ptr<EncodedFrame> RenderSession::sendFrame(Job& job, const ViewFrames& frames,
                                                       const StateRenderer::Prepared& prepared, const PassStats& stats,
                                                       int pass, bool last, bool preview, const nlohmann::json& selection)
{
    const auto encodeStart = Clock::now();
    auto frame = makeFrame(m_renderer, job, frames, prepared, stats, pass, last, preview, selection);
    send(*frame, job.request.id);
    job.encodeMs += millisecondsSince(encodeStart);
    return frame;
}

void RenderSession::sendKept(const EncodedFrame& kept, const Request& request)
{
    EncodedFrame frame = kept;
    nlohmann::json& h = frame.header;
    h["id"] = request.id;
    h["interactive"] = request.mode == FrameMode::interactive;
    h["playback"] = request.mode == FrameMode::playback;
    h["preview"] = false;
    h["cached"] = true;
    send(frame, request.id);
}

void RenderSession::planAhead(const Request& request, const std::string& key)
{
    {
        std::lock_guard lock(m_aheadMutex);
        if (!m_ahead || m_ahead->key != key)
            m_aheadCancel = true;  // the frame in flight is of a state no longer shown
        m_ahead = AheadPlan{key, request};
        m_aheadChanged = true;
    }
    m_aheadCv.notify_all();
}

std::shared_ptr<const EncodedFrame> RenderSession::renderFinished(StateRenderer& renderer, const Request& request,
                                                                  const std::atomic<bool>& cancel, int maxPasses)
{
    const state::RenderState& state = request.resolved.state;
    Job job{.request = request,
            .document = state::toJson(state),
            .shellKey = shellKeyJson(state, *m_context.dataset),
            .interactive = false,
            .passes = std::max(1, state.passes),
            .ranks = 1};
    const StateRenderer::Prepared prepared = renderer.prepare(request.resolved, LevelPolicy{});
    ViewFrames frames = prepared.frames();
    PassStats stats;
    int pass = 0;
    bool finished = false;
    while (pass < std::min(job.passes, maxPasses)) {
        if (cancel)
            return nullptr;
        stats = prepared.renderPass(frames, &cancel);
        if (stats.cancelled)
            return nullptr;
        ++pass;
        finished = pass == job.passes ||
                   std::all_of(frames.begin(), frames.end(), [](const FrameBuffer& f) { return f.converged(); });
        if (finished)
            break;
    }
    const auto volume = prepared.views.front().renderer->volume();
    const analysis::SelectionStats s = analysis::selectedVolume(*volume, prepared.views.front().params.brushes);
    const nlohmann::json selection{{"fractionOfMantle", s.fractionOfMantle}, {"volumeKm3", s.volumeKm3}};
    auto frame = makeFrame(renderer, job, frames, prepared, stats, pass, true, false, selection);
    frame->finished = finished;
    return frame;
}

// The level of a draft rendered ahead while playing: one finer than most of the session's own steps
// of playback of this state took within their period (their median level: a draft has a whole loop's
// time, shared with those steps), never
// finer than the still's; before any step of playback, one coarser than the still's. So at 2 steps/s
// on a full-resolution series (playback at level 1) the drafts are at level 0, at 5 steps/s (level 2)
// at level 1: a full-size frame of every step within about a loop, which the finished frame replaces.
int RenderSession::draftLevel(const state::RenderState& state) const
{
    const int still = state.level.value_or(0), coarsest = int(m_context.dataset->levels().size()) - 1;
    const int played = m_playbackLevel.load();
    return std::clamp(played >= 0 ? played - 1 : still + 1, still, std::max(still, coarsest));
}

void RenderSession::aheadLoop()
{
    // Below the session's own frames: a nicer thread, and a TBB arena whose tasks the shared workers
    // take only when the normal-priority arena has none.
    setpriority(PRIO_PROCESS, pid_t(syscall(SYS_gettid)), 10);
    tbb::task_arena arena(tbb::task_arena::automatic, 1, tbb::task_arena::priority::low);
    const int steps = int(m_context.dataset->steps().size());
    size_t frameBytes = 0;  // the last frame's, to stop before the bound
    for (;;) {
        std::optional<AheadPlan> plan;
        {
            std::unique_lock lock(m_aheadMutex);
            m_aheadCv.wait(lock, [&] { return m_aheadStop || (m_ahead && m_aheadChanged); });
            if (m_aheadStop)
                return;
            plan = m_ahead;
            m_aheadChanged = false;
            m_aheadCancel = false;
        }
        m_aheadBusy = true;
        // The steps after the one shown, in playing order (wrapping around), that have no frame yet.
        // While playing, first a draft of each (its first pass, at the still's level and size: one
        // loop then shows every step at that level), then the finished frames; paused, the finished
        // frames at once (a still asks for them; a draft would not answer it).
        const int shown = plan->request.resolved.state.step;
        const bool drafts = plan->request.mode == FrameMode::playback && plan->request.resolved.state.passes > 1;
        bool stopped = false;
        for (int round = drafts ? 0 : 1; round < 2 && !stopped; ++round) {
            const bool draft = round == 0;
            for (int k = 1; k <= steps; ++k) {
                const int step = (shown + k) % steps;
                if (m_aheadCancel || m_aheadStop)
                    stopped = true;
                {
                    std::lock_guard lock(m_aheadMutex);
                    if (m_aheadChanged)
                        stopped = true;  // a newer state: start again from its step
                }
                if (stopped)
                    break;
                if (m_frameCache.contains(plan->key, step, !draft))
                    continue;
                if (!m_frameCache.hasRoomFor(frameBytes)) {
                    stopped = true;
                    break;
                }
                try {
                    Request request = plan->request;
                    request.id = 0;
                    request.mode = FrameMode::still;
                    request.resolved.state.step = step;
                    if (draft)
                        request.resolved.state.level = draftLevel(request.resolved.state);
                    request.resolved = render::resolveState(std::move(request.resolved.state), *m_context.dataset);
                    std::shared_ptr<const EncodedFrame> frame;
                    arena.execute([&] {
                        frame = renderFinished(m_aheadRenderer, request, m_aheadCancel,
                                               draft ? 1 : std::numeric_limits<int>::max());
                    });
                    if (!frame) {
                        stopped = true;
                        break;
                    }
                    frameBytes = frame->bytes();
                    if (m_frameCache.insert(plan->key, step, frame))
                        spdlog::debug("{}: rendered ahead step {}{} ({} frames kept, {})", m_name, step,
                                      frame->finished ? "" : " (draft)", m_frameCache.frames(),
                                      formatBytes(m_frameCache.bytes()));
                } catch (const std::exception& e) {
                    // Logged, not sent: the client did not ask for this frame; the step is asked again in time.
                    spdlog::warn("{}: rendering ahead step {}: {}", m_name, step, e.what());
                    stopped = true;
                    break;
                }
            }
        }
        m_aheadBusy = false;
    }
}

PassStats RenderSession::renderPass(const Job& job, uint64_t frameNumber, int pass,
                                    const StateRenderer::Prepared& prepared, ViewFrames& frames)
{
    const PassStats stats = m_context.ranks ? m_context.ranks->renderPass(m_rankSession, frameNumber, pass,
                                                                          job.request.resolved, prepared, frames, &m_cancel)
                                            : prepared.renderPass(frames, &m_cancel);
    // Later passes of adaptive refinement render only the blocks that still refine and would
    // overstate the throughput: only a pass over every pixel measures it (an exponential average
    // shared with the other sessions).
    if (!stats.cancelled && stats.seconds > 0 && stats.everyBlock) {
        const double measured = prepared.estimatedSamplesPerPass / stats.seconds;
        m_context.samplesPerSecond.store(averagedMeasure(m_context.samplesPerSecond.load(), measured));
    }
    return stats;
}

void RenderSession::updateSelection(const std::string& key, int step, int level, const StateRenderer::Prepared& prepared)
{
    if (key == m_selectionKey)
        return;
    const StateRenderer::View& view = prepared.views.front();  // all views share the brushes
    const auto volume = level == prepared.level ? view.renderer->volume() : m_context.cache->get(step, level);
    const analysis::SelectionStats s = analysis::selectedVolume(*volume, view.params.brushes);
    m_selection = {{"fractionOfMantle", s.fractionOfMantle}, {"volumeKm3", s.volumeKm3}};
    m_selectionKey = key;
}

void RenderSession::render(const Request& request)
{
    const auto renderStart = Clock::now();
    const state::RenderState& state = request.resolved.state;
    const dataset::Dataset& dataset = *m_context.dataset;
    const int step = state.step;
    Job job{.request = request,
            .document = state::toJson(state),
            .shellKey = shellKeyJson(state, dataset),
            .interactive = request.mode == FrameMode::interactive,
            .passes = request.mode == FrameMode::interactive ? 1 : std::max(1, state.passes),
            .ranks = m_context.ranks ? m_context.ranks->ranks() : 1};

    // A finished frame of this state at this step, rendered ahead (or kept from an earlier still
    // frame), answers at once; any change but the step makes another key and drops the kept ones.
    const std::string frameKey = frameCacheKey(job.document);
    m_frameCache.setKey(frameKey);
    // Rendering ahead starts once the session moves in time (a step of playback, another step), so
    // that a session that only looks at one step costs no more than its own frames.
    if (m_context.frameCacheBytes > 0 &&
        (request.mode == FrameMode::playback || (m_lastStep >= 0 && step != m_lastStep)))
        m_renderAhead = true;
    if (m_renderAhead)
        planAhead(request, frameKey);
    // A step of playback is answered by a draft too, when the draft is no coarser than the level most
    // of this state's own steps of playback reached (a draft made before the first step knew it is at a
    // guessed level, which may be coarser than what the step renders in its time); a still or
    // interactive state only by a finished frame.
    const int played = m_playbackKey == frameKey ? m_playbackLevel.load() : -1;
    if (const auto kept = m_frameCache.find(frameKey, step, request.mode == FrameMode::playback ? played : -1)) {
        sendKept(*kept, request);
        m_lastStep = step;
        spdlog::info("{}: state {} step {} {}: the frame rendered ahead, after {:.1f} ms", m_name, request.id, step,
                     frameModeName(request.mode), millisecondsSince(request.received));
        return;
    }

    // Interactive and playback: the finest level within the time budget at the measured throughput
    // (interactiveLevelPolicy). Still: the state's level, else level 0.
    // An interactive frame's budget also holds its time outside the pass (a drag waits for each
    // frame before it sends the next state); a step of playback refines until its time is up.
    const LevelPolicy quickPolicy = interactiveLevelPolicy(
        m_context.samplesPerSecond.load(), job.interactive ? m_context.frameOverheadSeconds.load() : 0.0);
    const LevelPolicy policy = request.mode != FrameMode::still ? quickPolicy : LevelPolicy{};

    // The other ranks of a distributed server prepare the frame while this one does, when its level
    // is known before preparing (still frames).
    const uint64_t frameNumber = ++m_frames;
    if (m_context.ranks)
        if (const auto choice = StateRenderer::knownChoice(state, policy))
            m_context.ranks->prepare(m_rankSession, frameNumber, request.resolved, *choice);
    // Preview: a still state at level "auto" (level 0) is first prepared as an interactive
    // state is; when that chooses a coarser level or fewer pixels (level 0 would miss the state's
    // timeBudgetMs), one pass of that choice is sent first, as pass 0 with "preview": true, and its
    // passes at level 0 then refine it. So the picture changes at once after a brush is released, a
    // step is chosen or the page opens; level 0 is not even loaded before the preview is sent.
    double previewMs = 0;
    const bool mayPreview = request.mode == FrameMode::still && !state.level;
    StateRenderer::Prepared prepared = m_renderer.prepare(request.resolved, mayPreview ? quickPolicy : policy);
    if (mayPreview && (prepared.level != 0 || prepared.divisor != 1)) {
        ViewFrames previewFrames = prepared.frames();
        const PassStats stats = renderPass(job, ++m_frames, 1, prepared, previewFrames);
        if (stats.cancelled)
            return;
        previewMs = stats.seconds * 1000.0;
        sendFrame(job, previewFrames, prepared, stats, 0, false, true, nlohmann::json());
        prepared = m_renderer.prepare(request.resolved, policy);  // the preview's renderers are no longer valid
    }
    const int level = prepared.level;
    if (frameKey != m_playbackKey) {
        m_playbackKey = frameKey;
        m_playbackLevel = -1;
        m_playbackLevelCounts.assign(dataset.levels().size(), 0);
    }
    if (request.mode == FrameMode::playback && size_t(level) < m_playbackLevelCounts.size()) {
        ++m_playbackLevelCounts[size_t(level)];
        m_playbackLevel = typicalPlaybackLevel(m_playbackLevelCounts);
    }

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
    // states anyway). A step of playback takes them from the coarsest level too.
    const bool quickSelection = request.mode != FrameMode::still;
    const int selectionLevel = quickSelection ? int(dataset.levels().size()) - 1 : level;
    const std::string selectionKey = fmt::format("{}/{}/{}", step, selectionLevel, job.document["brushes"].dump());
    if (quickSelection)
        updateSelection(selectionKey, step, selectionLevel, prepared);

    const double waitedMs = std::chrono::duration<double, std::milli>(renderStart - request.received).count();
    const double preparedMs = millisecondsSince(renderStart);
    ViewFrames frames = prepared.frames();
    // While steps are still rendered ahead, a step of playback gets one pass (its last) and leaves
    // the cores to them: refining a frame shown once is worth less than the next loop at level 0.
    const bool onePass = request.mode == FrameMode::playback && m_aheadBusy;
    double renderMsTotal = 0, firstPassMs = 0;
    int done = 0, unsent = 0;
    for (int pass = 1; pass <= job.passes; ++pass) {
        if (m_cancel)
            break;
        const PassStats stats = renderPass(job, frameNumber, pass, prepared, frames);
        if (stats.cancelled)
            break;
        // Adaptive refinement (a still state's convergenceGreyLevels) may have stopped every block:
        // this frame is final, further passes would render nothing.
        const bool refined = std::all_of(frames.begin(), frames.end(), [](const FrameBuffer& f) { return f.converged(); });
        const bool finished = pass == job.passes || refined;
        const bool last = finished || onePass;
        renderMsTotal += stats.seconds * 1000.0;
        if (pass == 1)
            firstPassMs = stats.seconds * 1000.0;
        done = pass;
        // A step of playback is shown when its time is up (timeBudgetMs after it came), with the
        // newest pass that has arrived: a later pass is neither encoded nor sent when the next one
        // is predicted (from this one's time, with a quarter to spare) to be done before then.
        if (request.mode == FrameMode::playback && pass > 1 && !last &&
            1.25 * stats.seconds * 1000.0 < state.timeBudgetMs - millisecondsSince(request.received)) {
            ++unsent;
            continue;
        }
        const auto frame = sendFrame(job, frames, prepared, stats, pass, last, false,
                                     selectionKey == m_selectionKey ? m_selection : nlohmann::json());
        // A finished frame at still quality (the state's level, else 0; full size; every pass) is
        // what rendering ahead would make: kept for the next time this step is asked; a step of
        // playback's one pass at full size and at most the drafts' level is kept as a draft (what
        // the ahead thread's first round makes).
        const bool atStillQuality = finished && prepared.level == state.level.value_or(0);
        const bool asDraft = onePass && prepared.level <= draftLevel(state);
        if ((atStillQuality || asDraft) && !job.interactive && prepared.divisor == 1) {
            frame->finished = atStillQuality;
            m_frameCache.insert(frameKey, step, frame);
        }
        if (pass == 1 && job.interactive) {
            const double overhead = (preparedMs + job.encodeMs) / 1000.0;
            m_context.frameOverheadSeconds.store(averagedMeasure(m_context.frameOverheadSeconds.load(), overhead));
        }
        updateSelection(selectionKey, step, selectionLevel, prepared);
        if (last)
            break;
    }
    if (done > 0)
        spdlog::info("{}: state {} step {} level {} {}x{} {}: waited {:.1f} ms, prepared {:.1f} ms, {}/{} passes, "
                     "first {:.1f} ms, mean {:.1f} ms/pass, encode {:.1f} ms/frame{}{}",
                     m_name, request.id, step, level, frames.front().width() * int(frames.size()), frames.front().height(),
                     frameModeName(request.mode), waitedMs, preparedMs, done, job.passes, firstPassMs,
                     renderMsTotal / done, job.encodeMs / std::max(1, done - unsent),
                     unsent > 0 ? fmt::format(", {} passes not sent", unsent) : std::string(),
                     previewMs > 0 ? fmt::format(", after a preview of {:.1f} ms", previewMs) : std::string());
}

}  // namespace raypc::server
