// The kept analyses of the server (server/analysis_caches.h): the same numbers and bytes as computed
// afresh, each step or series computed once, bounded, and the endpoints' answers taken from them.
#include "server/analysis_caches.h"

#include "analysis/selection.h"
#include "io/netcdf_reader.h"
#include "preprocess/preprocess.h"
#include "render/resolve_state.h"
#include "server/api_views.h"
#include "server/dataset_api.h"
#include "state/render_state.h"
#include "synth/synth.h"

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>
#include <unistd.h>

#include <algorithm>
#include <atomic>
#include <filesystem>

namespace raypc::server {
namespace {

namespace fs = std::filesystem;
using nlohmann::json;

// A small synthetic series of 4 steps, preprocessed once for the tests of this file.
class AnalysisCaches : public ::testing::Test {
protected:
    static void SetUpTestSuite()
    {
        s_dir = fs::temp_directory_path() / ("raypc_analysis_caches_" + std::to_string(::getpid()));
        fs::remove_all(s_dir);
        synth::SynthOptions synth;
        synth.steps = 4;
        synth.nLat = 16;
        synth.nR = 11;
        synth.nLon = 24;
        synth::writeSyntheticSeries(s_dir / "nc", synth);
        preprocess::PreprocessOptions o;
        o.quiet = true;
        o.sampleRows = 100;
        o.pathlines.enabled = false;
        preprocess::preprocess(io::listSnapshotFiles({s_dir / "nc"}), s_dir / "ds", o);
        s_dataset = dataset::Dataset::open(s_dir / "ds");
    }
    static void TearDownTestSuite()
    {
        s_dataset.reset();
        fs::remove_all(s_dir);
    }

    void SetUp() override
    {
        m_loads = std::make_shared<std::atomic<int>>(0);
        m_volumes = std::make_unique<StepCache>(
            [dataset = s_dataset, loads = m_loads](int step, int level) {
                ++*loads;
                return dataset->load(step, level);
            },
            size_t(1) << 30, 16);
    }

    // The filters of a brush on the temperature anomaly and one on depth, in the order given.
    static std::vector<analysis::RangeFilter> filters(bool depthFirst, float anomalyMin = 50)
    {
        std::vector<analysis::NamedRange> ranges = {{"temperature anomaly", anomalyMin, 1e4f}, {"depth", 100, 2500}};
        if (depthFirst)
            std::reverse(ranges.begin(), ranges.end());
        return analysis::resolveRangeFilters(*s_dataset, ranges);
    }

    // A state document of the dataset with those brushes at `step`.
    static json stateWithBrushes(int step, float anomalyMin = 50)
    {
        json state = state::toJson(render::defaultState(*s_dataset));
        state["step"] = step;
        state["brushes"] = {{{"name", "temperature anomaly"}, {"min", anomalyMin}, {"max", 1e4}},
                            {{"name", "depth"}, {"min", 100}, {"max", 2500}}};
        return state;
    }

