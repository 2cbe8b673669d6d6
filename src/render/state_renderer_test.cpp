// The state-to-pixels path's own rules that need no dataset: the pathline tubes' minimum width on
// screen (tubeRadiusKm) against the pixel footprint at the camera target's distance.
#include "render/state_renderer.h"

#include <gtest/gtest.h>

#include <cmath>

namespace raypc::render {
namespace {

TEST(StateRenderer, TubesKeepAMinimumWidthOnScreen)
{
    RenderState s;
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

}  // namespace
}  // namespace raypc::render
