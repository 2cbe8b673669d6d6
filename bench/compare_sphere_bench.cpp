// Comparisons on the sphere (analysis/shell_compare.h, docs/compare.md) of two 1° global fields: 181
// latitudes with both pole rows (Clenshaw–Curtis) x 360 longitudes (a file's 361 with the seam stored
// twice) x 50 shells, 3.26 M points each, values in memory (pseudo-random, fixed seed: the cost does not
// depend on them).
//   BM_CorrelateShells: correlateShells unfiltered (area-weighted Pearson, RMS, ratio per shell). Target:
//     <= 1 s on 2 cores.
//   BM_CorrelateShellsFiltered: the same after low-pass filtering both to degree 60 (libsharp, 4
//     transforms a shell).
//   BM_ShellSpectra: shellSpectra to degree 60 (one analysis a shell). Target: <= 2 s on 2 cores.
//   BM_RegridAndCorrelate: B on a 2° cell-centred grid put on A's grid (grid::regrid) and correlated,
//     what `raypc correlate` does for two datasets on different grids.
// Each with 1 thread and with every core (oneTBB over shells; libsharp's OpenMP kept to one thread a
// transform). Counters: cpu_s/thread, Mpoints/s (of A's grid), threads.
//   build/bench/compare_sphere_bench --benchmark_min_time=1   (bench/compare_sphere.sh prints the load)
#include "bench_util.h"
#include "analysis/shell_compare.h"
#include "core/spherical.h"
#include "grid/regrid.h"

#include <benchmark/benchmark.h>

#include <random>
#include <vector>

using namespace raypc;

namespace {

grid::SphericalGrid oneDegreeGrid()
{
    grid::SphericalGrid g;
    for (int i = 0; i <= 180; ++i)
        g.latDeg.push_back(-90.0 + i);
    for (int i = 0; i < 50; ++i)
        g.rKm.push_back(kCoreRadiusKm + i * (kSurfaceRadiusKm - kCoreRadiusKm) / 49.0);
    for (int i = 0; i < 360; ++i)
        g.lonDeg.push_back(i);
    return g;
}

std::vector<float> noise(size_t n, uint32_t seed)
{
    std::mt19937 rng(seed);
    std::normal_distribution<float> d(0.0f, 1.0f);
    std::vector<float> v(n);
    for (float& x : v)
        x = d(rng);
    return v;
}

struct Fields {
    grid::SphericalGrid grid = oneDegreeGrid();
    std::vector<float> a = noise(grid.cellCount(), 1), b = noise(grid.cellCount(), 2);
};
const Fields& fields()
{
    static const Fields f;
    return f;
}

void BM_CorrelateShells(benchmark::State& state)
{
    const Fields& f = fields();
    bench::timedInArena(state, "Mpoints/s", double(f.grid.cellCount()) / 1e6, [&] {
        benchmark::DoNotOptimize(analysis::correlateShells(f.grid, f.a.data(), f.b.data(), {}, "bench"));
    });
}

void BM_CorrelateShellsFiltered(benchmark::State& state)
{
    const Fields& f = fields();
    bench::timedInArena(state, "Mpoints/s", double(f.grid.cellCount()) / 1e6, [&] {
        benchmark::DoNotOptimize(analysis::correlateShells(f.grid, f.a.data(), f.b.data(), {60}, "bench"));
    });
}

void BM_ShellSpectra(benchmark::State& state)
{
    const Fields& f = fields();
    bench::timedInArena(state, "Mpoints/s", double(f.grid.cellCount()) / 1e6, [&] {
        benchmark::DoNotOptimize(analysis::shellSpectra(f.grid, f.a.data(), 60, "bench"));
    });
}

void BM_RegridAndCorrelate(benchmark::State& state)
{
    const Fields& f = fields();
    grid::SphericalGrid coarse;
    for (int i = 0; i < 90; ++i)
        coarse.latDeg.push_back(-89.0 + 2 * i);
    coarse.rKm = f.grid.rKm;
    for (int i = 0; i < 180; ++i)
        coarse.lonDeg.push_back(1.0 + 2 * i);
    const std::vector<float> b = noise(coarse.cellCount(), 3);
    bench::timedInArena(state, "Mpoints/s", double(f.grid.cellCount()) / 1e6, [&] {
        const std::vector<float> onA = grid::regrid(coarse, b.data(), f.grid);
        benchmark::DoNotOptimize(analysis::correlateShells(f.grid, f.a.data(), onA.data(), {}, "bench"));
    });
}

}  // namespace

BENCHMARK(BM_CorrelateShells)->Arg(1)->Arg(0)->Unit(benchmark::kMillisecond)->UseRealTime();
BENCHMARK(BM_CorrelateShellsFiltered)->Arg(1)->Arg(0)->Unit(benchmark::kMillisecond)->UseRealTime();
BENCHMARK(BM_ShellSpectra)->Arg(1)->Arg(0)->Unit(benchmark::kMillisecond)->UseRealTime();
BENCHMARK(BM_RegridAndCorrelate)->Arg(1)->Arg(0)->Unit(benchmark::kMillisecond)->UseRealTime();
BENCHMARK_MAIN();
