// Two datasets side by side (render/pair_state.h): the second's step by index and by time, the
// first's colour range, the halves' widths and their composition, on the contest-layout fixture
// preprocessed with different step spacings.
#include "render/pair_state.h"

#include "core/error.h"
#include "grid/test_util.h"
#include "io/netcdf_reader.h"
#include "preprocess/preprocess.h"
#include "render/resolve_state.h"

#include <gtest/gtest.h>

namespace raypc::render {
namespace {

using state::PairSteps;

class PairState : public ::testing::Test {
protected:
    // The fixture's three steps every `dtMyr`, or its first `steps` of them.
    static std::shared_ptr<const dataset::Dataset> series(const std::string& name, double dtMyr, size_t steps = 3)
    {
        auto files = io::listSnapshotFiles({raypc::testing::contestLayoutDir()});
        files.resize(std::min(files.size(), steps));
        preprocess::PreprocessOptions o;
        o.quiet = true;
        o.sampleRows = 200;
        o.pathlines.enabled = false;
        o.dtMyr = dtMyr;
        preprocess::preprocess(files, s_dir->path() / name, o);
        return dataset::Dataset::open(s_dir->path() / name);
    }
    static void SetUpTestSuite()
    {
        s_dir = new raypc::testing::TempDir("pair_state");
        s_two = series("two", 2.0);    // 0, 2, 4 Myr
        s_three = series("three", 3.0, 2);  // 0, 3 Myr
        s_four = series("four", 4.0, 2);    // 0, 4 Myr
    }
    static void TearDownTestSuite()
    {
        s_two.reset();
        s_three.reset();
        s_four.reset();
        delete s_dir;
    }
    static inline raypc::testing::TempDir* s_dir = nullptr;
    static inline std::shared_ptr<const dataset::Dataset> s_two, s_three, s_four;
};

TEST_F(PairState, StepsMatchByIndexOrByTheNearestTime)
{
    // By index: the same, the second's last when it has fewer.
    EXPECT_EQ(pairedStep(*s_two, 1, *s_three, PairSteps::Index), 1);
    EXPECT_EQ(pairedStep(*s_two, 2, *s_three, PairSteps::Index), 1);
    // By time: 2 Myr is 1 from 3 Myr and 2 from 0; 4 Myr is nearest 3 Myr.
    EXPECT_EQ(pairedStep(*s_two, 0, *s_three, PairSteps::Time), 0);
    EXPECT_EQ(pairedStep(*s_two, 1, *s_three, PairSteps::Time), 1);
    EXPECT_EQ(pairedStep(*s_two, 2, *s_three, PairSteps::Time), 1);
    // 2 Myr lies halfway between 0 and 4 Myr: the earlier.
    EXPECT_EQ(pairedStep(*s_two, 1, *s_four, PairSteps::Time), 0);
    EXPECT_EQ(pairedStep(*s_two, 2, *s_four, PairSteps::Time), 1);
    EXPECT_THROW(pairedStep(*s_two, 3, *s_three, PairSteps::Time), Error);
}

TEST_F(PairState, TheSecondTakesTheFirstsColoursAndMatchedStep)
{
    state::RenderState s;
    s.step = 2;
    s.colorVariable = "temperature";
    s.pair = state::PairState{"three", PairSteps::Time};
    s.brushes = {{"temperature", 1000, 2000}, {"depth", 0, 660}};
    const PairedState paired = secondOfPair(s, *s_two, *s_three);
    EXPECT_EQ(paired.state.step, 1);
    EXPECT_TRUE(paired.notes.empty());
    ASSERT_TRUE(paired.state.colorRange.has_value());
    const ResolvedState first = resolveState(s, *s_two);
    EXPECT_EQ(paired.state.colorRange->min, first.params.transfer.range.min);
    EXPECT_EQ(paired.state.colorRange->max, first.params.transfer.range.max);
    EXPECT_EQ(paired.state.brushes.size(), 2u);
    // A brush on a name neither has is the first's error, not a note.
    s.brushes = {{"pressure", 0, 1}};
    EXPECT_THROW(secondOfPair(s, *s_two, *s_three), Error);
}

TEST_F(PairState, HalvesSplitTheWidthAndComposeSideBySide)
{
    state::RenderState s;
    s.width = 7;
    s.height = 3;
    const PairHalves halves = pairHalves(s, *s_two, *s_three);
    EXPECT_EQ(halves.left.width, 3);
    EXPECT_EQ(halves.right.state.width, 4);
    EXPECT_EQ(halves.right.state.height, 3);
    s.width = 1;
    EXPECT_THROW(pairHalves(s, *s_two, *s_three), Error);

    ImageRgba8 left{3, 2, std::vector<uint8_t>(3 * 2 * 4, 10)}, right{4, 2, std::vector<uint8_t>(4 * 2 * 4, 200)};
    const ImageRgba8 both = sideBySide(left, right);
    ASSERT_EQ(both.width, 7);
    ASSERT_EQ(both.height, 2);
    for (int y = 0; y < 2; ++y)
        for (int x = 0; x < 7; ++x)
            EXPECT_EQ(both.pixels[size_t(y * 7 + x) * 4], x < 3 ? 10 : 200) << x << "," << y;
}

}  // namespace
}  // namespace raypc::render
