// Ray-caster benchmarks on a full-resolution (180 x 201 x 360) synthetic step built in memory
// (synthesizeSnapshot), or on RAYPC_BENCH_DATASET (a preprocessed dataset directory, step 0).
// Prints per benchmark: seconds per pass and samples per second per thread (counter "Msamples/s/thread").
//   build-render/bench/render_bench --benchmark_min_time=1
#include "data/dataset.h"
#include "data/preprocess.h"
#include "data/synth.h"
#include "render/test_volumes.h"
#include "render/volume_renderer.h"

#include <benchmark/benchmark.h>
#include <tbb/task_arena.h>

#include <cstdlib>

using namespace raypc;
using namespace raypc::render;

namespace {

struct Data {
    std::vector<std::shared_ptr<const StepVolume>> levels;
    std::vector<std::string> names;
};

const Data& data()
{
    static const Data d = [] {
        Data out;
        if (const char* dir = std::getenv("RAYPC_BENCH_DATASET")) {
            const auto ds = Dataset::open(dir);
            for (int l = 0; l < int(ds->levels().size()); ++l)
                out.levels.push_back(ds->load(0, l));
            for (const auto& v : ds->variables())
                out.names.push_back(v.name);
            return out;
        }
        SynthOptions o;
        o.nLat = 180;
        o.nR = 201;
        o.nLon = 360;
        Snapshot s = synthesizeSnapshot(o, 0.0);
        for (const auto& f : s.fields)
            out.names.push_back(f.name);
        for (int l = 0; l < kLevelCount; ++l) {
            out.levels.push_back(StepVolume::fromSnapshot(s, 8));
            Snapshot coarse;
            coarse.grid = s.grid.coarsened();
            for (const auto& f : s.fields)
                coarse.fields.push_back({f.name, f.units, coarsenField(s.grid, f.values)});
            s = std::move(coarse);
        }
        return out;
    }();
    return d;
}

int var(const std::string& name)
{
    const auto& n = data().names;
    return int(std::find(n.begin(), n.end(), name) - n.begin());
}

RenderParams params(int size)
{
    RenderParams p;
    p.width = p.height = size;
    p.camera.distanceKm = 19000;
    p.camera.fovYDeg = 42;
    p.colorVariable = var("temperature anomaly");
    p.transfer.colorMap = ColorMapId::BlueWhiteRed;
    p.transfer.range = {-400, 400};
    p.transfer.opacity = {{0, 0.6f}, {0.4f, 0.0f}, {0.6f, 0.0f}, {1, 0.6f}};
    return p;
}

void report(benchmark::State& state, const PassStats& s, uint64_t samples, double seconds, int passes)
{
    state.counters["Msamples/s/thread"] = double(samples) / seconds / s.threads / 1e6;
    state.counters["ms/pass"] = 1e3 * seconds / passes;
    state.counters["threads"] = s.threads;
    state.counters["lanes"] = s.simdLanes;
}

void runPasses(benchmark::State& state, int level, const RenderParams& p, int passes)
{
    VolumeRenderer r(data().levels[size_t(level)]);
    r.setParams(p);
    uint64_t samples = 0;
    double seconds = 0;
    int total = 0;
    PassStats last;
    for (auto _ : state) {
        FrameBuffer f(p.width, p.height);
        for (int i = 0; i < passes; ++i) {
            last = r.renderPass(f);
            samples += last.samples + last.samplesSkipped;
            seconds += last.seconds;
            ++total;
        }
    }
    report(state, last, samples, seconds, total);
    state.counters["level"] = level;
}

void BM_InteractivePass512(benchmark::State& state)
{
    const RenderParams p = params(512);
    const int level = chooseLevelForBudget(data().levels, p, 0.050, 100e6 * tbb::this_task_arena::max_concurrency());
    runPasses(state, level, p, 1);
}
BENCHMARK(BM_InteractivePass512)->Unit(benchmark::kMillisecond);

void BM_Level0Pass512(benchmark::State& state) { runPasses(state, 0, params(512), 1); }
BENCHMARK(BM_Level0Pass512)->Unit(benchmark::kMillisecond);

void BM_Level0Pass512Scalar(benchmark::State& state)
{
    RenderParams p = params(512);
    p.kernel = KernelKind::Scalar;
    runPasses(state, 0, p, 1);
}
BENCHMARK(BM_Level0Pass512Scalar)->Unit(benchmark::kMillisecond);

// Converged: 8 jittered passes at 1024², full resolution.
void BM_Converged1024(benchmark::State& state) { runPasses(state, 0, params(1024), 8); }
BENCHMARK(BM_Converged1024)->Unit(benchmark::kMillisecond)->Iterations(1);

// Brushing four variables (about a fifth of the volume passes all four) against no brushing.
void BM_Brush4Pass512(benchmark::State& state)
{
    RenderParams p = params(512);
    p.brushes = {{var("temperature"), std::nullopt, 1800, 4000},
                 {var("thermal conductivity"), std::nullopt, 0, 100},
                 {var("vx"), std::nullopt, -1.0f, 1.0f},
                 {var("temperature anomaly"), std::nullopt, 50, 1000}};
    runPasses(state, 0, p, 1);
}
BENCHMARK(BM_Brush4Pass512)->Unit(benchmark::kMillisecond);

}  // namespace

BENCHMARK_MAIN();
