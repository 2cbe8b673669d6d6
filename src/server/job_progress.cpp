#include "server/job_progress.h"

#include "core/error.h"

#include <algorithm>
#include <cctype>

namespace raypc::server {

void JobProgress::checkId(std::string_view id)
{
    const bool ok = !id.empty() && id.size() <= 64 && std::all_of(id.begin(), id.end(), [](char c) {
        return std::isalnum(static_cast<unsigned char>(c)) || c == '-' || c == '_';
    });
    if (!ok)
        fail("job: '{}' is not a job id (1-64 letters, digits, '-' or '_')", id.substr(0, 80));
}

JobProgress::Job& JobProgress::find(const std::string& id)
{
    for (Job& j : m_jobs)
        if (j.id == id)
            return j;
    if (m_jobs.size() == kJobsKept)
        m_jobs.pop_front();
    m_jobs.push_back({id, "running", 0, 0, std::chrono::steady_clock::now()});
    return m_jobs.back();
}

void JobProgress::running(const std::string& id, int done, int total)
{
    std::lock_guard lock(m_mutex);
    Job& j = find(id);
    j.state = "running";
    j.done = done;
    j.total = total;
}

void JobProgress::ended(const std::string& id, bool answered)
{
    std::lock_guard lock(m_mutex);
    find(id).state = answered ? "done" : "failed";
}

nlohmann::json JobProgress::toJson(const std::string& id) const
{
    std::lock_guard lock(m_mutex);
    for (const Job& j : m_jobs)
        if (j.id == id)
            return {{"job", id},
                    {"state", j.state},
                    {"done", j.done},
                    {"total", j.total},
                    {"elapsedSeconds", std::chrono::duration<double>(std::chrono::steady_clock::now() - j.start).count()}};
    return {{"job", id}, {"state", "unknown"}, {"done", 0}, {"total", 0}, {"elapsedSeconds", 0.0}};
}

}  // namespace raypc::server
