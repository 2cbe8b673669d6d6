// Tubes along pathlines: visibility rules, state keys, and the composite with the volume
// checked analytically (a constant medium of known transmittance, ray-cylinder distance).
#include "render/pathline_scene.h"

#include "core/error.h"
#include "render/render_kernel.h"
#include "render/test_pathlines.h"
#include "render/test_volumes.h"
#include "render/volume_renderer.h"

#include <gtest/gtest.h>

#include <cmath>

using namespace raypc;
using namespace raypc::render;
using namespace raypc::render::testing;
using nlohmann::json;

namespace {

// Three sets (steps 3, 4, 5; 2 Myr apart): per set one line starting at lat 0 and one at lat 40,
// with "start plume" = the start radius / 1000.
std::vector<analysis::PathlineSet> windowSets()
{
    std::vector<analysis::PathlineSet> sets;
    for (int step = 3; step <= 5; ++step) {
        const double t0 = 2.0 * step;
        std::vector<TestLine> lines = {
            straightLine(sphericalToCartesianKm(0, 10.0 * step, 4000), sphericalToCartesianKm(0, 10.0 * step, 4500), 6, t0,
                         t0 + 6),
            straightLine(sphericalToCartesianKm(40, 10.0 * step, 5000), sphericalToCartesianKm(40, 10.0 * step, 5800), 12,
                         t0, t0 + 6)};
        sets.push_back(makePathlineSet(step, t0, step + 3, lines, {"plume"}, [](const std::string&, const Vec3d& p) {
            return std::sqrt(p.x * p.x + p.y * p.y + p.z * p.z) / 1000.0;
        }));
    }
    return sets;
}

state::RenderState visibleState(int step)
{
    state::RenderState s;
    s.step = step;
    s.pathlines.visible = true;
    return s;
}

std::vector<uint8_t> mask(std::initializer_list<int> v) { return std::vector<uint8_t>(v.begin(), v.end()); }

}  // namespace

TEST(PathlineScene, WindowRule)
{
    const PathlineScene scene(windowSets());
    ASSERT_EQ(scene.lineCount(), 6u);
    EXPECT_NEAR(scene.stepMyr(), 2.0, 1e-9);
    state::RenderState s = visibleState(5);
    EXPECT_EQ(scene.visibilityFor(s), mask({1, 1, 1, 1, 1, 1}));
    s.pathlines.window = 2;  // steps 4, 5
    EXPECT_EQ(scene.visibilityFor(s), mask({0, 0, 1, 1, 1, 1}));
    s.step = 4;  // steps 3, 4: lines of step 5 are not injected yet
    EXPECT_EQ(scene.visibilityFor(s), mask({1, 1, 1, 1, 0, 0}));
    s.pathlines.visible = false;
    EXPECT_EQ(scene.visibilityFor(s), mask({0, 0, 0, 0, 0, 0}));
}

