// A progress bar with rate and ETA on a terminal; on a pipe or in CI it prints
// a plain line every ~10% instead, so logs stay readable.
//
// Thread safety: advance() may be called from any thread.
#pragma once

#include <atomic>
#include <chrono>
#include <cstdint>
#include <mutex>
#include <string>

namespace raypc {

class Progress {
public:
    // `unit` names what is counted ("steps", "cells"). Writes to stderr.
    Progress(std::string label, int64_t total, std::string unit);
    ~Progress();
    Progress(const Progress&) = delete;
    Progress& operator=(const Progress&) = delete;

    void advance(int64_t n = 1);
    void finish();

    // True when progress bars are drawn (stderr is a terminal and CI is unset).
    static bool interactive();

private:
    void draw(int64_t done, bool final);

    std::string m_label, m_unit;
    int64_t m_total;
    std::atomic<int64_t> m_done{0};
    std::chrono::steady_clock::time_point m_start;
    std::chrono::steady_clock::time_point m_lastDraw;
    int m_lastDecile = -1;
    bool m_interactive;
    bool m_finished = false;
    std::mutex m_mutex;
};

}  // namespace raypc
