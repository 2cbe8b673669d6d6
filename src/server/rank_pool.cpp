#include "server/rank_pool.h"

#include "core/clock.h"
#include "core/error.h"
#include "core/mpi.h"

#include <fmt/format.h>
#include <fmt/ranges.h>
#include <nlohmann/json.hpp>
#include <spdlog/spdlog.h>

#include <chrono>
#include <csignal>
#include <cstring>
#include <exception>
#include <mutex>
#include <optional>
#include <thread>

namespace raypc::server {

using nlohmann::json;
using Clock = std::chrono::steady_clock;

namespace {

// Message tags (core/mpi.h send/tryReceive).
enum Tag : int {
    kTagPass = 1,
    kTagCancel = 2,  // a pass's or a job's, by its seq
    kTagDrop = 3,
    kTagStop = 4,
    kTagAnswer = 5,
    kTagPrepare = 6,
    kTagJob = 7,
    kTagJobAnswer = 8,
};

// A job's answer: a JSON header line ({seq}, with "error" or "cancelled" when it has no result)
// and the result's bytes.
std::string jobAnswer(const json& header, const std::string& bytes = {})
{
    return header.dump() + '\n' + bytes;
}


// What a rank needs to prepare a session's frame (kTagPrepare; a pass adds "seq" and "pass").
json frameJob(uint64_t session, uint64_t frame, const render::ResolvedState& resolved, render::LevelChoice choice)
{
    return {{"session", session},
            {"frame", frame},
            {"level", choice.level},
            {"divisor", choice.divisor},
            {"state", state::toJson(resolved.state)}};
}

}  // namespace

// ---- rank 0 ----------------------------------------------------------------------------------

RankPool::RankPool() : m_ranks(mpi::size())
{
    RAYPC_CHECK(mpi::distributed() && mpi::isRoot());
}

RankPool::~RankPool() = default;

uint64_t RankPool::openSession()
{
    std::lock_guard lock(m_mutex);
    return m_nextSession++;
}

void RankPool::closeSession(uint64_t session)
{
    {
        std::lock_guard lock(m_mutex);
        if (m_stopping || !m_broken.empty())
            return;
        auto task = std::make_unique<Task>();
        task->tag = kTagDrop;
        task->bytes = std::to_string(session);
        m_queue.push_back(std::move(task));
    }
    m_cv.notify_all();
}

void RankPool::prepare(uint64_t session, uint64_t frame, const render::ResolvedState& resolved,
                       render::LevelChoice choice)
{
    {
        std::lock_guard lock(m_mutex);
        if (m_stopping || !m_broken.empty())
            return;
        auto task = std::make_unique<Task>();
        task->tag = kTagPrepare;
        task->bytes = frameJob(session, frame, resolved, choice).dump();
        m_queue.push_back(std::move(task));
    }
    m_cv.notify_all();
}

render::PassStats RankPool::renderPass(uint64_t session, uint64_t frame, int pass,
                                       const render::ResolvedState& resolved,
                                       const render::StateRenderer::Prepared& prepared, render::ViewFrames& frames,
                                       const std::atomic<bool>* cancel)
{
    const auto start = Clock::now();
    auto task = std::make_unique<Task>();
    task->tag = kTagPass;
    task->cancel = cancel;
    std::future<std::vector<std::string>> answers = task->answers.get_future();
    uint64_t seq = 0;
    {
        std::lock_guard lock(m_mutex);
        if (!m_broken.empty())
            fail("{}", m_broken);
        if (m_stopping)
            fail("the server is stopping");
        seq = task->seq = m_nextSeq++;
        json job = frameJob(session, frame, resolved, {prepared.level, prepared.divisor});
        job["seq"] = seq;
        job["pass"] = pass;
        task->bytes = job.dump();
        m_queue.push_back(std::move(task));
    }
    m_cv.notify_all();

    // Rank 0's own tiles while the others render theirs; then theirs, whatever happened here, so
    // that the answers of this pass are taken before the next.
    render::PassStats total = prepared.renderPass(frames, cancel, {0, m_ranks});
    // When rank 0's own tiles stopped part-way, the pass is abandoned (a new state or the server's
    // stop follows): a rank that finished its tiles before the cancel reached it is not gathered,
    // since its blocks would be a pass ahead of rank 0's frame (FrameBuffer::unpackTiles refuses
    // that).
    const bool ownCancelled = total.cancelled;
    const std::vector<std::string> got = answers.get();  // throws when a rank stopped answering
    int stoppedPartWay = 0;
    for (size_t i = 0; i < got.size(); ++i) {
        const int rank = int(i) + 1;
        const size_t eol = got[i].find('\n');
        RAYPC_CHECK(eol != std::string::npos);
        const json header = json::parse(got[i].substr(0, eol));
        if (header.contains("error"))
            fail("rank {}: {}", rank, header["error"].get<std::string>());
        RAYPC_CHECK_EQ(header.at("seq").get<uint64_t>(), seq);
        if (header.at("cancelled").get<bool>()) {
            total.cancelled = true;
            ++stoppedPartWay;
            continue;
        }
        if (ownCancelled)
            continue;
        // The counters add up over ranks; the machine and brick figures stay rank 0's.
        total.addCounts(header.at("counts").get<render::PassStats::Counts>());
        // The floats follow the header; copied out, since the string's bytes need not be aligned.
        const size_t bytes = got[i].size() - eol - 1;
        RAYPC_CHECK_EQ(bytes % sizeof(float), size_t(0));
        std::vector<float> packed(bytes / sizeof(float));
        std::memcpy(packed.data(), got[i].data() + eol + 1, bytes);
        size_t offset = 0;
        for (render::FrameBuffer& f : frames)
            offset += f.unpackTiles(std::span<const float>(packed).subspan(offset), {rank, m_ranks});
        RAYPC_CHECK_EQ(offset, packed.size());
    }
    if (stoppedPartWay > 0)
        spdlog::info("distributed: session {} frame {} pass {}: {} of {} other ranks stopped part-way (cancelled)",
                     session, frame, pass, stoppedPartWay, m_ranks - 1);
    total.seconds = secondsSince(start);
    return total;
}

std::shared_future<std::vector<std::string>> RankPool::shareOut(json job, const std::atomic<bool>* cancel)
{
    auto task = std::make_unique<Task>();
    task->tag = kTagJob;
    task->cancel = cancel;
    std::shared_future<std::vector<std::string>> answers = task->answers.get_future().share();
    {
        std::lock_guard lock(m_mutex);
        if (!m_broken.empty())
            fail("{}", m_broken);
        if (m_stopping)
            fail("the server is stopping");
        task->seq = m_nextSeq++;
        job["seq"] = task->seq;
        task->bytes = job.dump();
        m_queue.push_back(std::move(task));
    }
    m_cv.notify_all();
    return answers;
}

void RankPool::takeJobAnswers()
{
    while (std::optional<mpi::Message> m = mpi::tryReceive(mpi::kAnySource, kTagJobAnswer)) {
        const size_t eol = m->bytes.find('\n');
        RAYPC_CHECK(eol != std::string::npos);
        const uint64_t seq = json::parse(m->bytes.substr(0, eol)).at("seq").get<uint64_t>();
        const auto it = m_jobs.find(seq);
        if (it == m_jobs.end()) {
            spdlog::debug("distributed: rank {} answered job {} after it was given up", m->source, seq);
            continue;
        }
        it->second.answers.at(size_t(m->source - 1)) = std::move(m->bytes);
    }
    bool stopping = false;
    {
        std::lock_guard lock(m_mutex);
        stopping = m_stopping;
    }
    for (auto it = m_jobs.begin(); it != m_jobs.end();) {
        Job& job = it->second;
        std::vector<int> silent;
        for (int r = 1; r < m_ranks; ++r)
            if (!job.answers[size_t(r - 1)])
                silent.push_back(r);
        if (silent.empty()) {
            std::vector<std::string> results;
            try {
                for (int r = 1; r < m_ranks; ++r) {
                    std::string& answer = *job.answers[size_t(r - 1)];
                    const size_t eol = answer.find('\n');
                    const json header = json::parse(answer.substr(0, eol));
                    if (header.contains("error"))
                        fail("rank {}: {}", r, header["error"].get<std::string>());
                    if (header.value("cancelled", false))
                        fail("cancelled (the client went away or the server is stopping)");
                    answer.erase(0, eol + 1);  // the packed steps, without copying them
                    results.push_back(std::move(answer));
                }
                job.task->answers.set_value(std::move(results));
            } catch (...) {
                job.task->answers.set_exception(std::current_exception());
            }
            it = m_jobs.erase(it);
            continue;
        }
        if (!job.cancelledAt && (stopping || (job.task->cancel && job.task->cancel->load()))) {
            for (const int r : silent)
                mpi::send(r, kTagCancel, std::to_string(it->first));
            job.cancelledAt = Clock::now();
        }
        if (job.cancelledAt && secondsSince(*job.cancelledAt) > kAnswerTimeoutSeconds) {
            job.task->answers.set_exception(std::make_exception_ptr(
                Error(fmt::format("distributed server: rank{} {} did not answer within {:.0f} s of a cancel",
                                  silent.size() > 1 ? "s" : "", fmt::join(silent, ", "), kAnswerTimeoutSeconds))));
            it = m_jobs.erase(it);
            continue;
        }
        ++it;
    }
}

void RankPool::stop()
{
    {
        std::lock_guard lock(m_mutex);
        m_stopping = true;
    }
    m_cv.notify_all();
}

std::vector<std::string> RankPool::collect(const Task& task, bool& broken, std::string& why)
{
    const int others = m_ranks - 1;
    for (int r = 1; r < m_ranks; ++r)
        mpi::send(r, kTagPass, task.bytes);
    std::vector<std::string> answers(static_cast<size_t>(others));
    std::vector<bool> answered(size_t(others), false);
    int missing = others;
    std::optional<Clock::time_point> cancelledAt;
    while (missing > 0) {
        bool arrived = false;
        for (int r = 1; r < m_ranks; ++r) {
            if (answered[size_t(r - 1)])
                continue;
            if (std::optional<mpi::Message> m = mpi::tryReceive(r, kTagAnswer)) {
                answers[size_t(r - 1)] = std::move(m->bytes);
                answered[size_t(r - 1)] = true;
                --missing;
                arrived = true;
            }
        }
        if (missing == 0)
            break;
        bool stopping = false;
        {
            std::lock_guard lock(m_mutex);
            stopping = m_stopping;
        }
        if (!cancelledAt && (stopping || (task.cancel && task.cancel->load()))) {
            for (int r = 1; r < m_ranks; ++r)
                if (!answered[size_t(r - 1)])
                    mpi::send(r, kTagCancel, std::to_string(task.seq));
            cancelledAt = Clock::now();
        }
        if (cancelledAt && secondsSince(*cancelledAt) > kAnswerTimeoutSeconds) {
            std::vector<int> silent;
            for (int r = 1; r < m_ranks; ++r)
                if (!answered[size_t(r - 1)])
                    silent.push_back(r);
            why = fmt::format("distributed server: rank{} {} did not answer within {:.0f} s of a cancel; the server "
                              "stops (MPI cannot go on without a rank)",
                              silent.size() > 1 ? "s" : "", fmt::join(silent, ", "), kAnswerTimeoutSeconds);
            broken = true;
            return {};
        }
        if (!arrived)
            std::this_thread::sleep_for(std::chrono::microseconds(200));
    }
    return answers;
}

bool RankPool::run(const std::function<void(const std::string&)>& onBroken)
{
    for (;;) {
        std::unique_ptr<Task> task;
        {
            std::unique_lock lock(m_mutex);
            if (m_jobs.empty())
                m_cv.wait(lock, [&] { return m_stopping || !m_queue.empty(); });
            else  // answers to take: look again soon
                m_cv.wait_for(lock, std::chrono::milliseconds(1), [&] { return !m_queue.empty(); });
            if (m_queue.empty() && m_stopping && m_jobs.empty())
                break;  // stopping, and nothing left: later calls fail at once
            if (!m_queue.empty()) {
                task = std::move(m_queue.front());
                m_queue.pop_front();
            }
        }
        if (task && task->tag == kTagJob) {
            for (int r = 1; r < m_ranks; ++r)
                mpi::send(r, kTagJob, task->bytes);
            const uint64_t seq = task->seq;
            m_jobs[seq] = Job{std::move(task), std::vector<std::optional<std::string>>(size_t(m_ranks - 1)), {}};
        } else if (task && task->tag != kTagPass) {
            for (int r = 1; r < m_ranks; ++r)
                mpi::send(r, task->tag, task->bytes);
        } else if (task) {
            bool broken = false;
            std::string why;
            std::vector<std::string> answers = collect(*task, broken, why);
            if (broken) {
                spdlog::error("{}", why);
                std::deque<std::unique_ptr<Task>> left;
                {
                    std::lock_guard lock(m_mutex);
                    m_broken = why;
                    left.swap(m_queue);
                }
                const auto error = std::make_exception_ptr(Error(why));
                task->answers.set_exception(error);
                for (auto& t : left)
                    if (t->tag == kTagPass || t->tag == kTagJob)
                        t->answers.set_exception(error);
                for (auto& [seq, job] : m_jobs)
                    job.task->answers.set_exception(error);
                m_jobs.clear();
                onBroken(why);
                return false;
            }
            task->answers.set_value(std::move(answers));
        }
        if (!m_jobs.empty())
            takeJobAnswers();
    }
    for (int r = 1; r < m_ranks; ++r)
        mpi::send(r, kTagStop, "");
    spdlog::info("distributed: ranks 1..{} stopped", m_ranks - 1);
    return true;
}

// ---- ranks 1..N-1 ----------------------------------------------------------------------------

struct WorkerRank::Session {
    Session(std::shared_ptr<const dataset::Dataset> dataset, render::StateSources sources)
        : renderer(std::move(dataset), std::move(sources))
    {
    }
    render::StateRenderer renderer;
    uint64_t frame = 0;
    std::optional<render::StateRenderer::Prepared> prepared;
    render::ViewFrames frames;
};

WorkerRank::WorkerRank(const std::filesystem::path& dataset, size_t cacheBytes, size_t cacheEntries)
    : m_caches(openDatasetCaches(dataset, cacheBytes, cacheEntries))
{
}

WorkerRank::~WorkerRank() = default;

namespace {
volatile std::sig_atomic_t g_signal = 0;
extern "C" void noteSignal(int signal) { g_signal = signal; }
}  // namespace

void WorkerRank::run()
{
    // mpirun passes SIGINT/SIGTERM to every rank: rank 0 then stops serving and tells this rank to
    // stop, so that every rank ends normally (exit status 0). Should rank 0 not do so in time, this
    // rank ends the job with an error.
    std::signal(SIGINT, noteSignal);
    std::signal(SIGTERM, noteSignal);
    std::optional<Clock::time_point> signalled;
    // Poll with a short sleep: a blocking MPI receive busy-waits and would take a core from the
    // ranks that render on the same node.
    auto idle = std::chrono::microseconds(100);
    for (;;) {
        if (g_signal && !signalled)
            signalled = Clock::now();
        if (signalled && secondsSince(*signalled) > kAnswerTimeoutSeconds)
            fail("distributed server: rank {} got signal {} and rank 0 did not stop the server within {:.0f} s",
                 mpi::rank(), int(g_signal), kAnswerTimeoutSeconds);
        sendFinishedJobs();
        std::optional<mpi::Message> m = mpi::tryReceive(0, mpi::kAnyTag);
        if (!m) {
            std::this_thread::sleep_for(idle);
            idle = std::min(idle * 2, std::chrono::microseconds(2000));
            continue;
        }
        idle = std::chrono::microseconds(100);
        switch (m->tag) {
        case kTagStop:
            endJobs();
            return;
        case kTagDrop:
            m_sessions.erase(std::stoull(m->bytes));
            break;
        case kTagCancel:
            noteCancel(m->bytes);  // a job's, or a pass's already answered
            break;
        case kTagJob:
            startJob(m->bytes);
            break;
        case kTagPass:
            mpi::send(0, kTagAnswer, renderPass(m->bytes));
            break;
        case kTagPrepare:
            prepareAhead(m->bytes);
            break;
        default:
            fail("distributed server: rank {} got a message with the unknown tag {}", mpi::rank(), m->tag);
        }
    }
}

void WorkerRank::startJob(const std::string& text)
{
    uint64_t seq = 0;
    json job;
    try {
        job = json::parse(text);
        seq = job.at("seq").get<uint64_t>();
    } catch (const std::exception& e) {
        m_sent.push_back(std::make_unique<mpi::PendingSend>(0, kTagJobAnswer, jobAnswer({{"seq", seq}, {"error", e.what()}})));
        return;
    }
    auto running = std::make_unique<RunningJob>();
    RunningJob& r = *running;
    r.answer = std::async(std::launch::async, [this, &r, seq, job = std::move(job)] {
        try {
            const std::string packed =
                featureBlockOfJob(*m_caches.dataset, *m_caches.volumes, job, mpi::rank(), mpi::size(), &r.cancel);
            return jobAnswer({{"seq", seq}}, packed);
        } catch (const std::exception& e) {
            if (r.cancel)
                return jobAnswer({{"seq", seq}, {"cancelled", true}});
            return jobAnswer({{"seq", seq}, {"error", e.what()}});
        }
    });
    m_jobs[seq] = std::move(running);
}

void WorkerRank::noteCancel(const std::string& seq)
{
    try {
        if (const auto it = m_jobs.find(std::stoull(seq)); it != m_jobs.end())
            it->second->cancel = true;
    } catch (const std::exception&) {  // not a number: no job of ours
    }
}

void WorkerRank::sendFinishedJobs()
{
    for (auto it = m_jobs.begin(); it != m_jobs.end();) {
        if (it->second->answer.wait_for(std::chrono::seconds(0)) != std::future_status::ready) {
            ++it;
            continue;
        }
        m_sent.push_back(std::make_unique<mpi::PendingSend>(0, kTagJobAnswer, it->second->answer.get()));
        it = m_jobs.erase(it);
    }
    std::erase_if(m_sent, [](const std::unique_ptr<mpi::PendingSend>& s) { return s->done(); });
}

void WorkerRank::endJobs()
{
    // Rank 0 takes every job's answers before it says stop; a job still running here was given up.
    for (auto& [seq, job] : m_jobs)
        job->cancel = true;
    for (auto& [seq, job] : m_jobs)
        job->answer.wait();
    m_jobs.clear();
    m_sent.clear();
}

WorkerRank::Session& WorkerRank::session(uint64_t id)
{
    std::unique_ptr<Session>& slot = m_sessions[id];
    if (!slot)
        slot = std::make_unique<Session>(m_caches.dataset, cacheSources(m_caches.volumes.get(), m_caches.pathlines.get()));
    return *slot;
}

void WorkerRank::prepare(Session& s, const json& job)
{
    s.prepared.reset();
    render::LevelPolicy policy;
    policy.chosen = render::LevelChoice{job.at("level").get<int>(), job.at("divisor").get<int>()};
    s.prepared = s.renderer.prepare(render::resolveState(job.at("state"), *m_caches.dataset), policy);
    s.frames = s.prepared->frames();
    s.frame = job.at("frame").get<uint64_t>();
}

void WorkerRank::prepareAhead(const std::string& text)
{
    // A failure here is the first pass's to report: that pass prepares again and answers with it.
    try {
        const auto start = Clock::now();
        const json job = json::parse(text);
        const uint64_t id = job.at("session").get<uint64_t>();
        prepare(session(id), job);
        spdlog::debug("distributed: rank {}: session {} frame {} prepared ahead of its first pass in {:.1f} ms",
                      mpi::rank(), id, job.at("frame").get<uint64_t>(), millisecondsSince(start));
    } catch (const std::exception& e) {
        spdlog::debug("distributed: rank {}: preparing ahead: {}", mpi::rank(), e.what());
    }
}

std::string WorkerRank::renderPass(const std::string& text)
{
    json header;
    std::string tiles;
    uint64_t seq = 0;
    try {
        const json job = json::parse(text);
        seq = job.at("seq").get<uint64_t>();
        const uint64_t id = job.at("session").get<uint64_t>(), frame = job.at("frame").get<uint64_t>();
        const int pass = job.at("pass").get<int>();
        Session& s = session(id);
        // Prepared ahead (kTagPrepare, at the same level and divisor) or not yet.
        if (s.frame != frame || !s.prepared || s.prepared->level != job.at("level").get<int>() ||
            s.prepared->divisor != job.at("divisor").get<int>()) {
            if (pass != 1)
                fail("pass {} of frame {} arrived before its first pass", pass, frame);
            const auto start = Clock::now();
            prepare(s, job);
            spdlog::debug("distributed: rank {}: session {} frame {} prepared at its first pass in {:.1f} ms",
                          mpi::rank(), id, frame, millisecondsSince(start));
        }
        if (s.frames.front().passes() != pass - 1)
            fail("pass {} of frame {} arrived after {} passes", pass, frame, s.frames.front().passes());

        // Render on another thread so that this one (MPI's) can take a cancel between tiles.
        std::atomic<bool> cancel{false};
        const render::TileShare share = render::rankTileShare();
        std::future<render::PassStats> rendered =
            std::async(std::launch::async, [&] { return s.prepared->renderPass(s.frames, &cancel, share); });
        const std::string mine = std::to_string(seq);
        while (rendered.wait_for(std::chrono::milliseconds(1)) != std::future_status::ready)
            if (std::optional<mpi::Message> c = mpi::tryReceive(0, kTagCancel)) {
                if (c->bytes == mine)
                    cancel = true;
                else
                    noteCancel(c->bytes);
            }
        const render::PassStats stats = rendered.get();
        mpi::dieHook("serve-pass");
        header = {{"seq", seq}, {"cancelled", stats.cancelled}, {"counts", stats.counts()}};
        if (!stats.cancelled)
            for (const render::FrameBuffer& f : s.frames) {
                const std::vector<float> packed = f.packTiles(share);
                tiles.append(reinterpret_cast<const char*>(packed.data()), packed.size() * sizeof(float));
            }
        else
            s.prepared.reset();  // rank 0 starts a new frame after a cancel
    } catch (const std::exception& e) {
        header = {{"seq", seq}, {"error", e.what()}};
        tiles.clear();
    }
    return header.dump() + '\n' + tiles;
}

}  // namespace raypc::server