TEST(PathlineScene, StartMustSatisfyBrushes)
{
    const PathlineScene scene(windowSets());
    state::RenderState s = visibleState(5);
    s.brushes = {{"lat", 20, 90}};
    EXPECT_EQ(scene.visibilityFor(s), mask({0, 1, 0, 1, 0, 1}));
    s.brushes = {{"depth", 0, 1000}};  // start radius 5000 -> depth 1371: none; 4000 -> 2371: none
    EXPECT_EQ(scene.visibilityFor(s), mask({0, 0, 0, 0, 0, 0}));
    s.brushes = {{"radius", 3900, 4100}, {"lon", 35, 45}};  // the lat-0 line of step 4 (lon 40)
    EXPECT_EQ(scene.visibilityFor(s), mask({0, 0, 1, 0, 0, 0}));
    s.brushes = {{"z", 1000, 1e9f}};  // z = 5000 sin 40° = 3214 for the lat-40 lines
    EXPECT_EQ(scene.visibilityFor(s), mask({0, 1, 0, 1, 0, 1}));
    s.brushes = {{"plume", 4.5f, 6.0f}};  // variable brush -> "start plume": 4 or 5
    EXPECT_EQ(scene.visibilityFor(s), mask({0, 1, 0, 1, 0, 1}));
    // Two ranges on one axis select either (lines at lon 30 and 50, not 40); AND with another axis.
    s.brushes = {{"lon", 25, 35}, {"lon", 45, 55}};
    EXPECT_EQ(scene.visibilityFor(s), mask({1, 1, 0, 0, 1, 1}));
    s.brushes = {{"radius", 3900, 4100}, {"lon", 35, 45}, {"radius", 4900, 5100}};
    EXPECT_EQ(scene.visibilityFor(s), mask({0, 0, 1, 1, 0, 0}));
    s.brushes = {{"plume", 3.9f, 4.1f}, {"lon", 25, 35}, {"plume", 4.9f, 5.1f}, {"lon", 45, 55}};
    EXPECT_EQ(scene.visibilityFor(s), mask({1, 1, 0, 0, 1, 1}));
    s.brushes = {{"plume", 4.5f, 6.0f}};
    s.pathlines.filterByBrushes = false;
    EXPECT_EQ(scene.visibilityFor(s), mask({1, 1, 1, 1, 1, 1}));
    s.pathlines.filterByBrushes = true;
    s.brushes = {{"pressure", 0, 1}};
    try {
        (void)scene.visibilityFor(s);
        FAIL() << "no error for a brush without a start column";
    } catch (const Error& e) {
        EXPECT_NE(std::string(e.what()).find("start pressure"), std::string::npos) << e.what();
    }
}

TEST(PathlineScene, AttributeFilters)
{
    const PathlineScene scene(windowSets());
    state::RenderState s = visibleState(5);
    s.pathlines.filters = {{"length", 600, 1000}};  // lengths 500 and 800
    EXPECT_EQ(scene.visibilityFor(s), mask({0, 1, 0, 1, 0, 1}));
    s.pathlines.filters = {{"length", 0, 1000}, {"injection time", 7, 9}};  // step 4 (8 Myr)
    EXPECT_EQ(scene.visibilityFor(s), mask({0, 0, 1, 1, 0, 0}));
    s.pathlines.filters = {{"injection time", 5, 7}, {"length", 0, 1000}, {"injection time", 9, 11}};  // steps 3, 5
    EXPECT_EQ(scene.visibilityFor(s), mask({1, 1, 0, 0, 1, 1}));
    s.pathlines.filters = {{"injection time", 5, 7}, {"injection time", 11, 9}};
    try {
        (void)scene.visibilityFor(s);
        FAIL() << "no error for min > max";
    } catch (const Error& e) {
        EXPECT_NE(std::string(e.what()).find("filters[1] (injection time): min 11 is greater than max 9"),
                  std::string::npos)
            << e.what();
    }
    s.pathlines.filters = {{"curvature", 0, 1}};
    try {
        (void)scene.visibilityFor(s);
        FAIL() << "no error for an unknown column";
    } catch (const Error& e) {
        EXPECT_NE(std::string(e.what()).find("filters[0]"), std::string::npos) << e.what();
        EXPECT_NE(std::string(e.what()).find("length"), std::string::npos) << "lists the columns: " << e.what();
    }
}

TEST(PathlineScene, ApplyStateSetsStyleRadiusAndMask)
{
    PathlineScene scene(windowSets());
    state::RenderState s = visibleState(5);
    s.pathlines.radiusKm = 30;
    s.pathlines.filters = {{"length", 600, 1000}};
    EXPECT_EQ(scene.applyState(s), 3u);
    EXPECT_EQ(scene.radiusKm(), 30.0f);
    EXPECT_EQ(scene.style().colorColumn, -1);
    EXPECT_EQ(scene.style().colorMap, ColorMapId::BlueWhiteRed);
    EXPECT_FLOAT_EQ(scene.style().range.max, 20.0f);  // window 10 x 2 Myr
    s.pathlines.colorBy = "start plume";
    EXPECT_EQ(scene.applyState(s), 3u);
    EXPECT_EQ(scene.style().colorMap, ColorMapId::Viridis);
    EXPECT_FLOAT_EQ(scene.style().range.min, 4.0f);
    EXPECT_FLOAT_EQ(scene.style().range.max, 5.0f);
    s.pathlines.colorBy = "colour";
    EXPECT_THROW(scene.applyState(s), Error);
    EXPECT_EQ(scene.style().colorColumn, scene.sets()[0].column("start plume")) << "a bad state changes nothing";
    EXPECT_THROW(scene.setVisibility(std::vector<uint8_t>(5, 1)), Error);
    EXPECT_THROW(PathlineScene(windowSets(), 0.0f), Error);
}

