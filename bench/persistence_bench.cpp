// Persistence pairs and seed selection on the synthetic model built in memory
// (synthesizeSnapshot), temperature anomaly.
//   BM_Persistence: persistencePairs of one full-resolution (180 x 201 x 360, 13 M vertices) step,
//     with 1 thread and with every core. Target: <= 10 s on 2 cores.
//   BM_CriticalPoints: findCriticalPoints of the same step, the pass every rule runs anyway
//     (the comparison: persistence costs this many critical-point passes).
//   BM_SelectSeeds: what preprocessing does per step: critical points + the rule's selection.
// Counters: cpu_s/thread (process CPU time per iteration divided by the threads: what it would take
// on an otherwise idle machine; the cores are often shared), Mvertices/s, pairs.
//
// Before the benchmarks it prints the seed report of docs/persistence.md: for every step of the
// demo data (64 x 81 x 128, 12 steps, seed 1) and each rule, the seeds, how many are saddles, the
// largest number within 500 km of one seed, and how many of the model's 10 plumes and 10 slabs
// (syntheticFeatures: the truth) have a seed of the right kind within 500 km of the plume's axis
// (CMB to head) or the slab's sheet (trench to tip). RAYPC_BENCH_REPORT=0 skips it.
//   build/bench/persistence_bench --benchmark_min_time=1
#include "bench_util.h"
#include "core/spherical.h"
#include "core/system_memory.h"
#include "analysis/critical_points.h"
#include "analysis/persistence.h"
#include "synth/synth.h"

#include <benchmark/benchmark.h>
#include <fmt/format.h>
#include <tbb/task_arena.h>

#include <sys/resource.h>

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <fstream>
#include <string>
#include <thread>

using namespace raypc;

