// raypc_golden CASE GOLDEN_DIR OUT_DIR: renders one golden case from an analytic volume and compares
// it with GOLDEN_DIR/CASE.png. Pass: at most 0.5% of pixels differ by more than 10/255 in any channel
// and the mean difference is below 1/255 (SIMD widths and libm differ slightly between machines).
// On failure writes OUT_DIR/CASE.png (actual) and OUT_DIR/CASE.diff.png (differences x8).
// With RAYPC_UPDATE_GOLDEN=1 the golden is (re)written instead.
// `raypc_golden view_equals_orbit`: no golden file; the picture of an explicit camera view
// (camera.views) equal to an orbit camera's frame must match the orbit camera's within 1/255.
#include "core/error.h"
#include "render/image_io.h"
#include "render/pathline_scene.h"
#include "render/slice_view.h"
#include "render/test_pathlines.h"
#include "render/test_volumes.h"
#include "render/volume_renderer.h"

#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <functional>
#include <map>
#include <string>

using namespace raypc;
using namespace raypc::render;
using raypc::render::testing::makeGrid;
using raypc::render::testing::makeVolume;

namespace {

constexpr int kSize = 128;

// Three analytic fields: a signed plume field, a radial temperature-like field, a lon/lat pattern.
std::shared_ptr<StepVolume> volumeAt(int level)
{
    SphericalGrid grid = makeGrid(48, 41, 96, 0.3);
    for (int i = 0; i < level; ++i)
        grid = grid.coarsened();
    return makeVolume(grid, {{"plume", testing::plumeField},
                             {"radial", [](double, double r, double) { return float((r - 3485) / 2886); }},
                             {"pattern", [](double lat, double, double lon) {
                                  return float(std::cos(3 * lon * M_PI / 180) * std::cos(lat * M_PI / 180));
                              }}});
}

RenderParams baseParams()
{
    RenderParams p;
    p.width = p.height = kSize;
    p.camera.azimuthDeg = 35;
    p.camera.elevationDeg = 25;
    p.camera.distanceKm = 18500;
    p.camera.fovYDeg = 45;
    p.colorVariable = 0;
    p.transfer.range = {-0.8f, 1.0f};
    p.transfer.opacity = {{0, 0.5f}, {0.4f, 0.0f}, {0.5f, 0.0f}, {1, 0.8f}};
    p.transfer.opacityUnitKm = 150;
    return p;
}

struct Case {
    int level = 0;
    std::function<void(RenderParams&)> setup;
    std::function<std::shared_ptr<PathlineScene>()> tubes = {};  // pathline tubes (issue 5), optional
};

// Maps and sections (render/slice_view.h): a state document each, drawn from the level-0 volume.
struct SliceCase {
    StateRenderer::Slice slice;
    const char* state;
};
const std::map<std::string, SliceCase> kSliceCases = {
    {"map_mollweide", {StateRenderer::Slice::Map, R"({"version": 9, "image": {"width": 256, "height": 150}, "color": {"variable": "plume", "colorMap": "vik", "range": [-1, 1]}, "map": {"projection": "mollweide", "depthKm": 800, "centralMeridianDeg": 60, "contours": [0], "flow": false}})"}},
    {"map_orthographic_brushed", {StateRenderer::Slice::Map, R"({"version": 9, "image": {"width": 200, "height": 200}, "color": {"variable": "pattern", "colorMap": "batlow", "range": [-1, 1]}, "brushes": [{"name": "lat", "min": 30, "max": 90}], "reference": {"graticule": {"visible": true, "spacingDeg": 30}}, "map": {"projection": "orthographic", "depthKm": 100, "centralLatitudeDeg": 60, "centralMeridianDeg": -20}})"}},
    {"section_plume", {StateRenderer::Slice::Section, R"({"version": 9, "image": {"width": 256, "height": 160}, "color": {"variable": "plume", "colorMap": "vik", "range": [-1, 1]}, "reference": {"shells": {"visible": true, "depthsKm": [660, 1600]}}, "map": {"contours": [0.5]}, "section": {"from": {"latDeg": 10, "lonDeg": -30}, "to": {"latDeg": 30, "lonDeg": 70}}})"}},
};

// A slice case's picture: the state document parsed and resolved as raypc map and section do.
ImageRgba8 slicePicture(const SliceCase& c)
{
    const auto volume = volumeAt(0);
    ResolvedState r;
    r.state = parseRenderState(nlohmann::json::parse(c.state), "golden case");
    const VariableCatalog catalog{{"plume", "radial", "pattern"}, {{-1, 1}, {0, 1}, {-1, 1}}};
    r.params = resolveParams(r.state, catalog);
    const SliceInputs in{volume.get(), &r, catalog.names, r.state.colorVariable, "golden", nullptr};
    return c.slice == StateRenderer::Slice::Map ? mapPicture(in) : sectionPicture(in);
}

// Eight helices rising through the mantle on the side facing the camera, injected at steps 0 and 1
// (2 Myr apart) and traced for 16 Myr: coloured by age they run from blue to red.
std::shared_ptr<PathlineScene> helixTubes(float radiusKm, bool ambientOcclusion, std::vector<uint8_t> mask = {})
{
    std::vector<PathlineSet> sets;
    for (int step = 0; step < 2; ++step) {
        std::vector<testing::TestLine> lines;
        for (int i = 0; i < 4; ++i) {
            const double lat = -25.0 + 22.0 * i + 9.0 * step, lon = 5.0 + 18.0 * i + 30.0 * step;
            lines.push_back(testing::helixLine(lat, lon, 3700, 6100, 250, 1.5 + 0.5 * i, 120, 2.0 * step,
                                               2.0 * step + 16.0));
        }
        sets.push_back(testing::makePathlineSet(step, 2.0 * step, step + 8, lines));
    }
    auto scene = std::make_shared<PathlineScene>(std::move(sets), radiusKm);
    RenderState state;
    state.step = 1;
    state.pathlines.visible = true;
    state.pathlines.radiusKm = radiusKm;
    state.pathlines.ambientOcclusion = ambientOcclusion;
    scene->applyState(state);
    if (!mask.empty())
        scene->setVisibility(std::move(mask));
    return scene;
}

std::map<std::string, Case> cases()
{
    std::map<std::string, Case> c;
    c["tf_viridis"] = {0, [](RenderParams& p) { p.transfer.colorMap = ColorMapId::Viridis; }};
    c["tf_inferno"] = {0, [](RenderParams& p) { p.transfer.colorMap = ColorMapId::Inferno; }};
    c["tf_cool_to_warm"] = {0, [](RenderParams& p) { p.transfer.colorMap = ColorMapId::CoolToWarm; }};
    c["tf_blue_white_red"] = {0, [](RenderParams& p) {
                                  p.transfer.colorMap = ColorMapId::BlueWhiteRed;
                                  p.transfer.range = {-1, 1};
                                  p.transfer.opacity = {{0, 0.8f}, {0.45f, 0}, {0.55f, 0}, {1, 0.8f}};
                              }};
    c["tf_opacity_steps"] = {0, [](RenderParams& p) {
                                 p.colorVariable = 1;
                                 p.transfer.range = {0, 1};
                                 p.transfer.opacity = {{0, 0}, {0.3f, 0}, {0.31f, 0.4f}, {0.4f, 0.4f}, {0.41f, 0}, {1, 0}};
                             }};
    // "Show the selection": a selection in the transparent middle of the V (values in [-0.3, 0.3]
    // inside 4000-5000 km) drawn with the floor's opacity in the colour map's pale middle.
    c["selection_shown"] = {0, [](RenderParams& p) {
                                p.transfer.colorMap = ColorMapId::BlueWhiteRed;
                                p.transfer.range = {-1, 1};
                                p.transfer.opacity = {{0, 0.8f}, {0.35f, 0}, {0.65f, 0}, {1, 0.8f}};
                                p.brushes = {{0, std::nullopt, {{-0.3f, 0.3f}}}, {-1, Coordinate::Radius, {{4000, 5000}}}};
                                p.selectionMinOpacity = 0.5f;
                            }};
    c["brush_one_variable"] = {0, [](RenderParams& p) { p.brushes = {{1, std::nullopt, {{0.3f, 0.7f}}}}; }};
    c["brush_several_variables"] = {0, [](RenderParams& p) {
                                        p.brushes = {{1, std::nullopt, {{0.2f, 0.9f}}},
                                                     {2, std::nullopt, {{-0.5f, 1.0f}}},
                                                     {0, std::nullopt, {{-0.9f, 0.9f}}}};
                                    }};
    c["cut_by_coordinate"] = {0, [](RenderParams& p) {
                                  p.colorVariable = 1;
                                  p.transfer.range = {0, 1};
                                  p.transfer.colorMap = ColorMapId::Inferno;
                                  p.transfer.opacity = {{0, 0.9f}, {1, 0.9f}};
                                  p.brushes = {{-1, Coordinate::Y, {{-7000, 0}}}, {-1, Coordinate::Depth, {{0, 2000}}}};
                              }};
    for (int level = 0; level < 3; ++level)
        c["level_" + std::to_string(level)] = {level, [](RenderParams&) {}};
    c["lon_seam"] = {0, [](RenderParams& p) {
                         // Looking at lon 0 from outside: the seam between the last column and column 0.
                         p.camera.azimuthDeg = 0;
                         p.camera.elevationDeg = 0;
                         p.colorVariable = 2;
                         p.transfer.range = {-1, 1};
                         p.transfer.colorMap = ColorMapId::CoolToWarm;
                         p.transfer.opacity = {{0, 0.6f}, {1, 0.6f}};
                         p.brushes = {{-1, Coordinate::Depth, {{0, 300}}}};
                     }};
    auto pole = [](double elevation) {
        return [elevation](RenderParams& p) {
            p.camera.elevationDeg = elevation;
            p.colorVariable = 2;
            p.transfer.range = {-1, 1};
            p.transfer.colorMap = ColorMapId::Viridis;
            p.transfer.opacity = {{0, 0.6f}, {1, 0.6f}};
            p.brushes = {{-1, Coordinate::Depth, {{0, 300}}}};
        };
    };
    c["north_pole"] = {0, pole(90)};
    c["south_pole"] = {0, pole(-90)};
    c["shading"] = {0, [](RenderParams& p) {
                        p.transfer.opacity = {{0, 0}, {0.6f, 0}, {0.65f, 0.9f}, {1, 0.9f}};
                        p.transfer.opacityUnitKm = 30;
                        p.shading.enabled = true;
                    }};
    // The shading case with occlusion (soft shadows and ambient occlusion, shadow_volume.h).
    c["shadows"] = {0, [](RenderParams& p) {
                        p.transfer.opacity = {{0, 0}, {0.6f, 0}, {0.65f, 0.9f}, {1, 0.9f}};
                        p.transfer.opacityUnitKm = 30;
                        p.shading.enabled = true;
                        p.shading.shadows = true;
                    }};
    c["core_plain"] = {0, [](RenderParams& p) {
                           p.brushes = {{-1, Coordinate::X, {{-1e9f, 0}}}};
                           p.core.color = {0.8f, 0.5f, 0.2f};
                       }};
    c["core_by_variable"] = {0, [](RenderParams& p) {
                                 p.brushes = {{-1, Coordinate::X, {{-1e9f, 0}}}};
                                 p.core.variable = 2;
                                 p.core.range = {-1, 1};
                                 p.core.colorMap = ColorMapId::CoolToWarm;
                             }};
    // Pathline tubes ray traced in the volume's frame (issue 5).
    c["tubes_age"] = {0, [](RenderParams& p) { p.transfer.opacity = {{0, 0}, {1, 0}}; },
                      [] { return helixTubes(60, true); }};
    c["tubes_opaque_volume"] = {0, [](RenderParams& p) {
                                    p.colorVariable = 1;
                                    p.transfer.range = {0, 1};
                                    p.transfer.colorMap = ColorMapId::Grayscale;
                                    p.transfer.opacity = {{0, 1}, {1, 1}};
                                    p.brushes = {{-1, Coordinate::Radius, {{0, 4800}}}};  // opaque below 4800 km
                                },
                                [] { return helixTubes(60, true); }};
    c["tubes_translucent_volume"] = {0, [](RenderParams&) {}, [] { return helixTubes(60, false); }};
    // Tubes and a translucent volume shadowing each other.
    c["tubes_shadows"] = {0, [](RenderParams& p) {
                              p.shading.enabled = true;
                              p.shading.shadows = true;
                          },
                          [] { return helixTubes(60, false); }};
    c["tubes_filtered"] = {0, [](RenderParams& p) { p.transfer.opacity = {{0, 0}, {1, 0}}; },
                           [] { return helixTubes(60, true, {1, 0, 1, 0, 0, 1, 0, 1}); }};
    return c;
}

ImageRgba8 renderCase(const Case& c, const RenderParams& params)
{
    VolumeRenderer renderer(volumeAt(c.level));
    renderer.setParams(params);
    if (c.tubes)
        renderer.setPathlines(c.tubes());
    FrameBuffer frame(params.width, params.height);
    for (int pass = 0; pass < 6; ++pass)
        renderer.renderPass(frame);
    return {params.width, params.height, frame.resolveRgba8({0.1f, 0.1f, 0.12f})};
}

// The orbit camera at azimuth 0, elevation 0 looks from +x along -x with +y to the right and +z
// up: as an explicit view, camera +x -> +y, +y -> +z, -z -> -x, the rotation by 120 degrees about
// (1, 1, 1) (quaternion [1/2, 1/2, 1/2, 1/2], exact in floats), and the symmetric frustum of
// fovYDeg. The volume, the shading, the core and the tubes must come out as the orbit's.
int viewEqualsOrbit(const std::filesystem::path& outDir)
{
    Case c{0, [](RenderParams& p) {
               p.camera.azimuthDeg = 0;
               p.camera.elevationDeg = 0;
               p.shading.enabled = true;
           },
           [] { return helixTubes(60, true); }};
    RenderParams orbit = baseParams();
    c.setup(orbit);
    RenderParams view = orbit;
    const double t = std::tan(orbit.camera.fovYDeg * M_PI / 360);
    view.camera.views = {CameraView{{float(orbit.camera.distanceKm), 0, 0}, {0.5f, 0.5f, 0.5f, 0.5f},
                                    {float(-t), float(t), float(-t), float(t)}}};
    // A control: the view shifted by a few pixels must give another picture (the view is used).
    RenderParams shifted = view;
    for (float& t : shifted.camera.views[0].frustum)
        t += float(2 * t / kSize * 4);
    const ImageRgba8 a = renderCase(c, orbit), b = renderCase(c, view), control = renderCase(c, shifted);
    auto compare = [&](const ImageRgba8& x, const ImageRgba8& y, size_t& differing) {
        int worst = 0;
        differing = 0;
        for (size_t i = 0; i < x.pixels.size(); ++i) {
            const int d = std::abs(int(x.pixels[i]) - int(y.pixels[i]));
            worst = std::max(worst, d);
            differing += d > 0;
        }
        return worst;
    };
    size_t differing = 0, controlDiffering = 0;
    const int worst = compare(a, b, differing), controlWorst = compare(a, control, controlDiffering);
    std::printf("view_equals_orbit: largest difference %d/255, %zu channel values differ; the view zoomed out by "
                "4 pixels: %d/255, %zu differ\n",
                worst, differing, controlWorst, controlDiffering);
    if (controlWorst < 32)
        fail("view_equals_orbit: a changed view gives the same picture: the view is not used");
    if (worst > 1) {
        std::filesystem::create_directories(outDir);
        writePng(outDir / "view_equals_orbit.orbit.png", a);
        writePng(outDir / "view_equals_orbit.view.png", b);
        std::fprintf(stderr, "view_equals_orbit: the view's picture differs from the orbit's; see %s\n",
                     outDir.string().c_str());
        return 1;
    }
    return 0;
}

}  // namespace