TEST(RenderStatePathlines, ParsesAndRoundTrips)
{
    const json j = json::parse(R"({"version": 2, "step": 3, "pathlines": {
        "visible": true, "radiusKm": 20, "window": 5, "colorBy": "length", "colorMap": "inferno",
        "range": [0, 3000], "filterByBrushes": false, "filters": [{"name": "length", "min": 100, "max": 5000}],
        "ambientOcclusion": false}})");
    const state::RenderState s = state::parseRenderState(j);
    EXPECT_TRUE(s.pathlines.visible);
    EXPECT_EQ(s.pathlines.radiusKm, 20.0f);
    EXPECT_EQ(s.pathlines.window, 5);
    EXPECT_EQ(s.pathlines.colorBy, "length");
    EXPECT_EQ(s.pathlines.effectiveColorMap(), ColorMapId::Inferno);
    ASSERT_TRUE(s.pathlines.range);
    EXPECT_EQ(s.pathlines.range->max, 3000.0f);
    EXPECT_FALSE(s.pathlines.filterByBrushes);
    ASSERT_EQ(s.pathlines.filters.size(), 1u);
    EXPECT_EQ(s.pathlines.filters[0].name, "length");
    EXPECT_FALSE(s.pathlines.ambientOcclusion);
    const state::RenderState back = state::parseRenderState(toJson(s));
    EXPECT_EQ(toJson(back), toJson(s));

    // Defaults, and version 1 documents (no pathlines) still load.
    const state::RenderState d = state::parseRenderState(json{{"version", 1}});
    EXPECT_FALSE(d.pathlines.visible);
    EXPECT_EQ(d.pathlines.radiusKm, 12.0f);
    EXPECT_EQ(d.pathlines.window, 10);
    EXPECT_EQ(d.pathlines.colorBy, "age");
    EXPECT_EQ(d.pathlines.effectiveColorMap(), ColorMapId::BlueWhiteRed);
    EXPECT_TRUE(d.pathlines.filterByBrushes);
    EXPECT_TRUE(d.pathlines.ambientOcclusion);
    EXPECT_EQ(toJson(d)["version"], state::kRenderStateVersion);  // written in the current version
}

