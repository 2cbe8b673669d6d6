// The task presets (examples/*.json, docs/tasks.md) against the synthetic generator's own truth
// (syntheticTruth): each preset's brushes, applied by the selection code `raypc stats` uses, must
// select most of what its task names (recall) and mostly that (precision) on the demo's grid at
// 0, 12 and 22 Myr. The table the test prints is the one in docs/tasks.md:
//   build/src/render/raypc_render_tests --gtest_filter='TaskPresets.*'
#include "state/render_state.h"

#include "core/spherical.h"
#include "preprocess/preprocess_numerics.h"
#include "analysis/selection.h"
#include "synth/synth.h"

#include <fmt/format.h>
#include <gtest/gtest.h>

#include <functional>

namespace raypc::render {
namespace {

// What a grid point is, for a target: the generator's feature there (nullptr: background), its
// part, whether it is in the part's core, and the point's depth.
struct Point {
    const synth::SynthFeature* feature;
    synth::SynthPart part;
    bool core;
    double depthKm;
};
using Target = std::function<bool(const Point&)>;

bool isSlab(const Point& p) { return p.feature && p.feature->kind == synth::SynthFeature::Kind::Slab; }
bool isPlume(const Point& p) { return p.feature && p.feature->kind == synth::SynthFeature::Kind::Plume; }
bool stallsAt(const Point& p, double depthKm) { return p.feature && p.feature->stallDepthKm == depthKm; }
bool isStem(const Point& p) { return p.part == synth::SynthPart::PlumeConduit || p.part == synth::SynthPart::PlumeHead; }
bool near660(const Point& p) { return p.depthKm >= 560 && p.depthKm <= 760; }

// The expansivity's temperature sensitivity is fully positive above 1500 km, fully negative below
// 2300 km and changes sign at 1900 km (docs/synthetic-data.md, "Material properties"), so "high"
// and "deep" targets are taken beyond the transition, and the right side of it is 1900 km.
constexpr double kHighKm = 1500, kSignChangeKm = 1900, kDeepKm = 2300;

// Thresholds, the same for every preset that has a target: the lowest figure measured over the
// three times is 0.69 for recall (task 1) and 0.82 for precision (task 4), the largest share of
// avoided features 0.002; a broken preset scores far outside them (BrokenPresetsFail).
constexpr double kMinRecall = 0.6, kMinPrecision = 0.75, kMaxAvoided = 0.02;

struct PresetCase {
    const char* file;
    const char* target;   // the recall target, in words (docs/tasks.md's table)
    Target recall;        // the core points of this the preset should select most of
    const char* right;    // in words
    Target isRight;       // points (core or extent) whose selection is right: precision
    const char* avoided;  // in words
    Target avoid;         // points the selection should hold almost none of
    bool assertPrecision = true;
};

std::vector<PresetCase> presetCases()
{
    auto slabHighPlumeDeep = [](const Point& p) {
        return (isSlab(p) && p.depthKm < kHighKm) || (isPlume(p) && isStem(p) && p.depthKm > kDeepKm);
    };
    auto slabAbovePlumeBelow = [](const Point& p) {
        return (isSlab(p) && p.depthKm < kSignChangeKm) || (isPlume(p) && p.depthKm > kSignChangeKm);
    };
    auto plumeAboveSlabBelow = [](const Point& p) {
        return (isPlume(p) && p.depthKm < kSignChangeKm) || (isSlab(p) && p.depthKm > kSignChangeKm);
    };
    return {
        {"task1-slabs-660km.json", "slabs stalled at 660 km, at 560–760 km",
         [](const Point& p) { return isSlab(p) && stallsAt(p, 660) && near660(p); }, "slabs at 560–760 km",
         [](const Point& p) { return isSlab(p) && near660(p); }, "plumes", isPlume},
        {"task2-slabs-1600km.json", "slabs at 1000–2200 km (the spin band)",
         [](const Point& p) { return isSlab(p) && p.depthKm >= 1000 && p.depthKm <= 2200; }, "slabs", isSlab, "plumes",
         isPlume},
        {"task3-plumes-1600km.json", "heads and pancakes of the plumes stalled at 1600 km",
         [](const Point& p) {
             return isPlume(p) && stallsAt(p, 1600) &&
                    (p.part == synth::SynthPart::PlumeHead || p.part == synth::SynthPart::PlumePancake1600);
         },
         "plumes", isPlume, "slabs", isSlab},
        {"task4-plumes-660km.json", "plumes stalled at 660 km, at 560–760 km",
         [](const Point& p) { return isPlume(p) && stallsAt(p, 660) && near660(p); }, "plumes at 560–760 km",
         [](const Point& p) { return isPlume(p) && near660(p); }, "slabs", isSlab},
        {"task5a-expansivity-negative.json", "slabs above 1500 km, plume stems below 2300 km", slabHighPlumeDeep,
         "slabs above, plumes below 1900 km", slabAbovePlumeBelow, "plumes above, slabs below 1900 km",
         plumeAboveSlabBelow},
        {"task5b-expansivity-negative-cold-high.json", "slabs above 1500 km",
         [](const Point& p) { return isSlab(p) && p.depthKm < kHighKm; }, "slabs", isSlab, "plumes", isPlume},
        {"task5c-expansivity-negative-hot-deep.json", "plume stems (conduits, heads) below 2300 km",
         [](const Point& p) { return isPlume(p) && isStem(p) && p.depthKm > kDeepKm; }, "plumes", isPlume, "slabs",
         isSlab},
        {"task5d-expansivity-positive.json", "plumes above 1500 km, slabs below 2300 km",
         [](const Point& p) { return (isPlume(p) && p.depthKm < kHighKm) || (isSlab(p) && p.depthKm > kDeepKm); },
         "plumes above, slabs below 1900 km", plumeAboveSlabBelow, "slabs above, plumes below 1900 km",
         slabAbovePlumeBelow},
        {"task5e-expansivity-negative-pathlines.json", "slabs above 1500 km, plume stems below 2300 km",
         slabHighPlumeDeep, "slabs above, plumes below 1900 km", slabAbovePlumeBelow,
         "plumes above, slabs below 1900 km", plumeAboveSlabBelow},
        // Absolute temperature selects a layer of the reference profile above the CMB, not a
        // feature: its precision against features is printed, not asserted, and the cold pools
        // lying in that layer are selected too.
        {"appendix-hot-with-pathlines.json", "plume piles on the CMB",
         [](const Point& p) { return p.part == synth::SynthPart::PlumePile; }, "plumes", isPlume, "",
         [](const Point&) { return false; }, false},
    };
}

// One time of the demo (the default SynthOptions: seed 1, 64 x 81 x 128): its volume with the
// derived variables preprocessing adds, and its points classified by (feature, part, core, radius)
// so that any selection is split by target in one pass.
struct DemoTime {
    double timeMyr;
    std::vector<synth::SynthFeature> features;
    std::vector<double> rKm;
    std::shared_ptr<dataset::StepVolume> volume;
    std::vector<std::string> variableNames;
    std::vector<uint32_t> classes;
    size_t classCount = 0;

