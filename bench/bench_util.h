// What the benchmarks share (header-only): the full-resolution synthetic model, and for the ones
// that run with 1 thread and with every core, the thread count, CPU time and a timed arena.
#pragma once

#include "synth/synth.h"

#include <benchmark/benchmark.h>
#include <tbb/task_arena.h>

#include <sys/resource.h>

#include <thread>

namespace raypc::bench {

// The synthetic model at the contest data's full resolution: 180 x 201 x 360 (lat x r x lon), 13 M
// points a step.
inline synth::SynthOptions fullResolution()
{
    synth::SynthOptions o;
    o.nLat = 180;
    o.nR = 201;
    o.nLon = 360;
    return o;
}

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

// Runs `work` once an iteration in an arena of the benchmark's threads (threadsFor its argument) and
// sets the counters cpu_s/thread, threads and `rate`: `millions` (of points, of vertices: what one
// iteration goes through) per second.
template <typename F>
void timedInArena(benchmark::State& state, const char* rate, double millions, F work)
{
    const int threads = threadsFor(static_cast<int>(state.range(0)));
    tbb::task_arena arena(threads);
    const double cpu0 = processCpuSeconds();
    for (auto _ : state)
        arena.execute(work);
    state.counters["cpu_s/thread"] = (processCpuSeconds() - cpu0) / double(state.iterations()) / threads;
    state.counters[rate] = benchmark::Counter(millions, benchmark::Counter::kIsIterationInvariantRate);
    state.counters["threads"] = threads;
}

}  // namespace raypc::bench
