// Decoding and encoding one u16 level array (docs/format.md, "Encoding of the level arrays") at full
// resolution: the synthetic model's temperature anomaly on 180 x 201 x 360 points (13 M), bricks of 8.
//   BM_Decode/threads: decodeUint16 of one variable (what the first values(var) of a loaded step
//     costs), with 1 thread and with every core; time per variable, counter points/s.
//   BM_Encode/threads: encodeUint16 (preprocessing, per variable and level).
// The peer is a plain copy of the float32 array (what a float32 dataset's first touch of mapped
// pages cannot beat), measured in the same run: BM_CopyFloat32.
//   build/bench/value_encoding_bench --benchmark_min_time=1
#include "bench_util.h"
#include "dataset/bricks.h"
#include "synth/synth.h"
#include "dataset/value_encoding.h"

#include <benchmark/benchmark.h>
#include <fmt/format.h>
#include <tbb/task_arena.h>

#include <cstring>
#include <thread>

using namespace raypc;

namespace {

struct Data {
    grid::SphericalGrid grid;
    grid::BrickLayout layout;
    std::vector<float> values, bounds;
    std::vector<uint16_t> encoded;
};

const Data& data()
{
    static const Data d = [] {
        Data out;
        const synth::SynthOptions o = bench::fullResolution();
        grid::Snapshot s = synth::synthesizeSnapshot(o, 0);
        out.grid = s.grid;
        out.layout = grid::BrickLayout::forGrid(out.grid, 8);
        out.values = std::move(s.find("temperature anomaly")->values);
        out.bounds.resize(2 * out.layout.brickCount());
        dataset::computeBrickBounds(out.grid, out.layout, out.values, out.bounds);
        out.encoded.resize(out.values.size());
        dataset::encodeUint16(out.grid, out.layout, out.values, out.bounds, out.encoded);
        fmt::print(stderr, "grid {}x{}x{} = {} points; {} cores\n", o.nLat, o.nR, o.nLon, out.values.size(),
                   std::thread::hardware_concurrency());
        return out;
    }();
    return d;
}

void report(benchmark::State& state, size_t points)
{
    state.counters["points/s"] = benchmark::Counter(double(points), benchmark::Counter::kIsIterationInvariantRate);
}

// Runs `code(out)` once an iteration in an arena of the benchmark's threads; `out` holds one T a point.
template <typename T, typename F>
void timedCoding(benchmark::State& state, F code)
{
    std::vector<T> out(data().values.size());
    tbb::task_arena arena(int(state.range(0)));
    for (auto _ : state) {
        arena.execute([&] { code(out); });
        benchmark::DoNotOptimize(out.data());
    }
    report(state, out.size());
}

void BM_Decode(benchmark::State& state)
{
    const Data& d = data();
    timedCoding<float>(state, [&](std::vector<float>& out) { dataset::decodeUint16(d.grid, d.layout, d.encoded, d.bounds, out); });
}

void BM_Encode(benchmark::State& state)
{
    const Data& d = data();
    timedCoding<uint16_t>(state,
                          [&](std::vector<uint16_t>& out) { dataset::encodeUint16(d.grid, d.layout, d.values, d.bounds, out); });
}

void BM_CopyFloat32(benchmark::State& state)
{
    const Data& d = data();
    std::vector<float> out(d.values.size());
    for (auto _ : state) {
        std::memcpy(out.data(), d.values.data(), d.values.size() * sizeof(float));
        benchmark::DoNotOptimize(out.data());
    }
    report(state, out.size());
}

const int kCores = int(std::max(1u, std::thread::hardware_concurrency()));

}  // namespace

BENCHMARK(BM_Decode)->Arg(1)->Arg(kCores)->Unit(benchmark::kMillisecond)->UseRealTime();
BENCHMARK(BM_Encode)->Arg(1)->Arg(kCores)->Unit(benchmark::kMillisecond)->UseRealTime();
BENCHMARK(BM_CopyFloat32)->Unit(benchmark::kMillisecond)->UseRealTime();
BENCHMARK_MAIN();