int main(int argc, char** argv)
{
    try {
        if (argc != 4) {
            std::fprintf(stderr, "usage: raypc_golden CASE GOLDEN_DIR OUT_DIR\n");
            return 2;
        }
        const std::string name = argv[1];
        const std::filesystem::path goldenDir = argv[2], outDir = argv[3];
        if (name == "view_equals_orbit")
            return viewEqualsOrbit(outDir);
        ImageRgba8 actual;
        if (const auto slice = kSliceCases.find(name); slice != kSliceCases.end()) {
            actual = slicePicture(slice->second);
        } else {
            const auto all = cases();
            const auto it = all.find(name);
            if (it == all.end())
                fail("unknown golden case '{}'", name);
            RenderParams params = baseParams();
            it->second.setup(params);
            VolumeRenderer renderer(volumeAt(it->second.level));
            renderer.setParams(params);
            if (it->second.tubes)
                renderer.setPathlines(it->second.tubes());
            FrameBuffer frame(params.width, params.height);
            for (int pass = 0; pass < 6; ++pass)
                renderer.renderPass(frame);
            actual = {kSize, kSize, frame.resolveRgba8({0.1f, 0.1f, 0.12f})};
        }
        const auto golden = goldenDir / (name + ".png");
        const char* update = std::getenv("RAYPC_UPDATE_GOLDEN");
        if (update && std::string(update) == "1") {
            writePng(golden, actual);
            std::printf("%s: golden written to %s\n", name.c_str(), golden.string().c_str());
            return 0;
        }
        std::filesystem::create_directories(outDir);
        if (!std::filesystem::exists(golden)) {
            writePng(outDir / (name + ".png"), actual);
            fail("{}: no golden image; run with RAYPC_UPDATE_GOLDEN=1 to create it", golden.string());
        }
        const ImageRgba8 expected = readPng(golden);
        if (expected.width != actual.width || expected.height != actual.height)
            fail("{}: golden is {}x{}, rendered {}x{}", golden.string(), expected.width, expected.height, actual.width,
                 actual.height);
        ImageRgba8 diff{actual.width, actual.height, std::vector<uint8_t>(actual.pixels.size(), 255)};
        size_t bad = 0;
        double sum = 0;
        for (size_t i = 0; i < actual.pixels.size(); i += 4) {
            int worst = 0;
            for (int c = 0; c < 3; ++c) {
                const int d = std::abs(int(actual.pixels[i + c]) - int(expected.pixels[i + c]));
                worst = std::max(worst, d);
                sum += d;
                diff.pixels[i + c] = uint8_t(std::min(255, d * 8));
            }
            bad += worst > 10;
        }
        const double pixels = double(actual.width) * actual.height;
        const double mean = sum / (3 * pixels);
        const double badFraction = double(bad) / pixels;
        std::printf("%s: %.3f%% pixels off by > 10/255, mean difference %.3f/255\n", name.c_str(), 100 * badFraction,
                    mean);
        if (badFraction > 0.005 || mean > 1.0) {
            writePng(outDir / (name + ".png"), actual);
            writePng(outDir / (name + ".diff.png"), diff);
            std::fprintf(stderr, "%s: differs from the golden; see %s\n", name.c_str(),
                         (outDir / (name + ".diff.png")).string().c_str());
            return 1;
        }
        return 0;
    } catch (const std::exception& e) {
        std::fprintf(stderr, "raypc_golden: error: %s\n", e.what());
        return 1;
    }
}
