// The state-to-pixels path's own rules that need no dataset: the pathline tubes' minimum width on
// screen (tubeRadiusKm) against the pixel footprint at the camera target's distance; the memory a
// picture needs, checked before anything is allocated (a huge picture is refused with its figures, not std::bad_alloc);
// the reference geometry it keeps between pictures, never that of another view.
#include "render/state_renderer.h"

#include "core/error.h"
#include "grid/test_util.h"
#include "io/netcdf_reader.h"
#include "preprocess/preprocess.h"
#include "render/resolve_state.h"

#include <gtest/gtest.h>

#include <cmath>

namespace raypc::render {
namespace {

TEST(StateRenderer, TubesKeepAMinimumWidthOnScreen)
{
    state::RenderState s;
    s.camera.distanceKm = 20000;
    s.camera.fovYDeg = 40;
    s.height = 500;
    s.pathlines.radiusKm = 12;
    // One pixel spans 2 * 20000 * tan(20 deg) / 500 = 29.1 km at the target's distance.
    const double kmPerPixel = 2 * 20000 * std::tan(20 * M_PI / 180) / 500;
    s.pathlines.minWidthPx = 0;
    EXPECT_FLOAT_EQ(tubeRadiusKm(s), 12.0f);  // no minimum: the radius alone
    s.pathlines.minWidthPx = 2;
    EXPECT_NEAR(tubeRadiusKm(s), kmPerPixel, 1e-3);  // 2 px wide = a radius of one pixel
    s.camera.distanceKm = 2000;                      // zoomed in: 12 km tubes are wider than 2 px
    EXPECT_FLOAT_EQ(tubeRadiusKm(s), 12.0f);
    s.height = 1000;  // twice the pixels over the same view: half the footprint
    s.camera.distanceKm = 20000;
    EXPECT_NEAR(tubeRadiusKm(s), kmPerPixel / 2, 1e-3);
}

// Interactive frames: the measured throughput and smaller images once there is one; before, an
// assumed rate per thread at full size (the first pass measures the machine).
TEST(StateRenderer, InteractivePolicyUsesTheMeasuredThroughput)
{
    const LevelPolicy none = interactiveLevelPolicy(0);
    EXPECT_GT(none.samplesPerSecond, 0);
    EXPECT_FALSE(none.reduceResolution);
    EXPECT_FALSE(none.chosen);
    const LevelPolicy measured = interactiveLevelPolicy(3.5e7);
    EXPECT_EQ(measured.samplesPerSecond, 3.5e7);
    EXPECT_TRUE(measured.reduceResolution);
    EXPECT_EQ(measured.overheadSeconds, 0);
    EXPECT_EQ(interactiveLevelPolicy(3.5e7, 0.012).overheadSeconds, 0.012);
}

// The reference geometry is kept between pictures of one view (ReferenceLayer); a picture after
// another camera, other shells or another size is the picture a new renderer makes of it.
TEST(StateRenderer, KeptReferenceGeometryIsNeverAnotherViews)
{
    raypc::testing::TempDir dir("state_renderer");
    auto files = io::listSnapshotFiles({raypc::testing::contestLayoutDir()});
    files.resize(1);
    preprocess::PreprocessOptions o;
    o.quiet = true;
    o.sampleRows = 200;
    o.pathlines.enabled = false;
    preprocess::preprocess(files, dir.path() / "ds", o);
    const auto dataset = dataset::Dataset::open(dir.path() / "ds");
    state::RenderState a;
    a.width = 96;
    a.height = 64;
    a.passes = 1;
    a.reference.shells.visible = true;
    a.reference.shells.depthsKm = {660};
    a.reference.graticule.visible = true;
    state::RenderState turned = a, deeper = a, larger = a;
    turned.camera.azimuthDeg += 37;  // not a multiple of the graticule's spacing: its lines move
    deeper.reference.shells.depthsKm = {1600};
    larger.width = 128;
    auto pictureOf = [&](StateRenderer& renderer, const state::RenderState& state) {
        const ResolvedState resolved = resolveState(state, *dataset);
        const StateRenderer::Still still = renderer.renderStill(resolved);
        return renderer.picture(still.frames, resolved, false).pixels;
    };
    StateRenderer kept(dataset);
    const auto first = pictureOf(kept, a);
    for (const state::RenderState* s : {&turned, &deeper, &larger, &a}) {
        StateRenderer fresh(dataset);
        EXPECT_EQ(pictureOf(kept, *s), pictureOf(fresh, *s));
    }
    EXPECT_NE(pictureOf(kept, turned), first);
    EXPECT_NE(pictureOf(kept, deeper), first);
}

TEST(PictureMemory, GrowsWithPixelsEyesAndDepth)
{
    state::RenderState s;
    s.width = 1000;
    s.height = 500;
    const uint64_t mono = pictureMemoryBytes(s, false);
    // At least the frame buffer's sums (RGBA and depth, 20 bytes a pixel) and the 8-bit picture.
    EXPECT_GE(mono, 500'000ull * (20 + 4));
    EXPECT_LT(mono, 500'000ull * 200);
    s.width = 2000;  // twice the pixels
    EXPECT_EQ(pictureMemoryBytes(s, false), 2 * mono);
    s.width = 1000;
    EXPECT_GT(pictureMemoryBytes(s, true), mono);  // the depth map
    s.stereo.mode = StereoMode::SideBySide;         // two eyes of 1000x500
    EXPECT_EQ(pictureMemoryBytes(s, false), 2 * mono);
    s.stereo.mode = StereoMode::SideBySideHalf;  // two eyes of 500x500: the pixels of one
    EXPECT_EQ(pictureMemoryBytes(s, false), mono);
}

TEST(PictureMemory, APictureLargerThanMemoryIsRefusedWithItsFigures)
{
    state::RenderState s;
    s.width = s.height = 16384;
    const uint64_t needed = pictureMemoryBytes(s, false);
    EXPECT_GT(needed, 16'000'000'000ull);  // 268 M pixels
    try {
        checkPictureFitsMemory(s, false, {4'000'000'000, "ulimit -v"});
        FAIL() << "a 16384x16384 picture with 4 GB available was accepted";
    } catch (const Error& e) {
        EXPECT_EQ(std::string(e.what()), "a picture of 16384x16384 pixels needs " + formatBytes(needed) +
                                             " of memory to render, 4.0 GB available (ulimit -v); choose a smaller "
                                             "--size");
    }
    EXPECT_NO_THROW(checkPictureFitsMemory(s, false, {needed, "MemAvailable"}));
    s.width = s.height = 512;
    EXPECT_NO_THROW(checkPictureFitsMemory(s, true, {100'000'000, "cgroup memory.max"}));
}

}  // namespace
}  // namespace raypc::render
