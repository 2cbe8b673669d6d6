// Critical points and pathlines on the full-resolution (180 x 201 x 360) synthetic model built in
// memory (synthesizeSnapshot): 11 steps 2 Myr apart, only vx, vy, vz kept (1.7 GB) plus the
// temperature anomaly of step 0.
//   BM_CriticalPoints: classify all 13 M vertices of step 0 (seconds per step).
//   BM_Pathlines: trace the seeds of step 0 (default rule: persistence > 5% of the range, <= 200) for 10 steps,
//     counter "lines/s" (and points per line), with 1 thread and with every core.
// No peer is measured here: the paper traced pathlines outside its tool (ParaView).
//   build-paths/bench/pathlines_bench --benchmark_min_time=1
#include "bench_util.h"
#include "analysis/critical_points.h"
#include "analysis/pathlines.h"
#include "analysis/persistence.h"
#include "synth/synth.h"

#include <benchmark/benchmark.h>
#include <fmt/format.h>
#include <tbb/task_arena.h>

#include <cmath>
#include <thread>

using namespace raypc;

namespace {

struct Data {
    analysis::FieldSeries series;
    std::vector<std::vector<float>> velocity;  // 3 per step
    std::vector<float> anomaly;                // step 0
    std::vector<analysis::CriticalPoint> seeds;
};

const Data& data()
{
    static const Data d = [] {
        Data out;
        const synth::SynthOptions o = bench::fullResolution();
        const int steps = 11;
        out.velocity.reserve(3 * steps);
        for (int k = 0; k < steps; ++k) {
            grid::Snapshot s = synth::synthesizeSnapshot(o, k * o.dtMyr);
            if (k == 0) {
                out.series.grid = s.grid;
                out.anomaly = std::move(s.find("temperature anomaly")->values);
            }
            std::vector<const float*> fields;
            for (const char* name : {"vx", "vy", "vz"})
                fields.push_back(out.velocity.emplace_back(std::move(s.find(name)->values)).data());
            out.series.timesMyr.push_back(k * o.dtMyr);
            out.series.fields.push_back(fields);
        }
        const auto all = analysis::findCriticalPoints(out.series.grid, out.anomaly);
        const analysis::SeedSelection selection = analysis::selectSeeds(out.series.grid, out.anomaly, all, analysis::CriticalPointFilter{});
        out.seeds = selection.seeds;
        fmt::print(stderr, "grid {}x{}x{}, {} critical points in step 0, {} seeds (persistence > {:.1f} K)\n", o.nLat,
                   o.nR, o.nLon, all.size(), out.seeds.size(), selection.threshold);
        return out;
    }();
    return d;
}

using bench::threadsFor;

void BM_CriticalPoints(benchmark::State& state)
{
    const Data& d = data();
    tbb::task_arena arena(threadsFor(static_cast<int>(state.range(0))));
    size_t found = 0;
    for (auto _ : state)
        arena.execute([&] { found = analysis::findCriticalPoints(d.series.grid, d.anomaly).size(); });
    state.counters["critical_points"] = static_cast<double>(found);
    state.counters["Mvertices/s"] = benchmark::Counter(static_cast<double>(d.anomaly.size()) * 1e-6,
                                                       benchmark::Counter::kIsIterationInvariantRate);
    state.counters["threads"] = threadsFor(static_cast<int>(state.range(0)));
}

void BM_Pathlines(benchmark::State& state)
{
    const Data& d = data();
    const analysis::PathlineTracer tracer(d.series, 0, 1, 2);
    tbb::task_arena arena(threadsFor(static_cast<int>(state.range(0))));
    analysis::PathlineSet set;
    for (auto _ : state)
        arena.execute([&] {
            set = analysis::tracePathlines(d.series, tracer, d.seeds, 0, 10, {"vx", "vy", "vz"}, {"m/s", "m/s", "m/s"});
        });
    state.counters["lines/s"] =
        benchmark::Counter(static_cast<double>(set.lineCount()), benchmark::Counter::kIsIterationInvariantRate);
    state.counters["points/line"] = set.lineCount() ? double(set.pointCount()) / set.lineCount() : 0;
    double length = 0;
    for (size_t i = 0; i < set.lineCount(); ++i)
        length += set.attribute(i, set.column("length"));
    state.counters["km/line"] = set.lineCount() ? length / set.lineCount() : 0;
    state.counters["threads"] = threadsFor(static_cast<int>(state.range(0)));
}

}  // namespace

BENCHMARK(BM_CriticalPoints)->Arg(1)->Arg(0)->Unit(benchmark::kMillisecond)->UseRealTime();
BENCHMARK(BM_Pathlines)->Arg(1)->Arg(0)->Unit(benchmark::kMillisecond)->UseRealTime();

BENCHMARK_MAIN();
