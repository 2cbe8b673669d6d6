// A u16 dataset renders as its float32 twin (docs/format.md, "Encoding of the level arrays"): the
// contest-layout files preprocessed both ways, rendered alike, compared with the golden tests'
// tolerance (tests/golden: at most 0.5 % of pixels off by more than 10/255 in a channel, mean
// difference at most 1/255). Also checks that skipping by the stored bounds stays exact on u16 data.
#include "render/volume_renderer.h"

#include "render/frame_buffer.h"
#include "render/image_io.h"

#include "dataset/dataset.h"
#include "io/netcdf_reader.h"
#include "preprocess/preprocess.h"
#include "grid/test_util.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fmt/format.h>

namespace raypc::render {
namespace {

std::vector<float> render(const std::shared_ptr<const dataset::StepVolume>& volume, const RenderParams& p, int passes)
{
    VolumeRenderer r(volume);
    r.setParams(p);
    FrameBuffer f(p.width, p.height);
    for (int i = 0; i < passes; ++i)
        r.renderPass(f);
    return f.averagedRgba();
}

struct Difference {
    double badFraction = 0, mean255 = 0;
};

Difference compare(const std::vector<float>& a, const std::vector<float>& b)
{
    size_t bad = 0, pixels = a.size() / 4;
    double sum = 0;
    for (size_t i = 0; i < a.size(); i += 4) {
        double worst = 0;
        for (int c = 0; c < 3; ++c) {
            const double d = std::abs(std::round(255 * std::clamp(a[i + c], 0.0f, 1.0f)) -
                                      std::round(255 * std::clamp(b[i + c], 0.0f, 1.0f)));
            worst = std::max(worst, d);
            sum += d;
        }
        bad += worst > 10;
    }
    return {double(bad) / double(pixels), sum / double(3 * pixels)};
}

TEST(EncodingRender, U16AndFloat32DatasetsRenderWithinTheGoldenTolerance)
{
    raypc::testing::TempDir dir("encoding_render");
    const auto files = io::listSnapshotFiles({raypc::testing::contestLayoutDir()});
    preprocess::PreprocessOptions o;
    o.quiet = true;
    o.sampleRows = 1000;
    o.pathlines.enabled = false;
    o.encoding = dataset::ValueEncoding::Uint16;
    preprocess::preprocess(files, dir / "u16", o);
    o.encoding = dataset::ValueEncoding::Float32;
    preprocess::preprocess(files, dir / "f32", o);
    const auto u16 = dataset::Dataset::open(dir / "u16");
    const auto f32 = dataset::Dataset::open(dir / "f32");
    const int anomaly = u16->variableIndex("temperature anomaly");
    const int temperature = u16->variableIndex("temperature");
    const int conductivity = u16->variableIndex("thermal conductivity");  // −1e-3 × the anomaly (truth.json)

    RenderParams p;
    p.width = p.height = 128;
    p.camera.distanceKm = 19000;
    p.camera.fovYDeg = 42;
    p.colorVariable = anomaly;
    p.transfer.colorMap = ColorMapId::BlueWhiteRed;
    p.transfer.range = u16->variables()[size_t(anomaly)].global.range;
    p.transfer.opacity = {{0, 0.6f}, {0.35f, 0.0f}, {0.65f, 0.0f}, {1, 0.6f}};
    struct Case {
        const char* name;
        RenderParams params;
    };
    std::vector<Case> cases;
    cases.push_back({"anomaly", p});
    RenderParams shaded = p;
    shaded.shading.enabled = true;
    cases.push_back({"anomaly shaded", shaded});
    RenderParams brushed = p;
    brushed.colorVariable = temperature;
    brushed.transfer.colorMap = ColorMapId::Inferno;
    brushed.transfer.range = u16->variables()[size_t(temperature)].global.range;
    brushed.transfer.opacity = {{0, 0.1f}, {1, 0.4f}};
    // The warm half: conductivity below 0.
    const dataset::ValueRange kv = u16->variables()[size_t(conductivity)].global.range;
    brushed.brushes.push_back({conductivity, std::nullopt, {{kv.min, 0.0f}}});
    cases.push_back({"temperature brushed by conductivity", brushed});
    for (int level = 0; level < 2; ++level)
        for (const Case& c : cases) {
            const auto a = render(u16->load(1, level), c.params, 4);
            const auto b = render(f32->load(1, level), c.params, 4);
            const Difference d = compare(a, b);
            double largest = 0;
            size_t covered = 0;
            for (size_t i = 0; i < a.size(); ++i)
                largest = std::max(largest, double(std::abs(a[i] - b[i])));
            for (size_t i = 3; i < a.size(); i += 4)
                covered += b[i] > 0.05f;
            std::printf("%s, level %d: %.3f%% pixels off by > 10/255, mean difference %.4f/255, largest channel "
                        "difference %.3g/255, %zu of %zu pixels covered\n",
                        c.name, level, 100 * d.badFraction, d.mean255, 255 * largest, covered, a.size() / 4);
            // The pictures, to look at (build/src/render/encoding_render/).
            const auto out = std::filesystem::current_path() / "encoding_render";
            std::filesystem::create_directories(out);
            for (const auto& [image, suffix] : {std::pair{&a, "u16"}, std::pair{&b, "f32"}})
                writePng(out / fmt::format("{}_L{}_{}.png", c.name, level, suffix),
                         {p.width, p.height, toRgba8(*image, {0, 0, 0})});
            // Not vacuous: the volume covers much of the picture.
            EXPECT_GT(covered, a.size() / 4 / 5) << c.name;
            EXPECT_LE(d.badFraction, 0.005) << c.name << " level " << level;
            EXPECT_LE(d.mean255, 1.0) << c.name << " level " << level;
            // Skipping by the stored (exact) bounds never changes a u16 image: decoded values stay
            // inside every brick's bounds.
            RenderParams noSkip = c.params;
            noSkip.skipBricks = false;
            const auto s = render(u16->load(1, level), noSkip, 4);
            double worst = 0;
            for (size_t i = 0; i < a.size(); ++i)
                worst = std::max(worst, double(std::abs(a[i] - s[i])));
            EXPECT_LE(worst, 1e-6) << c.name << " level " << level;
        }
}

}  // namespace
}  // namespace raypc::render
