// Features, their links and shell fluxes on the synthetic model built in memory
// (synthesizeSnapshot), two full-resolution (180 x 201 x 360, 13 M points) steps at 0 and 2 Myr
// (default seed), with the derived variables preprocessing adds (addDerivedVariables: radial
// velocity among them), as StepVolume::fromSnapshot. The selection is task 1's preset
// (examples/task1-slabs-660km.json): depth 560-760 km, radial velocity <= 0 cm/yr, temperature
// anomaly <= -25 K, resolved by name as the server and the CLI resolve brushes.
//   BM_ExtractFeatures: extractFeatures of one step (selection, connected components, every
//     feature's statistics), with 1 thread and with every core. Target: <= 1 s on 2 cores.
//   BM_LinkFeatures: linkFeatures of the two steps' features (extracted once, outside the timed
//     loop) over 2 Myr in the earlier step's vx, vy, vz. Target: <= 0.5 s. It runs on one thread
//     (the "all cores" run shows that the other cores do not help).
//   BM_ShellFlux: shellFluxes of one step at 660 and 1600 km depth within the selection.
// Counters: cpu_s/thread (process CPU time per iteration divided by the threads, as in
// persistence_bench.cpp), Mpoints/s (extraction and flux: the grid's points; linking: the points
// of the earlier step's features, the ones it moves), features, links.
//   build/bench/features_bench --benchmark_min_time=1
#include "bench_util.h"
#include "core/error.h"
#include "core/system_memory.h"
#include "dataset/dataset.h"
#include "analysis/features.h"
#include "analysis/flux.h"
#include "preprocess/preprocess_numerics.h"
#include "analysis/selection.h"
#include "synth/synth.h"

#include <benchmark/benchmark.h>
#include <fmt/format.h>
#include <tbb/task_arena.h>

#include <sys/resource.h>

#include <algorithm>
#include <memory>
#include <string>
#include <thread>
#include <vector>

using namespace raypc;

namespace {

struct Steps {
    std::shared_ptr<dataset::StepVolume> volumes[2];  // 0 and 2 Myr
    std::vector<std::string> names;          // the volumes' variables, in order
    std::vector<analysis::RangeFilter> filters;        // task 1's selection
    analysis::VelocityVariables velocity;
    size_t radialVelocity = 0;
};

size_t variableIndex(const std::vector<std::string>& names, const std::string& name)
{
    const auto it = std::find(names.begin(), names.end(), name);
    if (it == names.end())
        fail("features_bench: the synthetic step has no variable '{}'", name);
    return size_t(it - names.begin());
}

// Built once: the snapshots are dropped as soon as their volumes hold the values (two steps of
// eleven variables take about 1.2 GB as it is).
const Steps& steps()
{
    static const Steps s = [] {
        const synth::SynthOptions o = bench::fullResolution();
        Steps out;
        for (int k = 0; k < 2; ++k) {
            grid::Snapshot snapshot = synth::synthesizeSnapshot(o, k * o.dtMyr);
            preprocess::addDerivedVariables(snapshot);  // what preprocessing stores with the step
            if (k == 0)
                for (const grid::Field& f : snapshot.fields)
                    out.names.push_back(f.name);
            out.volumes[k] = dataset::StepVolume::fromSnapshot(snapshot);
        }
        const std::vector<analysis::NamedRange> brushes = {
            {"depth", 560, 760}, {"radial velocity", -100, 0}, {"temperature anomaly", -10000, -25}};
        out.filters = analysis::resolveRangeFilters(out.names, brushes);
        out.velocity = {variableIndex(out.names, "vx"), variableIndex(out.names, "vy"), variableIndex(out.names, "vz")};
        out.radialVelocity = variableIndex(out.names, "radial velocity");
        return out;
    }();
    return s;
}

// Runs `work` in an arena of the benchmark's threads and sets the shared counters; `points` is what
// one iteration goes through (for Mpoints/s).
template <typename F>
void timed(benchmark::State& state, size_t points, F work)
{
    bench::timedInArena(state, "Mpoints/s", static_cast<double>(points) * 1e-6, work);
}

void BM_ExtractFeatures(benchmark::State& state)
{
    const Steps& s = steps();
    size_t found = 0;
    timed(state, s.volumes[0]->grid().cellCount(), [&] {
        analysis::StepFeatures f = analysis::extractFeatures(*s.volumes[0], s.filters);
        found = f.features.size();
        benchmark::DoNotOptimize(f);
    });
    state.counters["features"] = static_cast<double>(found);
}

void BM_LinkFeatures(benchmark::State& state)
{
    const Steps& s = steps();
    // Extracted once: only the linking is timed.
    static const analysis::StepFeatures a = analysis::extractFeatures(*s.volumes[0], s.filters);
    static const analysis::StepFeatures b = analysis::extractFeatures(*s.volumes[1], s.filters);
    const size_t moved = a.labels.size() - size_t(std::count(a.labels.begin(), a.labels.end(), 0));
    size_t links = 0;
    timed(state, moved, [&] {
        auto l = analysis::linkFeatures(*s.volumes[0], a, b, s.velocity, 2.0);
        links = l.size();
        benchmark::DoNotOptimize(l);
    });
    state.counters["features"] = static_cast<double>(a.features.size());
    state.counters["links"] = static_cast<double>(links);
}

void BM_ShellFlux(benchmark::State& state)
{
    const Steps& s = steps();
    const std::vector<double> depthsKm = {660, 1600};
    timed(state, s.volumes[0]->grid().cellCount(), [&] {
        auto fluxes = analysis::shellFluxes(*s.volumes[0], s.radialVelocity, depthsKm, s.filters);
        benchmark::DoNotOptimize(fluxes);
    });
}

}  // namespace

BENCHMARK(BM_ExtractFeatures)->Arg(1)->Arg(0)->Unit(benchmark::kMillisecond)->UseRealTime();
BENCHMARK(BM_LinkFeatures)->Arg(1)->Arg(0)->Unit(benchmark::kMillisecond)->UseRealTime();
BENCHMARK(BM_ShellFlux)->Arg(1)->Arg(0)->Unit(benchmark::kMillisecond)->UseRealTime();

int main(int argc, char** argv)
{
    raypc::restartWithTransparentHugePages(argv);  // memory as `raypc` has it (render_bench.cpp)
    benchmark::Initialize(&argc, argv);
    fmt::print("machine: {} hardware threads\n", std::thread::hardware_concurrency());
    benchmark::RunSpecifiedBenchmarks();
    benchmark::Shutdown();
    return 0;
}