    explicit DemoTime(double t) : timeMyr(t)
    {
        const synth::SynthOptions options;
        features = synth::syntheticFeatures(options, t);
        grid::Snapshot snap = synth::synthesizeSnapshot(options, t);
        preprocess::addDerivedVariables(snap);
        for (const grid::Field& f : snap.fields)
            variableNames.push_back(f.name);
        const synth::SynthTruth truth = synth::syntheticTruth(options, t, snap.grid);
        const grid::SphericalGrid& g = snap.grid;
        rKm = g.rKm;
        classCount = (features.size() + 1) * synth::kSynthPartCount * 2 * g.nR();
        classes.resize(g.cellCount());
        for (size_t iLat = 0; iLat < g.nLat(); ++iLat)
            for (size_t iR = 0; iR < g.nR(); ++iR)
                for (size_t iLon = 0; iLon < g.nLon(); ++iLon) {
                    const size_t i = g.index(iLat, iR, iLon);
                    const size_t featurePart = size_t(truth.feature[i] + 1) * synth::kSynthPartCount + size_t(truth.part[i]);
                    classes[i] = static_cast<uint32_t>((featurePart * 2 + (truth.inCore(i) ? 1 : 0)) * g.nR() + iR);
                }
        volume = dataset::StepVolume::fromSnapshot(snap);
    }

