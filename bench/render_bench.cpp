// Ray-caster benchmarks on a full-resolution (180 x 201 x 360) synthetic step built in memory
// (synthesizeSnapshot), or on RAYPC_BENCH_DATASET (a preprocessed dataset directory, step 0).
//   build-perf/bench/render_bench --benchmark_min_time=1
// Counters per benchmark:
//   ms/pass            wall time of one pass (all threads)
//   cpu_ms/pass/thread process CPU time of one pass divided by the threads: what a pass would take on
//                      an otherwise idle machine; printed because the cores are often shared
//   Msteps/s/thread    every sample position along the rays, including those in skipped space
//   Mdata/s/thread     samples that read data (in active bricks): the honest sampling rate
//   jumped%            share of chunks passed over by interval skipping without locating a sample
// Targets (2 cores): interactive 512² pass <= 50 ms, converged 1024² full resolution <= 3 s (the
// aim: <= 0.5 s, and 1920x1080 <= 1 s, by adaptive refinement: BM_ConvergedAdaptive*),
// >= 100 M samples/s/thread, brushing 4 variables (<= 20 % selected) not slower than no brushing.
#include "bench_util.h"
#include "core/system_memory.h"
#include "dataset/bricks.h"
#include "dataset/dataset.h"
#include "preprocess/preprocess.h"
#include "analysis/selection.h"
#include "synth/synth.h"
#include "render/image_io.h"
#include "render/reference_geometry.h"
#include "state/render_state.h"
#include "render/shadow_volume.h"
#include "render/slice_view.h"
#include "server/image_codec.h"
#include "render/state_renderer.h"
#include "render/volume_renderer.h"

#include <benchmark/benchmark.h>
#include <fmt/format.h>
#include <tbb/task_arena.h>

#include <sys/resource.h>

#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <map>
#include <string>

using namespace raypc;
using namespace raypc::render;

