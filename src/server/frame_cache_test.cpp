#include "server/frame_cache.h"

#include <gtest/gtest.h>

#include <memory>

namespace raypc::server {
namespace {

// A frame of about `jpegBytes` (its depth map and header add a little: EncodedFrame::bytes).
std::shared_ptr<const EncodedFrame> frameOf(size_t jpegBytes)
{
    auto f = std::make_shared<EncodedFrame>();
    f->header = {{"type", "frame"}};
    f->jpeg.assign(jpegBytes, 'x');
    f->depth.assign(16, 1.0f);
    f->depthWidth = f->depthHeight = 4;
    return f;
}

// The kept frames count in the sessions' frame memory (--session-memory): a frame that would take the
// total over the limit is refused even though the cache's own bound has room, and the bytes come
// back when the frames go (a new key, reclaiming, the cache's end).
TEST(FrameCache, KeptFramesCountInTheSessionsFrameMemory)
{
    const size_t frameBytes = frameOf(1000)->bytes();
    FrameBudget budget(10 * frameBytes);
    size_t image = 0, others = 0;
    ASSERT_TRUE(budget.replace(image, 7 * frameBytes + frameBytes / 2, others));  // a session's image
    {
        FrameCache cache(100 * frameBytes, &budget);
        cache.setKey("a");
        EXPECT_TRUE(cache.insert("a", 0, frameOf(1000)));
        EXPECT_TRUE(cache.insert("a", 1, frameOf(1000)));
        EXPECT_FALSE(cache.hasRoomFor(frameBytes)) << "the budget has half a frame left";
        EXPECT_FALSE(cache.insert("a", 2, frameOf(1000))) << "a frame over the sessions' frame memory was kept";
        EXPECT_EQ(cache.frames(), 2u);
        EXPECT_EQ(budget.keptBytes(), 2 * frameBytes);
        EXPECT_EQ(budget.usedBytes(), image + 2 * frameBytes);

        // A state's image counts the kept frames as held by others, and fits once they are reclaimed.
        size_t other = 0;
        EXPECT_FALSE(budget.replace(other, 2 * frameBytes, others));
        EXPECT_EQ(others, image + 2 * frameBytes);
        EXPECT_EQ(budget.reclaimKeptFrames(), 2 * frameBytes);
        EXPECT_EQ(cache.frames(), 0u);
        EXPECT_EQ(budget.keptBytes(), 0u);
        ASSERT_TRUE(budget.replace(other, 2 * frameBytes, others));
        budget.release(other);

        // A new key gives its frames' bytes back.
        EXPECT_TRUE(cache.insert("a", 3, frameOf(1000)));
        EXPECT_EQ(budget.keptBytes(), frameBytes);
        cache.setKey("b");
        EXPECT_EQ(budget.keptBytes(), 0u);
        EXPECT_TRUE(cache.insert("b", 0, frameOf(1000)));
        EXPECT_EQ(budget.keptBytes(), frameBytes);

        // A finished frame replacing a draft of its step counts its own bytes, not both.
        auto draft = std::make_shared<EncodedFrame>(*frameOf(500));
        draft->finished = false;
        EXPECT_TRUE(cache.insert("b", 1, draft));
        EXPECT_EQ(budget.keptBytes(), frameBytes + draft->bytes());
        EXPECT_TRUE(cache.insert("b", 1, frameOf(1000)));
        EXPECT_EQ(budget.keptBytes(), 2 * frameBytes);
        EXPECT_EQ(cache.bytes(), 2 * frameBytes);
    }
    EXPECT_EQ(budget.keptBytes(), 0u) << "a cache's end did not give its frames' bytes back";
    EXPECT_EQ(budget.usedBytes(), image);
    EXPECT_EQ(budget.reclaimKeptFrames(), 0u) << "a cache that ended is still reclaimed";
}

// Without a budget the cache's own bound alone decides, and a frame over it is refused, never let in
// by evicting another.
TEST(FrameCache, OwnBoundRefusesWithoutEvicting)
{
    const size_t frameBytes = frameOf(1000)->bytes();
    FrameCache cache(2 * frameBytes + 10);
    cache.setKey("k");
    EXPECT_TRUE(cache.insert("k", 0, frameOf(1000)));
    EXPECT_TRUE(cache.insert("k", 1, frameOf(1000)));
    EXPECT_FALSE(cache.insert("k", 2, frameOf(1000)));
    EXPECT_NE(cache.find("k", 0), nullptr);
    EXPECT_NE(cache.find("k", 1), nullptr);
    EXPECT_EQ(cache.find("k", 2), nullptr);
    EXPECT_EQ(cache.find("other", 0), nullptr) << "a frame found under another key";
}

// A draft (one pass rendered ahead while playing) answers playback only, and only when no coarser
// than the level asked; a finished frame of its step replaces it, and nothing replaces a finished frame.
TEST(FrameCache, DraftsAnswerPlaybackAndGiveWayToFinishedFrames)
{
    FrameCache cache(1 << 20);
    cache.setKey("k");
    auto draft = std::make_shared<EncodedFrame>(*frameOf(300));
    draft->finished = false;
    draft->header["level"] = 1;
    ASSERT_TRUE(cache.insert("k", 4, draft));
    EXPECT_EQ(cache.find("k", 4), nullptr) << "a still was answered by a draft";
    EXPECT_FALSE(cache.contains("k", 4));
    EXPECT_EQ(cache.find("k", 4, 0), nullptr) << "a draft at level 1 answered a step whose own level is 0";
    EXPECT_EQ(cache.find("k", 4, 1), draft);
    EXPECT_TRUE(cache.contains("k", 4, false));

    auto another = std::make_shared<EncodedFrame>(*draft);
    EXPECT_FALSE(cache.insert("k", 4, another)) << "a draft replaced a draft";
    const auto finished = frameOf(1000);
    ASSERT_TRUE(cache.insert("k", 4, finished));
    EXPECT_EQ(cache.find("k", 4), finished);
    EXPECT_EQ(cache.bytes(), finished->bytes()) << "the draft's bytes were not given back";
    EXPECT_EQ(cache.frames(), 1u);
    EXPECT_FALSE(cache.insert("k", 4, draft)) << "a draft replaced a finished frame";
    EXPECT_FALSE(cache.insert("k", 4, frameOf(2000))) << "a finished frame was replaced";
    EXPECT_EQ(cache.find("k", 4, 0), finished);
}

// The drafts' level follows the level most steps of playback reached, not the finest: at 5 steps/s
// on a full-resolution series the first step rendered at level 1 and the 22 after it at level 2.
TEST(FrameCache, TypicalPlaybackLevelIsTheMedian)
{
    EXPECT_EQ(typicalPlaybackLevel({0, 0, 0}), -1);
    EXPECT_EQ(typicalPlaybackLevel({}), -1);
    EXPECT_EQ(typicalPlaybackLevel({0, 1, 22}), 2);
    EXPECT_EQ(typicalPlaybackLevel({0, 1, 0}), 1);
    EXPECT_EQ(typicalPlaybackLevel({12, 11, 0}), 0);
    EXPECT_EQ(typicalPlaybackLevel({1, 0, 1}), 0);  // a tie: the finer
    EXPECT_EQ(typicalPlaybackLevel({1, 1, 3}), 2);
    EXPECT_EQ(typicalPlaybackLevel({2, 1, 3}), 1);
}

}  // namespace
}  // namespace raypc::server