    static inline fs::path s_dir;
    static inline std::shared_ptr<const dataset::Dataset> s_dataset;
    std::shared_ptr<std::atomic<int>> m_loads;
    std::unique_ptr<StepCache> m_volumes;
};

TEST_F(AnalysisCaches, SelectionKeyIgnoresTheOrderOfAxesAndRanges)
{
    EXPECT_EQ(analysis::selectionKey(filters(false)), analysis::selectionKey(filters(true)));
    EXPECT_NE(analysis::selectionKey(filters(false)), analysis::selectionKey(filters(false, 60)));
    auto two = filters(false);
    two[0].ranges.push_back({-1e4f, -50});
    auto swapped = two;
    std::reverse(swapped[0].ranges.begin(), swapped[0].ranges.end());
    EXPECT_EQ(analysis::selectionKey(two), analysis::selectionKey(swapped));
    EXPECT_NE(analysis::selectionKey(two), analysis::selectionKey(filters(false)));
}

TEST_F(AnalysisCaches, SelectionStepsAreComputedOnceAndEqualTheUncachedOnes)
{
    SelectionCache cache;
    const int last = int(s_dataset->steps().size()) - 1;
    int computed = 0;
    const auto first = cache.overTime(*s_dataset, *m_volumes, filters(false), 1, 0, last, std::nullopt, nullptr, &computed);
    EXPECT_EQ(computed, last + 1);
    const auto fresh = analysis::selectionOverTime(*s_dataset, filters(false), 1, 0, last);
    ASSERT_EQ(first.size(), fresh.size());
    for (size_t i = 0; i < fresh.size(); ++i) {
        EXPECT_EQ(first[i].step, fresh[i].step);
        EXPECT_EQ(first[i].stats.volumeKm3, fresh[i].stats.volumeKm3);
        EXPECT_EQ(first[i].stats.volumeByRadiusKm3, fresh[i].stats.volumeByRadiusKm3);
    }
    EXPECT_GT(first[0].stats.volumeKm3, 0.0) << "the brush selects something";

    // The same selection with its axes in another order, and one step of it: nothing computed.
    const int loads = *m_loads;
    computed = 0;
    cache.overTime(*s_dataset, *m_volumes, filters(true), 1, 0, last, std::nullopt, nullptr, &computed);
    cache.overTime(*s_dataset, *m_volumes, filters(true), 1, 2, 2, std::nullopt, nullptr, &computed);
    EXPECT_EQ(computed, 0);
    EXPECT_EQ(*m_loads, loads) << "no volume loaded for kept steps";
    // Another level, another mean variable, another brush: computed.
    cache.overTime(*s_dataset, *m_volumes, filters(false), 0, 1, 1, std::nullopt, nullptr, &computed);
    cache.overTime(*s_dataset, *m_volumes, filters(false), 1, 1, 1, size_t(0), nullptr, &computed);
    cache.overTime(*s_dataset, *m_volumes, filters(false, 60), 1, 1, 1, std::nullopt, nullptr, &computed);
    EXPECT_EQ(computed, 3);
    const auto counts = cache.counts();
    EXPECT_EQ(counts.made, size_t(last + 1 + 3));
    EXPECT_EQ(counts.hits, size_t(last + 1 + 1));
}

TEST_F(AnalysisCaches, SelectionCacheIsBoundedAndCancelledStepsAreNotKept)
{
    SelectionCache cache(3);
    int computed = 0;
    cache.overTime(*s_dataset, *m_volumes, filters(false), 1, 0, 3, std::nullopt, nullptr, &computed);
    EXPECT_EQ(computed, 4);
    computed = 0;
    cache.overTime(*s_dataset, *m_volumes, filters(false), 1, 1, 3, std::nullopt, nullptr, &computed);
    EXPECT_EQ(computed, 0) << "the last three steps are kept";
    cache.overTime(*s_dataset, *m_volumes, filters(false), 1, 0, 0, std::nullopt, nullptr, &computed);
    EXPECT_EQ(computed, 1) << "step 0 went out first";

    SelectionCache other;
    std::atomic<bool> cancel{true};
    EXPECT_THROW(other.overTime(*s_dataset, *m_volumes, filters(false), 1, 0, 3, std::nullopt, &cancel), Error);
    computed = 0;
    other.overTime(*s_dataset, *m_volumes, filters(false), 1, 0, 3, std::nullopt, nullptr, &computed);
    EXPECT_EQ(computed, 4);
    EXPECT_THROW(other.overTime(*s_dataset, *m_volumes, filters(false), 7, 0, 3), Error);
    EXPECT_THROW(other.overTime(*s_dataset, *m_volumes, filters(false), 1, 0, 9), Error);
}

// /api/stats' answer: byte for byte the uncached one, for every step asked after the first request,
// computing nothing more; with ?profiles=all every step's profile equals that step's own answer.
TEST_F(AnalysisCaches, StatsAnswersAreTheUncachedBytes)
{
    SelectionCache cache;
    const auto f = filters(false);
    int computed = 0;
    for (int step = 0; step < 4; ++step) {
        const std::string kept = selectionStatsJson(*s_dataset, *m_volumes, f, 1, step, nullptr, &cache, false, &computed).dump();
        const std::string fresh = selectionStatsJson(*s_dataset, *m_volumes, f, 1, step).dump();
        EXPECT_EQ(kept, fresh) << "step " << step;
    }
    EXPECT_EQ(computed, 4) << "every step computed once, for the first request";
    const json all = selectionStatsJson(*s_dataset, *m_volumes, f, 1, 0, nullptr, &cache, true, &computed);
    EXPECT_EQ(computed, 4);
    ASSERT_EQ(all["profiles"].size(), 4u);
    for (int step = 0; step < 4; ++step) {
        const json one = selectionStatsJson(*s_dataset, *m_volumes, f, 1, step);
        EXPECT_EQ(all["profiles"][step]["step"], step);
        EXPECT_EQ(all["profiles"][step]["volumeKm3"].dump(), one["profile"]["volumeKm3"].dump());
        EXPECT_EQ(all["profiles"][step]["shellVolumeKm3"].dump(), one["profile"]["shellVolumeKm3"].dump());
    }
    json withoutProfiles = all;
    withoutProfiles.erase("profiles");
    EXPECT_EQ(withoutProfiles.dump(), selectionStatsJson(*s_dataset, *m_volumes, f, 1, 0).dump());
}

TEST_F(AnalysisCaches, FeatureSeriesKeyNamesWhatTheAnswerDependsOn)
{
    const analysis::FeatureOptions o;
    const std::string key = featureSeriesKey(filters(false), o, 0.3, analysis::StallMeasure::MeanDepth, 1, 2.0);
    EXPECT_EQ(key, featureSeriesKey(filters(true), o, 0.3, analysis::StallMeasure::MeanDepth, 1, 2.0));
    analysis::FeatureOptions bigger = o;
    bigger.minVolumeKm3 = 1e6;
    analysis::FeatureOptions depths = o;
    depths.bandDepthsKm = {660};
    for (const std::string& other :
         {featureSeriesKey(filters(false, 60), o, 0.3, analysis::StallMeasure::MeanDepth, 1, 2.0),
          featureSeriesKey(filters(false), bigger, 0.3, analysis::StallMeasure::MeanDepth, 1, 2.0),
          featureSeriesKey(filters(false), depths, 0.3, analysis::StallMeasure::MeanDepth, 1, 2.0),
          featureSeriesKey(filters(false), o, 0.5, analysis::StallMeasure::MeanDepth, 1, 2.0),
          featureSeriesKey(filters(false), o, 0.3, analysis::StallMeasure::Deepest, 1, 2.0),
          featureSeriesKey(filters(false), o, 0.3, analysis::StallMeasure::MeanDepth, 0, 2.0),
          featureSeriesKey(filters(false), o, 0.3, analysis::StallMeasure::MeanDepth, 1, 3.0)})
        EXPECT_NE(key, other);
}

// The endpoints through the route table: a second identical request (another step, the painting's
// settings changed) is answered from the kept analyses, byte for byte what an uncached server answers.
TEST_F(AnalysisCaches, EndpointsAnswerRepeatedRequestsFromTheCache)
{
    SelectionCache selections;
    FeatureSeriesCache featureSeries(4);
    ApiContext kept, fresh;
    for (ApiContext* api : {&kept, &fresh}) {
        api->dataset = s_dataset;
        api->cache = m_volumes.get();
    }
    kept.selections = &selections;
    kept.featureSeries = &featureSeries;
    auto route = [](std::string_view path) {
        for (const Route& r : apiRoutes())
            if (r.path == path)
                return r.handler;
        ADD_FAILURE() << "no route " << path;
        return ApiHandler{};
    };
    const ApiHandler stats = route("/api/stats"), features = route("/api/features"), selection = route("/api/selection");

    const std::string atStep1 = stateWithBrushes(1).dump();
    const ApiAnswer s1 = stats(kept, {"", atStep1});
    EXPECT_EQ(s1.stepsComputed, 4);
    EXPECT_EQ(s1.body, stats(fresh, {"", atStep1}).body);
    const std::string atStep3 = stateWithBrushes(3).dump();
    const ApiAnswer s3 = stats(kept, {"", atStep3});
    EXPECT_EQ(s3.stepsComputed, 0) << "a step change computes nothing";
    EXPECT_EQ(s3.body, stats(fresh, {"", atStep3}).body);
    EXPECT_EQ(stats(kept, {"", stateWithBrushes(3, 60).dump()}).stepsComputed, 4) << "a new brush";
    EXPECT_EQ(selection(kept, {"", atStep3}).body, selection(fresh, {"", atStep3}).body);

    const ApiAnswer f1 = features(kept, {"", atStep1});
    EXPECT_EQ(f1.stepsComputed, 4);
    EXPECT_EQ(f1.body, features(fresh, {"", atStep1}).body);
    json painted = stateWithBrushes(3);
    painted["features"]["colorById"] = true;
    const ApiAnswer f3 = features(kept, {"", painted.dump()});
    EXPECT_EQ(f3.stepsComputed, 0) << "another step and painting: the kept answer";
    EXPECT_EQ(f3.body, f1.body);
    EXPECT_EQ(featureSeries.counts().made, 1u);
    EXPECT_EQ(featureSeries.counts().hits, 1u);
    json otherLevel = stateWithBrushes(1);
    ASSERT_GE(s_dataset->levels().size(), 2u);
    otherLevel["features"]["level"] = painted["features"].value("level", 0) == 0 ? 1 : 0;
    EXPECT_EQ(features(kept, {"", otherLevel.dump()}).stepsComputed, 4);
    EXPECT_THROW(stats(kept, {"profiles=some", atStep1}), Error);

    // The painted features of the state's step: the labels the features request found, kept for the
    // renderers, equal to what they would extract themselves.
    FeatureLabelsCache labels;
    kept.featureLabels = &labels;
    json atStep2 = stateWithBrushes(2);
    atStep2["features"]["minVolumeKm3"] = 1.0;  // a settings change: the series is computed again
    EXPECT_EQ(features(kept, {"", atStep2.dump()}).stepsComputed, 4);
    const render::ResolvedState resolved = render::resolveState(atStep2, *s_dataset);
    const analysis::FeatureOptions options = state::featureOptions(resolved.state.features);
    const int level = resolved.state.features.level;
    const auto painted2 = labels.get(*m_volumes, 2, level, resolved.params.brushes, options);
    EXPECT_EQ(labels.counts().made, 0u) << "step 2's labels came from the features request";
    EXPECT_EQ(labels.counts().hits, 1u);
    const auto extracted = analysis::extractFeatures(*s_dataset->load(2, level), resolved.params.brushes, options).labels;
    ASSERT_EQ(painted2->size(), extracted.size());
    EXPECT_TRUE(std::equal(painted2->begin(), painted2->end(), extracted.begin()));
    EXPECT_TRUE(std::any_of(extracted.begin(), extracted.end(), [](int32_t l) { return l > 0; })) << "a feature to paint";
    labels.get(*m_volumes, 1, level, resolved.params.brushes, options);
    EXPECT_EQ(labels.counts().made, 1u) << "another step is extracted once";
    labels.get(*m_volumes, 1, level, filters(true), options);
    EXPECT_EQ(labels.counts().made, 1u);
    EXPECT_NE(json::parse(stats(kept, {"profiles=all", atStep1}).body)["profiles"].size(), 0u);
}

}  // namespace
}  // namespace raypc::server
