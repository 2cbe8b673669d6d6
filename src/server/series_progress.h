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

namespace raypc::server {

class SeriesProgress {
public:
    // `dataset`: where the whole series is written; `steps`: how many input files it has.
    SeriesProgress(std::filesystem::path dataset, int steps);

    void update(const preprocess::PreprocessProgress& progress);
    // The whole series is written: the server switches to it (the UI reloads).
    void finished();
    // The run stopped with `message`; the server goes on showing the first step.
    void failed(std::string message);

    // {state: "preparing" | "ready" | "failed", dataset, steps, phase: "steps" | "pathlines",
    //  done, total, elapsedSeconds, etaSeconds (null until something was done), message (when failed)}.
    nlohmann::json toJson() const;

private:
    const std::filesystem::path m_dataset;
    const int m_steps;
    const std::chrono::steady_clock::time_point m_start = std::chrono::steady_clock::now();
    mutable std::mutex m_mutex;
    std::string m_state = "preparing", m_phase = "steps", m_message;
    int m_done = 0, m_total = 0;
    int m_doneAtPhaseStart = 0;  // `done` before this run's first item of the phase, for the rate
    std::chrono::steady_clock::time_point m_phaseStart = m_start, m_lastUpdate = m_start;
    bool m_phaseSeen = false;
};

}  // namespace raypc::server