TEST(RenderStatePathlines, RejectsBadValuesNamingTheKey)
{
    auto errorOf = [](const std::string& text) {
        try {
            state::parseRenderState(json::parse(text), "STATE.json");
        } catch (const Error& e) {
            return std::string(e.what());
        }
        return std::string("no error");
    };
    auto has = [](const std::string& message, const std::string& part) {
        return message.find(part) != std::string::npos;
    };
    std::string e = errorOf(R"({"version": 1, "pathlines": {"visible": true}})");
    EXPECT_TRUE(has(e, "pathlines") && has(e, "version 2")) << e;
    e = errorOf(R"({"version": 99})");
    EXPECT_TRUE(has(e, "version") && has(e, "not supported")) << e;
    e = errorOf(R"({"version": 2, "pathlines": {"radiusKm": 0}})");
    EXPECT_TRUE(has(e, "STATE.json: pathlines.radiusKm")) << e;
    e = errorOf(R"({"version": 2, "pathlines": {"radiusKm": -4}})");
    EXPECT_TRUE(has(e, "pathlines.radiusKm")) << e;
    e = errorOf(R"({"version": 2, "pathlines": {"window": 0}})");
    EXPECT_TRUE(has(e, "pathlines.window")) << e;
    e = errorOf(R"({"version": 2, "pathlines": {"visible": "yes"}})");
    EXPECT_TRUE(has(e, "pathlines.visible")) << e;
    e = errorOf(R"({"version": 2, "pathlines": {"thickness": 3}})");
    EXPECT_TRUE(has(e, "pathlines.thickness: unknown key")) << e;
    e = errorOf(R"({"version": 2, "pathlines": {"colorMap": "rainbow"}})");
    EXPECT_TRUE(has(e, "pathlines.colorMap")) << e;
    e = errorOf(R"({"version": 2, "pathlines": {"colorBy": ""}})");
    EXPECT_TRUE(has(e, "pathlines.colorBy")) << e;
    e = errorOf(R"({"version": 2, "pathlines": {"range": [5, 1]}})");
    EXPECT_TRUE(has(e, "pathlines.range")) << e;
    e = errorOf(R"({"version": 2, "pathlines": {"filters": [{"name": "length", "min": 5, "max": 1}]}})");
    EXPECT_TRUE(has(e, "pathlines.filters[0].min")) << e;
    e = errorOf(R"({"version": 2, "pathlines": {"filters": [{"name": "length", "min": 5}]}})");
    EXPECT_TRUE(has(e, "pathlines.filters[0].max: missing")) << e;
    e = errorOf(R"({"version": 2, "pathlines": {"filters": [{"min": 1, "max": 5}]}})");
    EXPECT_TRUE(has(e, "pathlines.filters[0].name")) << e;
    e = errorOf(R"({"version": 2, "pathlines": {"filters": {"name": "length"}}})");
    EXPECT_TRUE(has(e, "pathlines.filters")) << e;
    e = errorOf(R"({"version": 2, "pathlines": [1]})");
    EXPECT_TRUE(has(e, "pathlines")) << e;
}

// --- The composite with the volume, analytically ------------------------------------------------

namespace {

constexpr int kSize = 65;
constexpr float kTubeRadiusKm = 150;  // about 2 pixels wide at the tube
const Vec3d kTubeX{5000, 0, -1500}, kTubeTop{5000, 0, 1500};  // a vertical tube at x = 5000 km

std::shared_ptr<dataset::StepVolume> constantVolume()
{
    return makeVolume(makeGrid(16, 9, 32), {{"c", [](double, double, double) { return 1.0f; }},
                                            {"radial", [](double, double r, double) { return float(r); }}});
}

// Looking down -x at the tube; the centre pixel's ray passes through the tube's axis (y = 0).
RenderParams analyticParams(float opacity)
{
    RenderParams p;
    p.width = p.height = kSize;
    p.camera.azimuthDeg = 0;
    p.camera.elevationDeg = 0;
    p.camera.distanceKm = 20000;
    p.camera.fovYDeg = 40;
    p.colorVariable = 0;
    p.transfer.colorMap = ColorMapId::Grayscale;
    p.transfer.range = {0, 2};
    p.transfer.opacity = {{0, opacity}, {1, opacity}};
    p.transfer.opacityUnitKm = 100;
    p.core.visible = false;
    p.depthOpacity = 0.9f;
    return p;
}

std::shared_ptr<PathlineScene> tubeScene(std::vector<TestLine> lines)
{
    auto scene = std::make_shared<PathlineScene>(std::vector<analysis::PathlineSet>{makePathlineSet(0, 0, 1, lines)},
                                                 kTubeRadiusKm);
    PathlineStyle style = scene->style();
    style.ambientOcclusion = false;
    scene->setStyle(style);
    return scene;
}

struct Frame {
    std::vector<float> rgba, depth;
};

Frame renderFrame(const RenderParams& p, std::shared_ptr<const PathlineScene> scene, int passes = 1,
             KernelKind kind = KernelKind::Simd)
{
    VolumeRenderer r(constantVolume());
    RenderParams q = p;
    q.kernel = kind;
    r.setParams(q);
    r.setPathlines(std::move(scene));
    FrameBuffer f(p.width, p.height);
    for (int i = 0; i < passes; ++i)
        r.renderPass(f);
    return {f.averagedRgba(), f.averagedDepthKm()};
}

// Closest t >= 0 of o + t d on the infinite cylinder of radius R around the line through c along a (unit).
float rayCylinder(Vec3 o, Vec3 d, Vec3 c, Vec3 a, float R)
{
    const Vec3 oc = o - c;
    const Vec3 dp = d - a * dot(d, a), op = oc - a * dot(oc, a);
    const float A = dot(dp, dp), B = 2 * dot(dp, op), C = dot(op, op) - R * R;
    const float disc = B * B - 4 * A * C;
    return disc < 0 ? INFINITY : (-B - std::sqrt(disc)) / (2 * A);
}

}  // namespace

