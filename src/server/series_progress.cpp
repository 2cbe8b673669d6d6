#include "server/series_progress.h"

#include <algorithm>
#include <iterator>
#include <utility>

namespace raypc::server {

using nlohmann::json;

SeriesProgress::SeriesProgress(std::filesystem::path dataset, int steps, Clock::time_point start)
    : m_dataset(std::move(dataset)), m_steps(steps), m_start(start), m_lastUpdate(start)
{
}

void SeriesProgress::update(const preprocess::PreprocessProgress& progress, Clock::time_point now)
{
    std::lock_guard lock(m_mutex);
    auto phase = std::find_if(m_phases.begin(), m_phases.end(), [&](const Phase& p) { return p.name == progress.phase; });
    if (phase == m_phases.end()) {
        // The run's first report says what an earlier run finished, before any item of this run:
        // those are in `done` but took no time. A later phase's first report comes after its first
        // item: its rate counts from the report before it.
        const bool first = m_phases.empty();
        Phase added;
        added.name = progress.phase;
        added.doneAtStart = first ? progress.done : progress.done - 1;
        added.start = first ? now : m_lastUpdate;
        m_phases.push_back(added);
        phase = std::prev(m_phases.end());
    }
    phase->done = progress.done;
    phase->total = progress.total;
    phase->lastUpdate = now;
    m_lastUpdate = now;
}

void SeriesProgress::finished()
{
    std::lock_guard lock(m_mutex);
    m_state = "ready";
}

void SeriesProgress::failed(std::string message)
{
    std::lock_guard lock(m_mutex);
    m_state = "failed";
    m_message = std::move(message);
}

json SeriesProgress::toJson(Clock::time_point now) const
{
    std::lock_guard lock(m_mutex);
    // Before the first report: the steps, none done yet.
    Phase none;
    none.name = "steps";
    none.total = m_steps;
    const auto unfinished = std::find_if(m_phases.begin(), m_phases.end(), [](const Phase& p) { return p.done < p.total; });
    const Phase& shown = m_phases.empty() ? none : unfinished != m_phases.end() ? *unfinished : m_phases.back();
    json j = {{"state", m_state},
              {"dataset", m_dataset.string()},
              {"steps", m_steps},
              {"phase", shown.name},
              {"done", shown.done},
              {"total", shown.total},
              {"elapsedSeconds", std::chrono::duration<double>(now - m_start).count()},
              {"etaSeconds", nullptr}};
    // The time left of the phase shown, at this run's rate in it. A one-pass run traces a pathline
    // set as soon as the steps it needs are written: while steps remain, the sets follow them.
    const int doneHere = shown.done - shown.doneAtStart;
    if (m_state == "preparing" && doneHere > 0) {
        const double perItem = std::chrono::duration<double>(shown.lastUpdate - shown.start).count() / doneHere;
        j["etaSeconds"] = std::max(
            0.0, perItem * (shown.total - shown.done) - std::chrono::duration<double>(now - shown.lastUpdate).count());
    }
    if (m_state == "failed")
        j["message"] = m_message;
    return j;
}

}  // namespace raypc::server