namespace {

struct Step {
    grid::SphericalGrid grid;
    std::vector<float> anomaly;
};

Step synthesizeAnomaly(const synth::SynthOptions& o, double timeMyr)
{
    grid::Snapshot s = synth::synthesizeSnapshot(o, timeMyr);
    return {s.grid, std::move(s.find("temperature anomaly")->values)};
}

const Step& fullStep()
{
    static const Step s = synthesizeAnomaly(bench::fullResolution(), 0.0);
    return s;
}

// Runs `work` on the full step in an arena of the benchmark's threads and sets the shared counters.
template <typename F>
void timed(benchmark::State& state, F work)
{
    const Step& s = fullStep();
    bench::timedInArena(state, "Mvertices/s", static_cast<double>(s.anomaly.size()) * 1e-6, [&] { work(s); });
}

void BM_Persistence(benchmark::State& state)
{
    size_t pairs = 0;
    timed(state, [&](const Step& s) { pairs = analysis::persistencePairs(s.grid, s.anomaly).size(); });
    state.counters["pairs"] = static_cast<double>(pairs);
}

void BM_CriticalPoints(benchmark::State& state)
{
    size_t found = 0;
    timed(state, [&](const Step& s) { found = analysis::findCriticalPoints(s.grid, s.anomaly).size(); });
    state.counters["critical_points"] = static_cast<double>(found);
}

void BM_SelectSeeds(benchmark::State& state)
{
    analysis::CriticalPointFilter filter;
    filter.rule = state.range(1) ? analysis::SeedRule::Value : analysis::SeedRule::Persistence;
    size_t seeds = 0;
    timed(state, [&](const Step& s) {
        seeds = analysis::selectSeeds(s.grid, s.anomaly, analysis::findCriticalPoints(s.grid, s.anomaly), filter).seeds.size();
    });
    state.counters["seeds"] = static_cast<double>(seeds);
    state.SetLabel(analysis::seedRuleName(filter.rule));
}

// --- Seed report ------------------------------------------------------------------------------

struct Rule {
    std::string name;
    analysis::CriticalPointFilter filter;
};

std::vector<Rule> rules()
{
    std::vector<Rule> out;
    analysis::CriticalPointFilter before;  // the rule before persistence: top 200 by |value|, saddles too
    before.rule = analysis::SeedRule::Value;
    before.saddles = true;
    out.push_back({"value (before)", before});
    for (const char* threshold : {"2%", "5%", "10%"}) {
        analysis::CriticalPointFilter f;
        analysis::parsePersistenceThreshold(threshold, f);
        const bool isDefault = std::string(threshold) == "5%";
        out.push_back({fmt::format("persistence {}{}", threshold, isDefault ? " (default)" : ""), f});
    }
    analysis::CriticalPointFilter withSaddles;
    withSaddles.saddles = true;
    out.push_back({"persistence 5% + saddles", withSaddles});
    return out;
}

double distanceKm(const Vec3d& a, const Vec3d& b)
{
    return std::sqrt((a.x - b.x) * (a.x - b.x) + (a.y - b.y) * (a.y - b.y) + (a.z - b.z) * (a.z - b.z));
}

struct Tally {
    double seeds = 0, saddles = 0, cluster = 0, plumes = 0, slabs = 0, elsewhere = 0, steps = 0;
};

constexpr double kNearKm = 500;

// Which seeds lie within kNearKm of feature f's centre line (a plume's axis from the CMB to its
// head, a slab's sheet from its tip to the trench) and are of its kind (maxima for plumes).
std::vector<bool> nearFeature(const synth::SynthOptions& o, double timeMyr, const synth::SynthFeature& feature, size_t f,
                              const std::vector<analysis::CriticalPoint>& seeds)
{
    const bool plume = feature.kind == synth::SynthFeature::Kind::Plume;
    const double r0 = plume ? kCoreRadiusKm : feature.frontRadiusKm;
    const double r1 = plume ? feature.frontRadiusKm : kSurfaceRadiusKm;
    std::vector<bool> near(seeds.size(), false);
    for (double r = r0; r <= r1 + 1e-9; r += 25) {
        const auto c = synth::syntheticFeatureCentreDeg(o, timeMyr, f, r);
        const Vec3d p = sphericalToCartesianKm(c[0], c[1], r);
        for (size_t k = 0; k < seeds.size(); ++k)
            near[k] = near[k] || (seeds[k].kind == (plume ? analysis::CriticalKind::Maximum : analysis::CriticalKind::Minimum) &&
                                  distanceKm(p, sphericalToCartesianKm(seeds[k].latDeg, seeds[k].lonDeg,
                                                                       seeds[k].rKm)) <= kNearKm);
    }
    return near;
}

void addStep(Tally& t, const synth::SynthOptions& o, double timeMyr, const std::vector<analysis::CriticalPoint>& seeds)
{
    std::vector<Vec3d> at;
    for (const auto& s : seeds)
        at.push_back(sphericalToCartesianKm(s.latDeg, s.lonDeg, s.rKm));
    size_t cluster = 0;
    for (const auto& a : at) {
        size_t n = 0;
        for (const auto& b : at)
            n += distanceKm(a, b) <= kNearKm;
        cluster = std::max(cluster, n);
    }
    const auto features = synth::syntheticFeatures(o, timeMyr);
    std::vector<bool> onAFeature(seeds.size(), false);
    for (size_t f = 0; f < features.size(); ++f) {
        const auto near = nearFeature(o, timeMyr, features[f], f, seeds);
        (features[f].kind == synth::SynthFeature::Kind::Plume ? t.plumes : t.slabs) +=
            std::find(near.begin(), near.end(), true) != near.end();
        for (size_t k = 0; k < seeds.size(); ++k)
            onAFeature[k] = onAFeature[k] || near[k];
    }
    t.elsewhere += double(std::count(onAFeature.begin(), onAFeature.end(), false));
    t.seeds += double(seeds.size());
    for (const auto& s : seeds)
        t.saddles += s.kind != analysis::CriticalKind::Maximum && s.kind != analysis::CriticalKind::Minimum;
    t.cluster += double(cluster);
    t.steps += 1;
}

void seedReport()
{
    const synth::SynthOptions o;  // the demo
    const auto all = rules();
    std::vector<Tally> tallies(all.size());
    for (int k = 0; k < o.steps; ++k) {
        const Step s = synthesizeAnomaly(o, k * o.dtMyr);
        const auto points = analysis::findCriticalPoints(s.grid, s.anomaly);
        for (size_t r = 0; r < all.size(); ++r)
            addStep(tallies[r], o, k * o.dtMyr, analysis::selectSeeds(s.grid, s.anomaly, points, all[r].filter).seeds);
    }
    fmt::print("seed report: demo data ({}x{}x{}, {} steps, seed {}), temperature anomaly; means per step\n", o.nLat,
               o.nR, o.nLon, o.steps, o.seed);
    fmt::print("{:<28} {:>7} {:>8} {:>16} {:>12} {:>12} {:>16}\n", "rule", "seeds", "saddles", "largest 500 km",
               "plumes /10", "slabs /10", "off-feature");
    for (size_t r = 0; r < all.size(); ++r) {
        const Tally& t = tallies[r];
        fmt::print("{:<28} {:>7.1f} {:>8.1f} {:>16.1f} {:>12.1f} {:>12.1f} {:>16.1f}\n", all[r].name,
                   t.seeds / t.steps, t.saddles / t.steps, t.cluster / t.steps, t.plumes / t.steps, t.slabs / t.steps,
                   t.elsewhere / t.steps);
    }
    // How far each feature stands out: the largest persistence of an extremum of its kind near it,
    // in % of the step's range (a feature is lost above that threshold), over all steps.
    std::vector<double> lowest(synth::syntheticFeatures(o, 0).size(), 1e9), highest(lowest.size(), 0);
    for (int k = 0; k < o.steps; ++k) {
        const Step s = synthesizeAnomaly(o, k * o.dtMyr);
        analysis::CriticalPointFilter everything;
        everything.minPersistence = 0;
        everything.persistenceIsFraction = false;
        everything.maxCount = s.anomaly.size();
        const auto seeds = analysis::selectSeeds(s.grid, s.anomaly, analysis::findCriticalPoints(s.grid, s.anomaly), everything).seeds;
        const auto [lo, hi] = std::minmax_element(s.anomaly.begin(), s.anomaly.end());
        const auto features = synth::syntheticFeatures(o, k * o.dtMyr);
        for (size_t f = 0; f < features.size(); ++f) {
            const auto near = nearFeature(o, k * o.dtMyr, features[f], f, seeds);
            double best = 0;
            for (size_t i = 0; i < seeds.size(); ++i)
                if (near[i])
                    best = std::max(best, seeds[i].persistence);
            lowest[f] = std::min(lowest[f], 100 * best / (*hi - *lo));
            highest[f] = std::max(highest[f], 100 * best / (*hi - *lo));
        }
    }
    const auto features = synth::syntheticFeatures(o, 0);
    fmt::print("persistence of each feature's extremum, % of the step's range (lowest - highest over the steps):\n");
    for (size_t f = 0; f < features.size(); ++f)
        fmt::print("  {} {:>2} ({:>4.0f} K, front at {:>4.0f} km depth at t = 0): {:5.1f} - {:5.1f} %\n",
                   features[f].kind == synth::SynthFeature::Kind::Plume ? "plume" : "slab ", f, features[f].temperatureK,
                   kSurfaceRadiusKm - features[f].frontRadiusKm, lowest[f], highest[f]);
    std::fflush(stdout);
}

}  // namespace

BENCHMARK(BM_Persistence)->Arg(1)->Arg(0)->Unit(benchmark::kMillisecond)->UseRealTime();
BENCHMARK(BM_CriticalPoints)->Arg(1)->Arg(0)->Unit(benchmark::kMillisecond)->UseRealTime();
BENCHMARK(BM_SelectSeeds)->Args({0, 0})->Args({0, 1})->Unit(benchmark::kMillisecond)->UseRealTime();

int main(int argc, char** argv)
{
    raypc::restartWithTransparentHugePages(argv);  // memory as `raypc` has it (render_bench.cpp)
    benchmark::Initialize(&argc, argv);
    std::string cpu;
    std::ifstream info("/proc/cpuinfo");
    for (std::string line; cpu.empty() && std::getline(info, line);)
        if (line.rfind("model name", 0) == 0)
            cpu = line.substr(line.find(':') + 2);
    fmt::print("machine: {} hardware threads, {}\n", std::thread::hardware_concurrency(), cpu);
    const char* report = std::getenv("RAYPC_BENCH_REPORT");
    if (!report || std::string(report) != "0")
        seedReport();
    benchmark::RunSpecifiedBenchmarks();
    benchmark::Shutdown();
    return 0;
}