TEST(TubeRendering, DepthIsTheRayCylinderDistance)
{
    const auto scene = tubeScene({straightLine(kTubeX, kTubeTop, 2, 0, 10)});
    const RenderParams p = analyticParams(0.0f);  // transparent volume
    const Frame f = renderFrame(p, scene);
    const CameraFrame cam(p.camera, p.width, p.height);
    int tubePixels = 0;
    for (int y = 0; y < kSize; ++y) {
        for (int x = 0; x < kSize; ++x) {
            const Vec3 d = cam.direction(float(x) + 0.5f, float(y) + 0.5f);
            const float t = rayCylinder(cam.eye, d, {5000, 0, 0}, {0, 0, 1}, kTubeRadiusKm);
            const float z = cam.eye.z + t * d.z;
            const size_t i = size_t(y) * kSize + size_t(x);
            if (std::isfinite(t) && std::abs(z) < 1400) {
                ++tubePixels;
                EXPECT_NEAR(f.depth[i], t, 0.5f) << "pixel " << x << ", " << y;
                EXPECT_EQ(f.rgba[4 * i + 3], 1.0f);
            } else if (!std::isfinite(t)) {
                EXPECT_FALSE(std::isfinite(f.depth[i])) << "pixel " << x << ", " << y;
            }
        }
    }
    EXPECT_GT(tubePixels, 12);
}

TEST(TubeRendering, TubeBehindConstantMediumIsAttenuated)
{
    const auto scene = tubeScene({straightLine(kTubeX, kTubeTop, 2, 0, 10)});
    const RenderParams alone = analyticParams(0.0f);
    const RenderParams medium = analyticParams(0.05f);  // 5% per 100 km
    const CameraFrame cam(medium.camera, kSize, kSize);
    const TransferTable table = TransferTable::bake(medium.transfer);
    const int idx = table.indexOf(1.0f);
    const float sigma = table.sigmaPerKm[size_t(idx)];
    for (KernelKind kind : {KernelKind::Simd, KernelKind::Scalar}) {
        const Frame tube = renderFrame(alone, scene, 1, kind);
        const Frame both = renderFrame(medium, scene, 1, kind);
        const Frame none = renderFrame(medium, nullptr, 1, kind);
        const int x = kSize / 2, y = kSize / 2;
        const size_t i = size_t(y) * kSize + size_t(x);
        const Vec3 d = cam.direction(float(x) + 0.5f, float(y) + 0.5f);
        float tIn, tOut;
        ASSERT_TRUE(intersectSphere(cam.eye, d, 6371.0f, tIn, tOut));
        const float tHit = rayCylinder(cam.eye, d, {5000, 0, 0}, {0, 0, 1}, kTubeRadiusKm);
        const float T = std::exp(-sigma * (tHit - tIn));
        ASSERT_GT(T, 0.3f);
        ASSERT_LT(T, 0.7f);
        const float volumeColor[3] = {table.red[size_t(idx)], table.green[size_t(idx)], table.blue[size_t(idx)]};
        for (int c = 0; c < 3; ++c)
            EXPECT_NEAR(both.rgba[4 * i + size_t(c)], volumeColor[c] * (1 - T) + T * tube.rgba[4 * i + size_t(c)], 2e-3f)
                << "channel " << c;
        EXPECT_NEAR(both.rgba[4 * i + 3], 1.0f, 1e-6f);
        EXPECT_NEAR(both.depth[i], tHit, 0.5f) << "the medium alone does not reach the depth opacity";
        // Without the tube the ray goes on through the whole shell (more opacity there).
        EXPECT_LT(none.rgba[4 * i + 3], 1.0f);
        EXPECT_NE(none.rgba[4 * i], both.rgba[4 * i]);
    }
}

