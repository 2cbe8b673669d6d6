// What the benchmarks that run with 1 thread and with every core share (header-only).
#pragma once

#include <sys/resource.h>

#include <thread>

namespace raypc::bench {

// A benchmark's thread argument: 0 means every core.
inline int threadsFor(int arg) { return arg == 0 ? static_cast<int>(std::thread::hardware_concurrency()) : arg; }

// The process's CPU time (user and system) so far, seconds: per iteration and thread, what a
// benchmark would take on an otherwise idle machine (the cores are often shared).
inline double processCpuSeconds()
{
    rusage u{};
    getrusage(RUSAGE_SELF, &u);
    return double(u.ru_utime.tv_sec + u.ru_stime.tv_sec) + 1e-6 * double(u.ru_utime.tv_usec + u.ru_stime.tv_usec);
}

}  // namespace raypc::bench
