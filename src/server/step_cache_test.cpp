#include "server/step_cache.h"

#include "core/error.h"
#include "io/netcdf_reader.h"
#include "dataset/dataset_format.h"
#include "preprocess/preprocess.h"
#include "synth/synth.h"

#include <gtest/gtest.h>
#include <unistd.h>

#include <atomic>
#include <filesystem>

namespace raypc::server {
namespace {

// A small in-memory volume whose values encode (step, level), 8 x 4 x 16 points, one variable.
std::shared_ptr<const dataset::StepVolume> makeVolume(int step, int level)
{
    grid::Snapshot s;
    for (int i = 0; i < 8; ++i)
        s.grid.latDeg.push_back(-80.0 + 20.0 * i);
    for (int i = 0; i < 4; ++i)
        s.grid.rKm.push_back(3500.0 + 900.0 * i);
    for (int i = 0; i < 16; ++i)
        s.grid.lonDeg.push_back(22.5 * i);
    s.fields.push_back({"v", "1", std::vector<float>(s.grid.cellCount(), float(step * 10 + level))});
    return dataset::StepVolume::fromSnapshot(s);
}

struct CountingLoader {
    std::shared_ptr<std::atomic<int>> calls = std::make_shared<std::atomic<int>>(0);
    std::shared_ptr<const dataset::StepVolume> operator()(int step, int level) const
    {
        ++*calls;
        if (step < 0)
            fail("step {} out of range", step);
        return makeVolume(step, level);
    }
};

TEST(StepCache, HitsDoNotReload)
{
    CountingLoader loader;
    StepCache cache(loader, size_t(1) << 30, 8);
    const auto a = cache.get(1, 0);
    const auto b = cache.get(1, 0);
    EXPECT_EQ(a.get(), b.get());
    EXPECT_EQ(*loader.calls, 1);
    EXPECT_EQ(a->values(0)[0], 10.0f);
    EXPECT_EQ(cache.get(1, 2)->values(0)[0], 12.0f);
    EXPECT_EQ(*loader.calls, 2);
}

// A new step takes the shading gradient's memory of a step that only the cache holds; a step a
// renderer holds keeps its gradient (the renderer reads it through pointers).
TEST(StepCache, ANewStepDropsTheGradientsOfStepsNoOneHolds)
{
    CountingLoader loader;
    StepCache cache(loader, size_t(1) << 30, 8);
    const size_t gradientBytes = 3 * cache.get(0, 0)->grid().cellCount() * sizeof(float);
    cache.get(0, 0)->nodeGradient(0);  // shown, then let go
    const auto held = cache.get(1, 0);
    held->nodeGradient(0);
    cache.get(2, 0);
    EXPECT_EQ(cache.get(0, 0)->dropGradients(), 0u) << "step 0's gradient stayed though no one held it";
    EXPECT_EQ(held->dropGradients(), gradientBytes) << "step 1's gradient went while held";
    EXPECT_EQ(*loader.calls, 3);
}

TEST(StepCache, BoundedByEntriesWhilePlayingManySteps)
{
    CountingLoader loader;
    StepCache cache(loader, size_t(1) << 30, 3);
    for (int step = 0; step < 100; ++step) {
        cache.get(step, 0);
        EXPECT_LE(cache.entries(), 3u);
    }
    EXPECT_TRUE(cache.contains(99, 0));
    EXPECT_TRUE(cache.contains(97, 0));
    EXPECT_FALSE(cache.contains(96, 0));
}

TEST(StepCache, BoundedByBytesLeastRecentlyUsedFirst)
{
    CountingLoader loader;
    const size_t one = StepCache::volumeBytes(*makeVolume(0, 0));
    EXPECT_GE(one, 8u * 4 * 16 * sizeof(float));
    StepCache cache(loader, 2 * one + one / 2, 100);  // room for two
    cache.get(0, 0);
    cache.get(1, 0);
    cache.get(0, 0);  // 0 is now the most recently used
    cache.get(2, 0);  // evicts 1
    EXPECT_TRUE(cache.contains(0, 0));
    EXPECT_FALSE(cache.contains(1, 0));
    EXPECT_TRUE(cache.contains(2, 0));
    EXPECT_LE(cache.bytes(), 2 * one + one / 2);
    for (int step = 3; step < 50; ++step)
        cache.get(step, 1);
    EXPECT_EQ(cache.entries(), 2u);
    EXPECT_LE(cache.bytes(), 2 * one + one / 2);
}

TEST(StepCache, EvictedVolumesStayValidForTheirUsers)
{
    CountingLoader loader;
    StepCache cache(loader, 1, 1);  // holds one entry at most
    const auto held = cache.get(5, 0);
    cache.get(6, 0);
    EXPECT_FALSE(cache.contains(5, 0));
    EXPECT_EQ(held->values(0)[0], 50.0f);
}

TEST(StepCache, PrefetchLoadsInTheBackground)
{
    CountingLoader loader;
    StepCache cache(loader, size_t(1) << 30, 8);
    cache.prefetch(4, 2);
    cache.waitForPrefetch();
    EXPECT_TRUE(cache.contains(4, 2));
    const int calls = *loader.calls;
    cache.get(4, 2);
    EXPECT_EQ(*loader.calls, calls);  // served from the prefetch
    cache.prefetch(4, 2);             // already cached: no load
    cache.waitForPrefetch();
    EXPECT_EQ(*loader.calls, calls);
}

TEST(StepCache, LoaderErrorsReachTheCallerAndSpareThePrefetchThread)
{
    CountingLoader loader;
    StepCache cache(loader, size_t(1) << 30, 8);
    EXPECT_THROW(cache.get(-1, 0), Error);
    cache.prefetch(-1, 0);  // logged, not thrown
    cache.waitForPrefetch();
    EXPECT_FALSE(cache.contains(-1, 0));
    cache.prefetch(2, 0);
    cache.waitForPrefetch();
    EXPECT_TRUE(cache.contains(2, 0));
}

TEST(StepCache, ScansDoNotEvictTheWorkingSet)
{
    CountingLoader loader;
    StepCache cache(loader, size_t(1) << 30, 2);
    cache.get(0, 0);
    cache.get(1, 0);
    // A scan over other steps loads them but keeps the two entries in use.
    for (int step = 2; step < 6; ++step)
        EXPECT_FLOAT_EQ(cache.getWithoutEvicting(step, 1)->values(0)[0], float(step * 10 + 1));
    EXPECT_TRUE(cache.contains(0, 0));
    EXPECT_TRUE(cache.contains(1, 0));
    EXPECT_EQ(cache.entries(), 2u);
    // A cached entry is returned without a load.
    const int calls = *loader.calls;
    cache.getWithoutEvicting(0, 0);
    EXPECT_EQ(*loader.calls, calls);
    // With room, a scanned volume is kept (as the least recently used entry).
    StepCache roomy(loader, size_t(1) << 30, 4);
    roomy.get(0, 0);
    roomy.getWithoutEvicting(3, 0);
    EXPECT_TRUE(roomy.contains(3, 0));
    roomy.get(1, 0);
    roomy.get(2, 0);
    roomy.get(4, 0);  // evicts the scanned entry first
    EXPECT_FALSE(roomy.contains(3, 0));
    EXPECT_TRUE(roomy.contains(0, 0));
}

// A u16 dataset's volumes grow as their variables are decoded (docs/format.md, "Loading"): the cache
// counts the decoded values when a volume is next asked for, and a prefetch decodes the variables the
// current step shows.
TEST(StepCache, CountsDecodedValuesAndPrefetchDecodesWhatIsShown)
{
    const auto dir = std::filesystem::temp_directory_path() / ("raypc_step_cache_u16_" + std::to_string(::getpid()));
    std::filesystem::remove_all(dir);
    preprocess::PreprocessOptions o;
    o.quiet = true;
    o.sampleRows = 500;
    o.pathlines.enabled = false;
    preprocess::preprocess(io::listSnapshotFiles({std::filesystem::path(RAYPC_TEST_DATA_DIR) / "contest-layout"}), dir, o);
    {
        const auto dataset = dataset::Dataset::open(dir);
        ASSERT_EQ(dataset->encoding(), dataset::ValueEncoding::Uint16);
        StepCache cache([dataset](int step, int level) { return dataset->load(step, level); }, size_t(1) << 30, 8);
        const auto a = cache.get(0, 0);
        const size_t floats = a->grid().cellCount() * sizeof(float);
        // Mapped u16 arrays and bounds of the stored variables (the computed anomalies have none until
        // asked for), room for a gradient (3 floats a point) and one decoded variable.
        size_t mapped = 0;
        for (const auto& v : dataset->variables())
            if (!v.computed)
                mapped += a->grid().cellCount() * 2 + a->bricks().brickCount() * 2 * sizeof(float);
        EXPECT_EQ(a->memoryBytes(), mapped);
        EXPECT_EQ(cache.bytes(), mapped + 3 * floats + floats);
        a->values(2);
        a->values(5);
        EXPECT_EQ(a->decodedBytes(), 2 * floats);
        cache.get(0, 0);
        EXPECT_EQ(cache.bytes(), mapped + 2 * floats + 3 * floats);
        cache.prefetch(1, 0);
        cache.waitForPrefetch();
        const auto b = cache.get(1, 0);
        EXPECT_TRUE(b->valuesReady(2));
        EXPECT_TRUE(b->valuesReady(5));
        EXPECT_FALSE(b->valuesReady(0));
        EXPECT_EQ(cache.bytes(), 2 * (mapped + 2 * floats + 3 * floats));
    }
    std::filesystem::remove_all(dir);
}


// `truncate -s 0` of an array of a cached step once killed the server with SIGBUS when a
// session next read it. A cut file now makes the cache drop the step and load it again, which names the file.
TEST(StepCache, AFileCutShortWhileCachedIsDroppedAndTheReloadNamesIt)
{
    const auto dir = std::filesystem::temp_directory_path() / ("raypc_step_cache_cut_" + std::to_string(::getpid()));
    std::filesystem::remove_all(dir);
    synth::SynthOptions synth;
    synth.steps = 2;
    synth.nLat = 12;
    synth.nR = 9;
    synth.nLon = 16;
    synth::writeSyntheticSeries(dir / "nc", synth);
    preprocess::PreprocessOptions o;
    o.quiet = true;
    o.sampleRows = 100;
    o.pathlines.enabled = false;
    preprocess::preprocess(io::listSnapshotFiles({dir / "nc"}), dir / "ds", o);
    {
        const auto dataset = dataset::Dataset::open(dir / "ds");
        StepCache cache([dataset](int step, int level) { return dataset->load(step, level); }, size_t(1) << 30, 8);
        const auto a = cache.get(0, 0);
        a->values(0);  // a first frame
        const auto file = dataset::format::encodedValuesFile(dataset::format::levelDir(dataset::format::stepDir(dir / "ds", 0), 0), "vx");
        std::filesystem::resize_file(file, 0);
        try {
            cache.get(0, 0)->values(static_cast<size_t>(dataset->variableIndex("vx")));
            ADD_FAILURE() << "no error";
        } catch (const Error& e) {
            EXPECT_NE(std::string(e.what()).find(file.string() + ": 0 bytes, expected"), std::string::npos) << e.what();
        }
        EXPECT_FALSE(cache.contains(0, 0));
        EXPECT_EQ(cache.get(1, 0)->values(0)[0], cache.get(1, 0)->values(0)[0]);  // other steps serve on
        // The volume a renderer still holds refuses the cut file too.
        try {
            a->values(static_cast<size_t>(dataset->variableIndex("vx")));
            ADD_FAILURE() << "no error";
        } catch (const Error& e) {
            EXPECT_NE(std::string(e.what()).find("cut short while in use"), std::string::npos) << e.what();
        }
    }
    std::filesystem::remove_all(dir);
}

}  // namespace
}  // namespace raypc::server
