// A series being preprocessed in the background while the server shows its first step (`raypc serve
// FILE.nc…`, app/serve_setup.h): where the run is, for GET /api/progress (docs/protocol.md) and the
// UI's status line. Written by the preprocessing thread, read by the network thread.
//
// Thread safety: every member function may be called from any thread.
#pragma once

#include "preprocess/preprocess.h"

#include <nlohmann/json.hpp>

#include <chrono>
#include <filesystem>
#include <mutex>
#include <string>
#include <vector>

namespace raypc::server {

class SeriesProgress {
public:
    using Clock = std::chrono::steady_clock;

    // `dataset`: where the whole series is written; `steps`: how many input files it has.
    SeriesProgress(std::filesystem::path dataset, int steps, Clock::time_point start = Clock::now());

    // `now`: when the report came (a parameter for tests).
    void update(const preprocess::PreprocessProgress& progress, Clock::time_point now = Clock::now());
    // The whole series is written: the server switches to it (the UI reloads).
    void finished();
    // The run stopped with `message`; the server goes on showing the first step.
    void failed(std::string message);

    // {state: "preparing" | "ready" | "failed", dataset, steps, phase: "steps" | "pathlines",
    //  done, total, elapsedSeconds, etaSeconds (null until something was done), message (when failed)}.
    // The phase shown is the first one reported that is not finished (a one-pass run reports steps
    // and pathline sets in turn: it shows the steps until they are all written, then the pathlines),
    // with its time left at this run's rate in that phase (not since the other phase's last report).
    nlohmann::json toJson(Clock::time_point now = Clock::now()) const;

private:
    struct Phase {
        std::string name;
        int done = 0, total = 0;
        int doneAtStart = 0;  // `done` before this run's first item of the phase, for the rate
        Clock::time_point start, lastUpdate;
    };

    const std::filesystem::path m_dataset;
    const int m_steps;
    const Clock::time_point m_start;
    mutable std::mutex m_mutex;
    std::string m_state = "preparing", m_message;
    std::vector<Phase> m_phases;  // in the order first reported
    Clock::time_point m_lastUpdate;
};

}  // namespace raypc::server