    Point decode(size_t c) const
    {
        const size_t iR = c % rKm.size();
        c /= rKm.size();
        const bool core = c % 2 == 1;
        c /= 2;
        const size_t f = c / synth::kSynthPartCount;
        return {f == 0 ? nullptr : &features[f - 1], static_cast<synth::SynthPart>(c % synth::kSynthPartCount), core,
                kSurfaceRadiusKm - rKm[iR]};
    }
};

const std::vector<DemoTime>& demoTimes()
{
    static const std::vector<DemoTime> times = [] {
        std::vector<DemoTime> t;
        for (double myr : {0.0, 12.0, 22.0})  // the demo's first, figure (step 6) and last step
            t.emplace_back(myr);
        return t;
    }();
    return times;
}

struct Figures {
    double recall = 0, precision = 0, avoided = 0;
};

Figures measure(const DemoTime& demo, const PresetCase& preset, std::span<const state::BrushSpec> brushes)
{
    const auto filters = analysis::resolveRangeFilters(std::span<const std::string>(demo.variableNames), brushes);
    const analysis::ClassVolumes v = analysis::selectedVolumeByClass(*demo.volume, filters, demo.classes, demo.classCount);
    double target = 0, targetSelected = 0, selected = 0, right = 0, avoided = 0;
    for (size_t c = 0; c < demo.classCount; ++c) {
        const Point p = demo.decode(c);
        selected += v.selectedKm3[c];
        if (p.core && preset.recall(p)) {
            target += v.totalKm3[c];
            targetSelected += v.selectedKm3[c];
        }
        if (preset.isRight(p))
            right += v.selectedKm3[c];
        if (preset.avoid(p))
            avoided += v.selectedKm3[c];
    }
    // A target that is not there would make every preset pass: it must be.
    EXPECT_GT(target, 1e7) << preset.file << " at " << demo.timeMyr << " Myr: no target";
    return {target > 0 ? targetSelected / target : 0, selected > 0 ? right / selected : 0,
            selected > 0 ? avoided / selected : 0};
}

std::vector<state::BrushSpec> presetBrushes(const char* file)
{
    return state::loadRenderState(std::filesystem::path(RAYPC_SOURCE_DIR) / "examples" / file).brushes;
}

TEST(TaskPresets, FindWhatTheyNameInTheSyntheticTruth)
{
    std::string table = "| preset | recall target (its core) | recall at 0 / 12 / 22 Myr | right when | precision | "
                        "share of | |\n|---|---|---|---|---|---|---|\n";
    auto three = [](const std::array<double, 3>& v, int digits) {
        return fmt::format("{:.{}f} / {:.{}f} / {:.{}f}", v[0], digits, v[1], digits, v[2], digits);
    };
    for (const PresetCase& preset : presetCases()) {
        SCOPED_TRACE(preset.file);
        const std::vector<state::BrushSpec> brushes = presetBrushes(preset.file);
        std::array<double, 3> recall{}, precision{}, avoided{};
        for (size_t t = 0; t < demoTimes().size(); ++t) {
            const DemoTime& demo = demoTimes()[t];
            const Figures f = measure(demo, preset, brushes);
            recall[t] = f.recall;
            precision[t] = f.precision;
            avoided[t] = f.avoided;
            EXPECT_GE(f.recall, kMinRecall) << demo.timeMyr << " Myr";
            if (preset.assertPrecision) {
                EXPECT_GE(f.precision, kMinPrecision) << demo.timeMyr << " Myr";
                EXPECT_LE(f.avoided, kMaxAvoided) << demo.timeMyr << " Myr: " << preset.avoided;
            }
        }
        const bool avoids = preset.assertPrecision;
        fmt::format_to(std::back_inserter(table), "| `{}` | {} | {} | {} | {} | {} | {} |\n", preset.file, preset.target,
                       three(recall, 2), preset.right, three(precision, 2), avoids ? preset.avoided : "—",
                       avoids ? three(avoided, 3) : "—");
    }
    fmt::print("\nVolume-weighted recall and precision of the presets on the demo (seed 1, 64x81x128):\n{}", table);
}

// The test can fail: presets with a brush flipped, dropped or made too weak score outside the
// thresholds (at the figure time, 12 Myr).
TEST(TaskPresets, BrokenPresetsFail)
{
    const DemoTime& demo = demoTimes()[1];
    const auto cases = presetCases();
    auto find = [&](const char* file) {
        return *std::find_if(cases.begin(), cases.end(), [&](const PresetCase& c) { return std::string(c.file) == file; });
    };
    auto with = [](std::vector<state::BrushSpec> brushes, const std::string& name, float min, float max) {
        std::erase_if(brushes, [&](const state::BrushSpec& b) { return b.name == name; });
        brushes.push_back({name, min, max});
        return brushes;
    };
    auto without = [](std::vector<state::BrushSpec> brushes, const std::string& name) {
        std::erase_if(brushes, [&](const state::BrushSpec& b) { return b.name == name; });
        return brushes;
    };
    auto broken = [&](const PresetCase& preset, const char* change, const std::vector<state::BrushSpec>& brushes) {
        const Figures f = measure(demo, preset, brushes);
        fmt::print("{} {}: recall {:.2f}, precision {:.2f}, share of {} {:.3f}\n", preset.file, change, f.recall,
                   f.precision, preset.avoided, f.avoided);
        return f;
    };
    const PresetCase task1 = find("task1-slabs-660km.json");
    const auto brushes1 = presetBrushes(task1.file);
    EXPECT_LT(broken(task1, "with temperature anomaly > 25 K", with(brushes1, "temperature anomaly", 25, 10000)).recall,
              kMinRecall);
    EXPECT_LT(broken(task1, "without depth", without(brushes1, "depth")).precision, kMinPrecision);

    const PresetCase task3 = find("task3-plumes-1600km.json");
    const Figures cold = broken(task3, "with temperature anomaly < -60 K",
                                with(presetBrushes(task3.file), "temperature anomaly", -10000, -60));
    EXPECT_LT(cold.recall, kMinRecall);
    EXPECT_GT(cold.avoided, kMaxAvoided);

    // Task 4 at its former 25 K: the slabs' pancakes lower the 660 km shells' mean so much that
    // most of the band is 25 K warmer than it.
    const PresetCase task4 = find("task4-plumes-660km.json");
    const auto brushes4 = presetBrushes(task4.file);
    EXPECT_LT(broken(task4, "with temperature anomaly > 25 K (the former preset)",
                     with(brushes4, "temperature anomaly", 25, 10000))
                  .precision,
              kMinPrecision);
    EXPECT_LT(broken(task4, "without depth", without(brushes4, "depth")).precision, kMinPrecision);

    // The negative expansivity preset with the sign of 5d finds the other pair.
    const PresetCase task5a = find("task5a-expansivity-negative.json");
    const Figures positive = broken(task5a, "with the brush of 5d", presetBrushes("task5d-expansivity-positive.json"));
    EXPECT_LT(positive.recall, kMinRecall);
    EXPECT_GT(positive.avoided, kMaxAvoided);
}

}  // namespace
}  // namespace raypc::render