namespace {

struct Data {
    std::vector<std::shared_ptr<const dataset::StepVolume>> levels;
    std::vector<std::string> names;
};

const Data& data()
{
    static const Data d = [] {
        Data out;
        if (const char* dir = std::getenv("RAYPC_BENCH_DATASET")) {
            const auto ds = dataset::Dataset::open(dir);
            for (int l = 0; l < int(ds->levels().size()); ++l)
                out.levels.push_back(ds->load(0, l));
            for (const auto& v : ds->variables())
                out.names.push_back(v.name);
            return out;
        }
        grid::Snapshot s = synth::synthesizeSnapshot(bench::fullResolution(), 0.0);
        for (const auto& f : s.fields)
            out.names.push_back(f.name);
        for (int l = 0; l < dataset::kLevelCount; ++l) {
            out.levels.push_back(dataset::StepVolume::fromSnapshot(s, 8));
            grid::Snapshot coarse;
            coarse.grid = s.grid.coarsened();
            for (const auto& f : s.fields)
                coarse.fields.push_back({f.name, f.units, preprocess::coarsenField(s.grid, f.values)});
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

// The UI's first view (render::defaultState: temperature anomaly, lit, the middle of the range
// transparent) resolved against the benchmark volume's variables and ranges, at size x size.
// The benchmark step's variables with their ranges, for defaultState.
VariableCatalog benchCatalog()
{
    const dataset::StepVolume& v = *data().levels[0];
    VariableCatalog catalog;
    catalog.names = data().names;
    for (size_t i = 0; i < v.variableCount(); ++i) {
        const auto [lo, hi] = std::minmax_element(v.values(i), v.values(i) + v.grid().cellCount());
        catalog.ranges.push_back({*lo, *hi});
    }
    return catalog;
}

RenderParams defaultViewParams(int size, bool lit, bool shadows = false)
{
    const VariableCatalog catalog = benchCatalog();
    state::RenderState s = defaultState(catalog);
    s.width = s.height = size;
    s.shading.enabled = lit;
    s.shading.shadows = shadows;
    return resolveParams(s, catalog);
}

using bench::processCpuSeconds;

struct Totals {
    uint64_t samples = 0, skipped = 0, chunks = 0, jumped = 0;
    double seconds = 0, cpuSeconds = 0;
    int passes = 0;
    PassStats last;
    void add(const PassStats& s, double cpu)
    {
        samples += s.samples;
        skipped += s.samplesSkipped;
        chunks += s.chunks;
        jumped += s.chunksJumped;
        seconds += s.seconds;
        cpuSeconds += cpu;
        ++passes;
        last = s;
    }
};

void report(benchmark::State& state, const Totals& t)
{
    const int threads = t.last.threads;
    state.counters["ms/pass"] = 1e3 * t.seconds / t.passes;
    state.counters["cpu_ms/pass/thread"] = 1e3 * t.cpuSeconds / t.passes / threads;
    state.counters["Msteps/s/thread"] = double(t.samples + t.skipped) / t.seconds / threads / 1e6;
    state.counters["Mdata/s/thread"] = double(t.samples) / t.seconds / threads / 1e6;
    state.counters["Mdata/cpu_s"] = double(t.samples) / t.cpuSeconds / 1e6;
    state.counters["jumped%"] = t.chunks ? 100.0 * double(t.jumped) / double(t.chunks) : 0.0;
    state.counters["threads"] = threads;
    state.counters["lanes"] = t.last.simdLanes;
}

PassStats timedPass(VolumeRenderer& r, FrameBuffer& f, Totals& t)
{
    const double c0 = processCpuSeconds();
    const PassStats s = r.renderPass(f);
    t.add(s, processCpuSeconds() - c0);
    return s;
}

void runPasses(benchmark::State& state, int level, const RenderParams& p, int passes)
{
    VolumeRenderer r(data().levels[size_t(level)]);
    r.setParams(p);
    Totals t;
    FrameBuffer f(p.width, p.height);
    for (auto _ : state) {
        f.clear();
        for (int i = 0; i < passes; ++i)
            timedPass(r, f, t);
    }
    report(state, t);
    state.counters["level"] = level;
}

// The interactive mode: the level (and, if even the coarsest level is too slow, a reduced internal
// resolution) chosen as the server chooses it (interactiveLevelPolicy, chooseLevel, the throughput
// averaged by averagedMeasure over passes); the first choice assumes a throughput, as a new
// server does.
void BM_InteractivePass512(benchmark::State& state)
{
    const RenderParams p = params(512);
    const auto& levels = data().levels;
    std::vector<std::unique_ptr<VolumeRenderer>> renderers;
    for (const auto& v : levels) {
        renderers.push_back(std::make_unique<VolumeRenderer>(v));
        renderers.back()->setParams(p);
    }
    auto choose = [&](double measured) {
        const LevelPolicy policy = interactiveLevelPolicy(measured);
        return chooseLevel(int(levels.size()), kInteractiveBudgetShare * 0.050, policy.samplesPerSecond,
                           policy.reduceResolution, [&](int l) {
                               renderers[size_t(l)]->setParams(p);  // the full size: the estimate's
                               return renderers[size_t(l)]->estimateSamplesPerPass();
                           });
    };
    auto reduced = [&](LevelChoice c) {
        RenderParams q = p;
        q.width = std::max(1, (p.width + c.divisor - 1) / c.divisor);
        q.height = std::max(1, (p.height + c.divisor - 1) / c.divisor);
        return q;
    };
    // Warm-up as a session would start: each pass measures the machine.
    double rate = 0;
    LevelChoice choice = choose(rate);
    for (int i = 0; i < 4; ++i) {
        const RenderParams q = reduced(choice);
        VolumeRenderer& r = *renderers[size_t(choice.level)];
        r.setParams(q);
        FrameBuffer f(q.width, q.height);
        const PassStats s = r.renderPass(f);
        rate = averagedMeasure(rate, r.estimateSamplesPerPass() / s.seconds);
        choice = choose(rate);
    }
    const RenderParams q = reduced(choice);
    VolumeRenderer& r = *renderers[size_t(choice.level)];
    r.setParams(q);
    Totals t;
    FrameBuffer f(q.width, q.height);
    for (auto _ : state) {
        f.clear();
        timedPass(r, f, t);
    }
    report(state, t);
    state.counters["level"] = choice.level;
    state.counters["internal_px"] = q.width;
    state.counters["est_ms"] = 1e3 * r.estimateSamplesPerPass() / rate;
}
BENCHMARK(BM_InteractivePass512)->Unit(benchmark::kMillisecond);

void BM_Level0Pass512(benchmark::State& state) { runPasses(state, 0, params(512), 1); }
BENCHMARK(BM_Level0Pass512)->Unit(benchmark::kMillisecond);
// One full-resolution pass at the peers' image size (bench/peers/run_peers.sh).
void BM_Level0Pass1024(benchmark::State& state) { runPasses(state, 0, params(1024), 1); }
BENCHMARK(BM_Level0Pass1024)->Unit(benchmark::kMillisecond);
// The UI's first view, lit (as it is shown) and unlit: what shading costs per pass.
void BM_DefaultViewPass1024(benchmark::State& state) { runPasses(state, 0, defaultViewParams(1024, true), 1); }
BENCHMARK(BM_DefaultViewPass1024)->Unit(benchmark::kMillisecond);
void BM_DefaultViewPass1024Unlit(benchmark::State& state) { runPasses(state, 0, defaultViewParams(1024, false), 1); }
BENCHMARK(BM_DefaultViewPass1024Unlit)->Unit(benchmark::kMillisecond);
// Lit and shadowed: what the occlusion lookups cost per pass. The shadow volume is built by a
// pass before the timed ones (its build is BM_ShadowBuild).
void BM_DefaultViewPass1024Shadowed(benchmark::State& state)
{
    const RenderParams p = defaultViewParams(1024, true, true);
    VolumeRenderer r(data().levels[0]);
    r.setParams(p);
    FrameBuffer f(p.width, p.height);
    r.renderPass(f);
    Totals t;
    for (auto _ : state) {
        f.clear();
        timedPass(r, f, t);
    }
    report(state, t);
    state.counters["level"] = 0;
}
BENCHMARK(BM_DefaultViewPass1024Shadowed)->Unit(benchmark::kMillisecond);

// What occlusion costs before a pass can start, on the default view at full resolution: all of it
// (a transfer function or brush change: the extinction, the light's and the ambient visibility) and
// the light's visibility alone (a camera move: the light follows the camera).
void BM_ShadowBuild(benchmark::State& state)
{
    const int level = int(state.range(0));
    VolumeRenderer r(data().levels[size_t(level)]);
    r.setParams(defaultViewParams(512, true, true));
    const kernel::KernelParams& k = r.kernelParams();
    ShadowBuildStats last;
    for (auto _ : state) {
        ShadowVolume shadows(shadowNodesFor(k.dAngleRad, k.rOuterKm));
        last = shadows.update(k, 0.8f, nullptr);
    }
    state.counters["level"] = level;
    state.counters["extinctionMs"] = last.extinctionMs;
    state.counters["lightMs"] = last.lightMs;
    state.counters["ambientMs"] = last.ambientMs;
}
BENCHMARK(BM_ShadowBuild)->Arg(0)->Arg(2)->Unit(benchmark::kMillisecond);
void BM_ShadowLightOnly(benchmark::State& state)
{
    const int level = int(state.range(0));
    VolumeRenderer r(data().levels[size_t(level)]);
    r.setParams(defaultViewParams(512, true, true));
    kernel::KernelParams k = r.kernelParams();
    ShadowVolume shadows(shadowNodesFor(k.dAngleRad, k.rOuterKm));
    state.counters["nodes"] = shadows.nodes();
    state.counters["level"] = level;
    shadows.update(k, 0.8f, nullptr);
    int i = 0;
    for (auto _ : state) {
        const float a = 0.01f * float(++i);
        k.lightDir = normalize(Vec3{std::cos(a), std::sin(a), 0.5f});
        shadows.update(k, 0.8f, nullptr);
    }
}
BENCHMARK(BM_ShadowLightOnly)->Arg(0)->Arg(2)->Unit(benchmark::kMillisecond);
// What the server does to a pass's accumulation before it is a JPEG (StateRenderer::picture with
// the default view's reference shells, and the frame's depth map): at the 3D view's size at
// 1920x1080, 1500x628. Per stage: averaged colour, averaged depth, the shells composited, 8-bit.
void BM_FramePicture1500(benchmark::State& state)
{
    state::RenderState s = defaultState(benchCatalog());
    s.width = 1500;
    s.height = 628;
    RenderParams p = defaultViewParams(16, true);
    p.width = s.width;
    p.height = s.height;
    VolumeRenderer r(data().levels[0]);
    r.setParams(p);
    FrameBuffer f(p.width, p.height);
    r.renderPass(f);
    const grid::SphericalGrid& grid = data().levels[0]->grid();
    double colour = 0, depth = 0, shells = 0, bytes = 0;
    using Clock = std::chrono::steady_clock;
    auto since = [](Clock::time_point t) { return std::chrono::duration<double, std::milli>(Clock::now() - t).count(); };
    for (auto _ : state) {
        auto t = Clock::now();
        std::vector<float> rgba = f.averagedRgba();
        colour += since(t);
        t = Clock::now();
        const std::vector<float> depthKm = f.averagedDepthKm();
        depth += since(t);
        t = Clock::now();
        drawReferenceGeometry(s.reference, s.camera, p.width, p.height, float(grid.rKm.back()), float(grid.rKm.front()),
                              rgba, depthKm, nullptr);
        shells += since(t);
        t = Clock::now();
        benchmark::DoNotOptimize(toRgba8(rgba, s.background));
        bytes += since(t);
    }
    const double n = double(state.iterations());
    state.counters["colour_ms"] = colour / n;
    state.counters["depth_ms"] = depth / n;
    state.counters["shells_ms"] = shells / n;
    state.counters["rgba8_ms"] = bytes / n;
}
BENCHMARK(BM_FramePicture1500)->Unit(benchmark::kMillisecond);

// Maps and sections (the goal: dragging the depth or a section's end updates at >= 10 pictures/s at
// 1920x1080 on 2 cores for full-resolution data) of the temperature anomaly, the state's colours:
// first arg 0 map, 1 map with contours and flow arrows, 2 section, 3 section with contours and
// flow, 4 map of a new central meridian each time (the first map of a projection and size: every
// pixel's inverse projection, kept for the next ones); then width and height. Every picture is of
// a new depth (maps) or a section's end moved (sections), as when dragging them. The server sends
// them as PNG (POST /api/slice): png1_ms is its encoding at zlib level 1, what it sends, png6_ms at
// level 6 (screenshots'), apart.
void BM_SlicePicture1920(benchmark::State& state)
{
    const VariableCatalog catalog = benchCatalog();
    ResolvedState r;
    r.state = defaultState(catalog);
    r.state.width = int(state.range(1));
    r.state.height = int(state.range(2));
    r.state.reference.coastlines.visible = false;  // the coastline file is the UI build's; not needed here
    const int kind = int(state.range(0));
    const bool extras = kind == 1 || kind == 3;
    if (extras) {
        r.state.map.contours = {-100, 100};
        r.state.map.flow = r.state.section.flow = true;
    }
    r.state.section.from = {30, -20};
    r.state.section.to = {30, 60};
    r.params = resolveParams(r.state, catalog);
    const SliceInputs in{data().levels[0].get(), &r, catalog.names, "temperature anomaly [K]", "step 0", nullptr};
    const bool map = kind < 2 || kind == 4;
    int n = 0;
    for (auto _ : state) {
        ++n;
        r.state.map.depthKm = 400 + n % 200;
        r.state.section.to.lonDeg = 60 + 0.1 * (n % 200);
        if (kind == 4)
            r.state.map.centralMeridianDeg = -150 + n % 300;
        benchmark::DoNotOptimize(map ? mapPicture(in) : sectionPicture(in));
    }
    const ImageRgba8 image = map ? mapPicture(in) : sectionPicture(in);
    for (const int level : {1, 6}) {
        const auto t = std::chrono::steady_clock::now();
        benchmark::DoNotOptimize(server::encodePng(image.pixels, image.width, image.height, level));
        state.counters[fmt::format("png{}_ms", level)] =
            std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t).count();
    }
    state.counters["pictures/s"] = benchmark::Counter(double(state.iterations()), benchmark::Counter::kIsRate);
}
// At 1920x1080, and at the size of the UI's map pane in a 1920x1080 window (about 950x340).
BENCHMARK(BM_SlicePicture1920)
    ->ArgsProduct({{0, 1, 2, 3, 4}, {1920}, {1080}})
    ->Args({0, 950, 340})
    ->Args({2, 950, 340})
    ->Unit(benchmark::kMillisecond)
    ->UseRealTime();

// The sampling alone, without projection or drawing: the slice on a 0.2-degree lat-lon grid
// (900 x 1800 = 1.6 M points, as in a 1920x1080 map's sphere).
void BM_LatLonSlice(benchmark::State& state)
{
    const size_t var = size_t(std::find(data().names.begin(), data().names.end(), "temperature anomaly") - data().names.begin());
    for (auto _ : state)
        benchmark::DoNotOptimize(latLonSlice(*data().levels[0], var, 660, 0.2));
}
BENCHMARK(BM_LatLonSlice)->Unit(benchmark::kMillisecond)->UseRealTime();

void BM_Level2Pass1024(benchmark::State& state) { runPasses(state, 2, params(1024), 1); }
BENCHMARK(BM_Level2Pass1024)->Unit(benchmark::kMillisecond);
void BM_Level1Pass512(benchmark::State& state) { runPasses(state, 1, params(512), 1); }
BENCHMARK(BM_Level1Pass512)->Unit(benchmark::kMillisecond);
void BM_Level2Pass512(benchmark::State& state) { runPasses(state, 2, params(512), 1); }
BENCHMARK(BM_Level2Pass512)->Unit(benchmark::kMillisecond);

void BM_Level0Pass512Scalar(benchmark::State& state)
{
    RenderParams p = params(512);
    p.kernel = KernelKind::Scalar;
    runPasses(state, 0, p, 1);
}
BENCHMARK(BM_Level0Pass512Scalar)->Unit(benchmark::kMillisecond);

void BM_Level0Pass512NoSkipping(benchmark::State& state)
{
    RenderParams p = params(512);
    p.skipBricks = false;
    runPasses(state, 0, p, 1);
}
BENCHMARK(BM_Level0Pass512NoSkipping)->Unit(benchmark::kMillisecond);
void BM_Level2Pass512NoSkipping(benchmark::State& state)
{
    RenderParams p = params(512);
    p.skipBricks = false;
    runPasses(state, 2, p, 1);
}
BENCHMARK(BM_Level2Pass512NoSkipping)->Unit(benchmark::kMillisecond);

// What a brush or transfer-function change costs before the next pass can start: setParams bakes the
// transfer table, the brick flags, the brick distance map and the skip grid's cell distances.
void BM_SetParams(benchmark::State& state)
{
    const int level = int(state.range(0));
    VolumeRenderer r(data().levels[size_t(level)]);
    RenderParams p = params(512);
    r.setParams(p);  // the first call also builds the grid's skip geometry (cached per grid)
    int i = 0;
    for (auto _ : state) {
        p.brushes = {{var("temperature anomaly"), std::nullopt, {{-400.0f + float(i++ % 7), 400.0f}}}};
        r.setParams(p);
    }
    state.counters["level"] = level;
}
BENCHMARK(BM_SetParams)->Arg(0)->Arg(1)->Arg(2)->Unit(benchmark::kMillisecond);

// What a new step costs the first renderer at level 0: the bounds of its 4-point activity bricks
// are derived from the values once per volume (StepVolume::brickBounds(var, 4)).
void BM_DeriveBrickBounds4(benchmark::State& state)
{
    const dataset::StepVolume& v = *data().levels[0];
    const grid::BrickLayout layout = grid::BrickLayout::forGrid(v.grid(), 4);
    std::vector<float> bounds(2 * layout.brickCount());
    for (auto _ : state)
        dataset::computeBrickBounds(v.grid(), layout, {v.values(size_t(var("temperature anomaly"))), v.grid().cellCount()}, bounds);
}
BENCHMARK(BM_DeriveBrickBounds4)->Unit(benchmark::kMillisecond);

// What shading costs a step the first time it is shown lit: the colouring variable's gradient at
// every grid point (nodeGradient, kept with the volume).
void BM_NodeGradient(benchmark::State& state)
{
    const dataset::StepVolume& v = *data().levels[0];
    for (auto _ : state)
        benchmark::DoNotOptimize(grid::nodeGradient(v.grid(), v.values(size_t(var("temperature anomaly")))));
}
BENCHMARK(BM_NodeGradient)->Unit(benchmark::kMillisecond);

// Converged 1024² at full resolution: passes are accumulated until the image stops changing, measured
// two ways on the 8-bit scale: the mean absolute change of the accumulated RGBA between successive
// passes is below kConvergedChange grey levels, and the per-pixel standard error of the mean (from the
// spread of the passes; RMS over pixels, dominated by edges) is below kConvergedSem grey levels.
// Reports the passes it took.
constexpr double kConvergedChange = 0.25;
constexpr double kConvergedSem = 1.0;
constexpr int kMaxPasses = 32;
void BM_Converged1024(benchmark::State& state)
{
    const RenderParams p = params(1024);
    VolumeRenderer r(data().levels[0]);
    r.setParams(p);
    Totals t;
    double lastChange = 0, lastSem = 0;
    for (auto _ : state) {
        FrameBuffer f(p.width, p.height);
        std::vector<float> previous(size_t(4) * p.width * p.height, 0.0f);
        std::vector<double> sum(previous.size(), 0.0), sumSq(previous.size(), 0.0);
        for (int n = 1; n <= kMaxPasses; ++n) {
            timedPass(r, f, t);
            state.PauseTiming();
            const std::vector<float> avg = f.averagedRgba();
            double change = 0, sem2 = 0;
            for (size_t i = 0; i < avg.size(); ++i) {
                const double x = double(n) * avg[i] - double(n - 1) * previous[i];  // this pass alone
                sum[i] += x;
                sumSq[i] += x * x;
                change += std::abs(avg[i] - previous[i]);
                if (n > 1) {
                    const double mean = sum[i] / n, var = std::max(0.0, (sumSq[i] - n * mean * mean) / (n - 1));
                    sem2 += var / n;
                }
            }
            lastChange = 255.0 * change / double(avg.size());
            lastSem = 255.0 * std::sqrt(sem2 / double(avg.size()));
            std::fprintf(stderr, "converged1024: pass %2d  %.0f ms  mean change %.3f grey levels  RMS SEM %.3f\n", n,
                         1e3 * t.last.seconds, lastChange, lastSem);
            previous = avg;
            state.ResumeTiming();
            if (n > 1 && lastChange < kConvergedChange && lastSem < kConvergedSem)
                break;
        }
    }
    report(state, t);
    state.counters["passes"] = double(t.passes) / double(state.iterations());
    state.counters["total_s"] = t.seconds / double(state.iterations());
    state.counters["cpu_total_s/thread"] = t.cpuSeconds / double(state.iterations()) / t.last.threads;
    state.counters["final_change"] = lastChange;
    state.counters["final_sem"] = lastSem;
}
BENCHMARK(BM_Converged1024)->Unit(benchmark::kMillisecond)->Iterations(1);

// The old fixed count, for comparison with earlier runs.
void BM_Converged1024Fixed8(benchmark::State& state) { runPasses(state, 0, params(1024), 8); }
BENCHMARK(BM_Converged1024Fixed8)->Unit(benchmark::kMillisecond)->Iterations(1);

// Converged stills with adaptive refinement (FrameBuffer Refinement, docs/rendering.md "Adaptive
// refinement") against the fixed 8 passes of the state's default, at 1024² and at a screen's
// 1920x1080. Up to 8 passes; a block stops once its estimated error is below the threshold
// (argument: hundredths of an 8-bit level). Counters: passes until every block stopped, the share of
// block-passes rendered, and the picture (8-bit, over black) against the 8-pass image: max and mean
// difference and the share of pixels off by more than 10 levels (the golden tests' rule: <= 0.5 %
// and mean < 1).
const std::vector<uint8_t>& fixed8Picture(int width, int height)
{
    static std::map<std::pair<int, int>, std::vector<uint8_t>> cache;
    auto& slot = cache[{width, height}];
    if (slot.empty()) {
        RenderParams p = params(width);
        p.width = width;
        p.height = height;
        VolumeRenderer r(data().levels[0]);
        r.setParams(p);
        FrameBuffer f(width, height);
        for (int i = 0; i < 8; ++i)
            r.renderPass(f);
        slot = f.resolveRgba8({0, 0, 0});
    }
    return slot;
}

void convergedStill(benchmark::State& state, int width, int height, float errorGreyLevels, int maxPasses = 8)
{
    RenderParams p = params(width);
    p.width = width;
    p.height = height;
    const std::vector<uint8_t>& reference = fixed8Picture(width, height);
    VolumeRenderer r(data().levels[0]);
    r.setParams(p);
    Totals t;
    std::vector<uint8_t> picture;
    double blockPasses = 0, blockPassesMax = 0;
    int passesToConverge = 0;
    for (auto _ : state) {
        FrameBuffer f(width, height);
        f.setRefinement({errorGreyLevels});
        int n = 0;
        for (; n < maxPasses && !f.converged(); ++n) {
            int refining = 0;
            for (int b = 0; b < f.blockCount(); ++b)
                refining += f.blockRefining(b);
            const PassStats s = timedPass(r, f, t);
            std::fprintf(stderr, "converged %dx%d at %.2f: pass %d  %5.1f %% of the blocks  %.0f ms\n", width, height,
                         errorGreyLevels, n, 100.0 * refining / f.blockCount(), 1e3 * s.seconds);
        }
        state.PauseTiming();
        passesToConverge = n;
        blockPasses = blockPassesMax = 0;
        for (int b = 0; b < f.blockCount(); ++b) {
            blockPasses += f.blockPasses(b);
            blockPassesMax += maxPasses;
        }
        picture = f.resolveRgba8({0, 0, 0});
        if (const char* dir = std::getenv("RAYPC_BENCH_PICTURES")) {
            // The picture, a map of each block's passes (grey: passes / maximum) and the difference from the 8-pass picture x 8.
            const std::string name = fmt::format("{}/converged_{}x{}_{:.2f}", dir, width, height, errorGreyLevels);
            writePng(name + ".png", {width, height, picture});
            std::vector<uint8_t> map(picture.size(), 255);
            for (int b = 0; b < f.blockCount(); ++b) {
                const TileRect rect = f.block(b);
                for (int y = rect.y0; y < rect.y1; ++y)
                    for (int x = rect.x0; x < rect.x1; ++x)
                        for (int c = 0; c < 3; ++c)
                            map[4 * (size_t(y) * size_t(width) + size_t(x)) + size_t(c)] = uint8_t(255 * f.blockPasses(b) / maxPasses);
            }
            writePng(name + "_passes.png", {width, height, map});
            std::vector<uint8_t> diff(picture.size(), 255);
            for (size_t i = 0; i < picture.size(); ++i)
                if (i % 4 != 3)
                    diff[i] = uint8_t(std::min(255, 8 * std::abs(int(picture[i]) - int(reference[i]))));
            writePng(name + "_diff8.png", {width, height, diff});
        }
        state.ResumeTiming();
    }
    int maxDiff = 0;
    double sum = 0;
    size_t over10 = 0, over2 = 0;
    for (size_t i = 0; i < picture.size(); i += 4) {
        int worst = 0;
        for (int c = 0; c < 3; ++c) {
            const int d = std::abs(int(picture[i + c]) - int(reference[i + c]));
            worst = std::max(worst, d);
            sum += d;
        }
        maxDiff = std::max(maxDiff, worst);
        over10 += worst > 10;
        over2 += worst > 2;
    }
    const double pixels = double(picture.size() / 4);
    report(state, t);
    state.counters["passes"] = passesToConverge;
    state.counters["total_s"] = t.seconds / double(state.iterations());
    state.counters["cpu_total_s/thread"] = t.cpuSeconds / double(state.iterations()) / t.last.threads;
    state.counters["block_passes%"] = 100.0 * blockPasses / blockPassesMax;
    state.counters["vs8_max"] = maxDiff;
    state.counters["vs8_mean"] = sum / (3 * pixels);
    state.counters["vs8_over10%"] = 100.0 * double(over10) / pixels;
    state.counters["vs8_over2%"] = 100.0 * double(over2) / pixels;
}
void BM_ConvergedAdaptive1024(benchmark::State& state) { convergedStill(state, 1024, 1024, float(state.range(0)) / 100); }
BENCHMARK(BM_ConvergedAdaptive1024)->Arg(50)->Arg(100)->Arg(200)->Arg(400)->Unit(benchmark::kMillisecond)->Iterations(1);
void BM_ConvergedFixed8_1024(benchmark::State& state) { convergedStill(state, 1024, 1024, 0); }
BENCHMARK(BM_ConvergedFixed8_1024)->Unit(benchmark::kMillisecond)->Iterations(1);
// What the 8-pass image itself is off by: 32 fixed passes against it.
void BM_ConvergedFixed32_1024(benchmark::State& state) { convergedStill(state, 1024, 1024, 0, 32); }
BENCHMARK(BM_ConvergedFixed32_1024)->Unit(benchmark::kMillisecond)->Iterations(1);
void BM_ConvergedAdaptive1920x1080(benchmark::State& state) { convergedStill(state, 1920, 1080, float(state.range(0)) / 100); }
BENCHMARK(BM_ConvergedAdaptive1920x1080)->Arg(200)->Unit(benchmark::kMillisecond)->Iterations(1);
void BM_ConvergedFixed8_1920x1080(benchmark::State& state) { convergedStill(state, 1920, 1080, 0); }
BENCHMARK(BM_ConvergedFixed8_1920x1080)->Unit(benchmark::kMillisecond)->Iterations(1);

// Brushing four variables against no brushing; the selected share of the mantle is computed exactly
// (selectedVolume over dual cells) and printed as counter selected%.
std::vector<analysis::RangeFilter> fourBrushes()
{
    return {{var("temperature"), std::nullopt, {{1800, 4000}}},
            {var("thermal conductivity"), std::nullopt, {{0, 100}}},
            {var("vx"), std::nullopt, {{-1.0f, 1.0f}}},
            {var("temperature anomaly"), std::nullopt, {{50, 1000}}}};
}
// The same selection with the anomaly's range split in two touching ranges (OR): the cost of an
// axis with several ranges.
std::vector<analysis::RangeFilter> fourBrushesSplit()
{
    std::vector<analysis::RangeFilter> b = fourBrushes();
    b.back().ranges = {{50, 400}, {400, 1000}};
    return b;
}
double selectedPercent(const std::vector<analysis::RangeFilter>& brushes)
{
    return 100.0 * selectedVolume(*data().levels[0], brushes).fractionOfMantle;
}
void brushedPass(benchmark::State& state, std::vector<analysis::RangeFilter> brushes)
{
    RenderParams p = params(512);
    p.brushes = std::move(brushes);
    runPasses(state, 0, p, 1);
    state.counters["selected%"] = selectedPercent(p.brushes);
}
void BM_Brush4Pass512(benchmark::State& state) { brushedPass(state, fourBrushes()); }
BENCHMARK(BM_Brush4Pass512)->Unit(benchmark::kMillisecond);
void BM_Brush4SplitPass512(benchmark::State& state) { brushedPass(state, fourBrushesSplit()); }
BENCHMARK(BM_Brush4SplitPass512)->Unit(benchmark::kMillisecond);
void BM_NoBrushPass512(benchmark::State& state) { runPasses(state, 0, params(512), 1); }
BENCHMARK(BM_NoBrushPass512)->Unit(benchmark::kMillisecond);

std::string firstLine(const char* path)
{
    std::ifstream in(path);
    std::string s;
    std::getline(in, s);
    return s;
}

}  // namespace

int main(int argc, char** argv)
{
    // Memory as `raypc` has it (transparent huge pages where the kernel gives them on request), so
    // that these figures compare with raypc's; RAYPC_HUGE_PAGES=0 for 4 KB pages.
    raypc::restartWithTransparentHugePages(argv);
    benchmark::Initialize(&argc, argv);
    std::string cpu;
    {
        std::ifstream in("/proc/cpuinfo");
        for (std::string line; std::getline(in, line);)
            if (line.rfind("model name", 0) == 0) {
                cpu = line.substr(line.find(':') + 2);
                break;
            }
    }
    std::fprintf(stderr, "machine: %s, %d threads (oneTBB); load average at start: %s\n", cpu.c_str(),
                 tbb::this_task_arena::max_concurrency(), firstLine("/proc/loadavg").c_str());
    data();
    benchmark::RunSpecifiedBenchmarks();
    std::fprintf(stderr, "load average at end: %s\n", firstLine("/proc/loadavg").c_str());
    benchmark::Shutdown();
}

