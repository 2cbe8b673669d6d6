#include "server/series_progress.h"

#include <algorithm>
#include <utility>

namespace raypc::server {

using nlohmann::json;

SeriesProgress::SeriesProgress(std::filesystem::path dataset, int steps)
    : m_dataset(std::move(dataset)), m_steps(steps), m_total(steps)
{
}

void SeriesProgress::update(const preprocess::PreprocessProgress& progress)
{
    std::lock_guard lock(m_mutex);
    const auto now = std::chrono::steady_clock::now();
    if (!m_phaseSeen) {
        // The run's first report says what an earlier run finished, before any item of this run:
        // those are in `done` but took no time.
        m_phaseStart = now;
        m_doneAtPhaseStart = progress.done;
        m_phase = progress.phase;
        m_phaseSeen = true;
    } else if (progress.phase != m_phase) {
        // A later phase's first report comes after its first item: the rate counts the items this run
        // did since the previous report.
        m_phaseStart = m_lastUpdate;
        m_doneAtPhaseStart = progress.done - 1;
        m_phase = progress.phase;
    }
    m_lastUpdate = now;
    m_done = progress.done;
    m_total = progress.total;
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

json SeriesProgress::toJson() const
{
    std::lock_guard lock(m_mutex);
    const auto now = std::chrono::steady_clock::now();
    json j = {{"state", m_state},
              {"dataset", m_dataset.string()},
              {"steps", m_steps},
              {"phase", m_phase},
              {"done", m_done},
              {"total", m_total},
              {"elapsedSeconds", std::chrono::duration<double>(now - m_start).count()},
              {"etaSeconds", nullptr}};
    const int doneHere = m_done - m_doneAtPhaseStart;
    const double perItem = std::chrono::duration<double>(m_lastUpdate - m_phaseStart).count() / std::max(doneHere, 1);
    if (m_state == "preparing" && doneHere > 0)
        j["etaSeconds"] =
            std::max(0.0, perItem * (m_total - m_done) - std::chrono::duration<double>(now - m_lastUpdate).count());
    if (m_state == "failed")
        j["message"] = m_message;
    return j;
}

}  // namespace raypc::server
