#include "analysis/feature_run.h"

#include "core/error.h"
#include "core/spherical.h"
#include "grid/test_util.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <atomic>
#include <mutex>
#include <thread>
#include <utility>
#include <vector>

namespace raypc::analysis {
namespace {

// Step k's volume: k + 1 separate blobs of "f" along the equator, so that each step's feature count
// names the step.
std::shared_ptr<const dataset::StepVolume> blobsOfStep(const grid::SphericalGrid& g, int step)
{
    grid::Snapshot snap;
    snap.grid = g;
    snap.fields.push_back({"f", "K", testing::fillGrid(g, [&](size_t a, size_t r, size_t o) {
                               double v = 0;
                               for (int k = 0; k <= step; ++k)
                                   v += testing::gaussianBlob(g, a, r, o, 0.0, 60.0 * k, kSurfaceRadiusKm - 1500.0, 700.0);
                               return v;
                           })});
    return dataset::StepVolume::fromSnapshot(snap);
}

const std::vector<RangeFilter> kAboveHalf{RangeFilter{0, std::nullopt, {{0.5f, 1e30f}}}};

TEST(FeatureRun, EveryStepInOrderWithItsVolumeAndProgressBeforeEachAndAfterTheLast)
{
    const grid::SphericalGrid g = testing::centredGrid(36, 21, 72);
    std::vector<int> loaded, counts;
    std::mutex loadedMutex;  // steps load on other threads, ahead of the one handed over
    std::vector<std::pair<int, int>> progress;
    const auto caller = std::this_thread::get_id();
    const auto stopped = forEachStepFeatures(
        1, 3,
        [&](int step) {
            std::lock_guard lock(loadedMutex);
            loaded.push_back(step);
            return blobsOfStep(g, step);
        },
        kAboveHalf, {},
        [&](FeatureStep& s) {
            EXPECT_EQ(std::this_thread::get_id(), caller) << "onStep runs on the calling thread";
            EXPECT_EQ(s.volume->grid().nLon(), g.nLon());
            EXPECT_EQ(s.features.labels.size(), g.nLat() * g.nR() * g.nLon());
            counts.push_back(int(s.features.features.size()));
        },
        {nullptr, [&](int done, int total) { progress.emplace_back(done, total); }});
    EXPECT_FALSE(stopped);
    std::sort(loaded.begin(), loaded.end());
    EXPECT_EQ(loaded, (std::vector<int>{1, 2, 3})) << "each step loaded once";
    EXPECT_EQ(counts, (std::vector<int>{2, 3, 4}));
    EXPECT_EQ(progress, (std::vector<std::pair<int, int>>{{0, 3}, {1, 3}, {2, 3}, {3, 3}}));
}

TEST(FeatureRun, CancellingStopsBeforeTheNextStepAndSaysWhich)
{
    const grid::SphericalGrid g = testing::centredGrid(36, 21, 72);
    std::atomic<bool> cancel{false};
    std::vector<int> done;
    std::vector<std::pair<int, int>> progress;
    // Cancelled by the progress report before step 2 (as Python's callback cancels): step 2 is not run.
    const auto stopped = forEachStepFeatures(
        0, 4, [&](int step) { return blobsOfStep(g, step); }, kAboveHalf, {},
        [&](FeatureStep& s) { done.push_back(s.step); },
        {&cancel, [&](int d, int total) {
             progress.emplace_back(d, total);
             if (d == 2)
                 cancel = true;
         }});
    ASSERT_TRUE(stopped);
    EXPECT_EQ(*stopped, 2);
    EXPECT_EQ(done, (std::vector<int>{0, 1}));
    EXPECT_EQ(progress.back(), (std::pair<int, int>{2, 5})) << "no last report after a cancelled run";
    // Cancelled before it starts: nothing is loaded.
    const auto none = forEachStepFeatures(
        0, 4, [&](int) -> std::shared_ptr<const dataset::StepVolume> { throw Error("loaded"); }, kAboveHalf, {},
        [](FeatureStep&) {}, {&cancel, {}});
    EXPECT_EQ(none, std::optional<int>(0));
}

// A step that fails to load (or extract) fails the run when its turn comes: the steps before it are
// handed over first, whatever was loaded ahead.
TEST(FeatureRun, AStepThatFailsIsThrownInItsTurnAfterTheStepsBefore)
{
    const grid::SphericalGrid g = testing::centredGrid(36, 21, 72);
    std::vector<int> done;
    try {
        forEachStepFeatures(
            0, 5,
            [&](int step) {
                if (step == 3)
                    throw Error("step 3 is damaged");
                return blobsOfStep(g, step);
            },
            kAboveHalf, {}, [&](FeatureStep& s) { done.push_back(s.step); });
        FAIL() << "no error";
    } catch (const Error& e) {
        EXPECT_STREQ(e.what(), "step 3 is damaged");
    }
    EXPECT_EQ(done, (std::vector<int>{0, 1, 2}));
}

}  // namespace
}  // namespace raypc::analysis
