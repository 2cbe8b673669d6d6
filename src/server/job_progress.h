// Where a long statistics request is (POST /api/features?job=ID): the client names the request with
// an id of its own and asks GET /api/job-progress?job=ID while it waits (docs/protocol.md,
// JobProgress), so that the UI can say "step 5 of 12" rather than count seconds. The registry keeps
// the last kJobsKept jobs; an id it does not know (never started, or long forgotten) is "unknown".
//
// Thread safety: every member function may be called from any thread.
#pragma once

#include <nlohmann/json.hpp>

#include <chrono>
#include <deque>
#include <mutex>
#include <string>
#include <string_view>

namespace raypc::server {

class JobProgress {
public:
    static constexpr size_t kJobsKept = 32;

    // Throws raypc::Error unless `id` is 1-64 characters of letters, digits, '-' and '_'.
    static void checkId(std::string_view id);

    // The job runs: `done` of `total` steps (call again as steps are done).
    void running(const std::string& id, int done, int total);
    // It ended: answered ("done") or not ("failed", e.g. cancelled or refused).
    void ended(const std::string& id, bool answered);

    // {job, state: "unknown" (not started: waiting behind another request, or forgotten) | "running" |
    //  "done" | "failed", done, total, elapsedSeconds}.
    nlohmann::json toJson(const std::string& id) const;

private:
    struct Job {
        std::string id, state;
        int done = 0, total = 0;
        std::chrono::steady_clock::time_point start;
    };
    Job& find(const std::string& id);  // adding it (and forgetting the oldest) when new; holds m_mutex
    mutable std::mutex m_mutex;
    std::deque<Job> m_jobs;
};

}  // namespace raypc::server