TEST(TubeRendering, TubeInFrontHidesAnOpaqueVolume)
{
    const auto scene = tubeScene({straightLine(kTubeX, kTubeTop, 2, 0, 10)});
    RenderParams opaque = analyticParams(1.0f);
    opaque.brushes = {{1, std::nullopt, {{0.0f, 4500.0f}}}};  // opaque below r = 4500 km, behind the tube
    const Frame tube = renderFrame(analyticParams(0.0f), scene);
    const Frame both = renderFrame(opaque, scene);
    const Frame volume = renderFrame(opaque, nullptr);
    const size_t i = size_t(kSize / 2) * kSize + size_t(kSize / 2);
    EXPECT_GT(volume.rgba[4 * i + 3], 0.99f) << "the volume alone is opaque at the centre";
    for (int c = 0; c < 4; ++c)
        EXPECT_FLOAT_EQ(both.rgba[4 * i + size_t(c)], tube.rgba[4 * i + size_t(c)]);
    EXPECT_FLOAT_EQ(both.depth[i], tube.depth[i]);
    EXPECT_LT(both.depth[i], volume.depth[i]);
}

TEST(TubeRendering, MaskHidesLinesWithoutRebuilding)
{
    // Line A at y = -1500, line B at y = +1500; AO on, several passes (jitter and AO rays).
    const TestLine a = straightLine({5000, -1500, -1500}, {5000, -1500, 1500}, 20, 0, 10);
    const TestLine b = straightLine({5000, 1500, -1500}, {5000, 1500, 1500}, 20, 0, 10);
    auto both = std::make_shared<PathlineScene>(std::vector<analysis::PathlineSet>{makePathlineSet(0, 0, 1, {a, b})}, 200.0f);
    auto onlyA = std::make_shared<PathlineScene>(std::vector<analysis::PathlineSet>{makePathlineSet(0, 0, 1, {a})}, 200.0f);
    RenderParams p = analyticParams(0.02f);
    p.core.visible = true;
    const Frame all = renderFrame(p, both, 3);
    EXPECT_EQ(both->setVisibility({1, 0}), 1u);
    const Frame hidden = renderFrame(p, both, 3);
    const Frame reference = renderFrame(p, onlyA, 3);
    EXPECT_NE(all.rgba, hidden.rgba);
    EXPECT_EQ(hidden.rgba, reference.rgba) << "a hidden line is invisible to primary and occlusion rays";
    EXPECT_EQ(hidden.depth, reference.depth);
    EXPECT_EQ(both->setVisibility({0, 0}), 0u);
    const Frame none = renderFrame(p, both, 3);
    const Frame noScene = renderFrame(p, nullptr, 3);
    EXPECT_EQ(none.rgba, noScene.rgba);
    EXPECT_EQ(none.depth, noScene.depth);
}

TEST(TubeRendering, AgeColorsBlueAtTheSeedRedAtTheWindowEnd)
{
    // A line along z whose time runs 0..20 Myr from bottom to top: bottom blue, top red.
    auto scene = tubeScene({straightLine(kTubeX, kTubeTop, 30, 0, 20)});
    PathlineStyle style = scene->style();
    style.range = {0, 20};
    scene->setStyle(style);
    const Frame f = renderFrame(analyticParams(0.0f), scene);
    const CameraFrame cam(analyticParams(0).camera, kSize, kSize);
    auto pixelAtZ = [&](float zKm) {
        // The row whose centre ray meets the plane x = 5040 at height z.
        for (int y = 0; y < kSize; ++y) {
            const Vec3 d = cam.direction(kSize / 2 + 0.5f, float(y) + 0.5f);
            const float t = (cam.eye.x - 5000 - kTubeRadiusKm) / -d.x;
            if (cam.eye.z + t * d.z < zKm)
                return size_t(y) * kSize + kSize / 2;
        }
        return size_t(0);
    };
    const size_t low = pixelAtZ(-1300), high = pixelAtZ(1300);
    EXPECT_GT(f.rgba[4 * low + 2], f.rgba[4 * low]) << "blue near the seed";
    EXPECT_GT(f.rgba[4 * high], f.rgba[4 * high + 2]) << "red 20 Myr later";
}
