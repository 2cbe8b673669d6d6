// raypc_stereo_check DATASET RAYPC WORKDIR: stereo pairs of a preprocessed (synthetic) dataset
// checked against geometry, through the one state-to-pixels path (StateRenderer) and through
// `raypc render --state`:
//  1. the core's limb on the centre row of each eye lies where the tangents from that eye to the
//     core sphere meet the eye's (off-axis) image plane, for several separations and convergence
//     distances: the parallax between the eyes is the predicted one (0 for 0 separation: each eye
//     is then the mono picture, bit for bit);
//  2. an anaglyph's red is the left eye's luma and its green and blue the right eye's (the eyes of
//     a side-by-side pair of the same state); where only the left eye sees the core the anaglyph is
//     pure red;
//  3. `raypc render --state` writes the composed pair: 2W x H, W x H (halves), W x H (anaglyph),
//     equal to the picture rendered here.
// Exit 0 when all hold; otherwise prints each failure.
#include "core/error.h"
#include "dataset/dataset.h"
#include "render/camera.h"
#include "render/image_io.h"
#include "render/state_renderer.h"

#include <fmt/format.h>
#include <nlohmann/json.hpp>

#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <fstream>

using namespace raypc;
using namespace raypc::render;
namespace fs = std::filesystem;

namespace {

int g_failures = 0;

void expect(bool ok, const std::string& what)
{
    if (!ok) {
        ++g_failures;
        fmt::print("FAIL: {}\n", what);
    }
}

// The core alone: a transparent volume, a flat white core (ambient 1, no diffuse) over black, seen
// edge-on from the equator.
state::RenderState coreOnly()
{
    state::RenderState s;
    s.camera.azimuthDeg = 0;
    s.camera.elevationDeg = 0;
    s.camera.distanceKm = 16000;
    s.camera.fovYDeg = 40;
    s.width = 240;
    s.height = 161;  // odd: the centre row's pixel centres lie on the view axis' plane
    s.opacity = {{0.0f, 0.0f}, {1.0f, 0.0f}};
    s.core.color = {1, 1, 1};
    s.shading.ambient = 1;
    s.shading.diffuse = 0;
    s.passes = 64;  // jittered passes: the alpha of an edge pixel is its coverage to about 1/64
    s.level = 0;
    return s;
}

// Where the core (alpha) starts and ends on the centre row, in continuous pixel x: the first and
// last fully covered pixels, moved out by the coverage of the partial pixels beyond them.
std::pair<double, double> limbOnCentreRow(const FrameBuffer& frame)
{
    const std::vector<float> rgba = frame.averagedRgba();
    const int w = frame.width(), y = frame.height() / 2;
    auto alpha = [&](int x) { return double(rgba[(size_t(y) * size_t(w) + size_t(x)) * 4 + 3]); };
    int first = -1, last = -1;
    for (int x = 0; x < w; ++x)
        if (alpha(x) > 0.999) {
            if (first < 0)
                first = x;
            last = x;
        }
    if (first < 0)
        return {NAN, NAN};
    double left = first, right = last + 1;
    for (int x = 0; x < first; ++x)
        left -= alpha(x);
    for (int x = last + 1; x < w; ++x)
        right += alpha(x);
    return {left, right};
}

// The tangents from an eye (in the horizontal plane through the view axis: the eye at `offsetKm`
// along the image's right axis, the core's centre `distanceKm` ahead) to a sphere of `radiusKm`,
// in pixels of an image whose window is shifted for convergence at `convergenceKm`.
std::pair<double, double> predictedLimb(const state::RenderState& s, double offsetKm, double convergenceKm, double radiusKm)
{
    const double d = s.camera.distanceKm;
    const double towardsCentre = std::atan2(-offsetKm, d);
    const double halfAngle = std::asin(radiusKm / std::hypot(offsetKm, d));
    const double shift = convergenceKm > 0 ? -offsetKm / convergenceKm : 0.0;
    const double tanHalfX = std::tan(s.camera.fovYDeg * M_PI / 360.0) * double(s.width) / double(s.height);
    auto pixel = [&](double angle) { return (((std::tan(angle) - shift) / tanHalfX) + 1.0) * 0.5 * s.width; };
    return {pixel(towardsCentre - halfAngle), pixel(towardsCentre + halfAngle)};
}

void checkParallax(const std::shared_ptr<const dataset::Dataset>& dataset)
{
    const double coreKm = dataset->levels().front().grid.rKm.front();
    StateRenderer renderer(dataset);
    state::RenderState mono = coreOnly();
    const auto monoStill = renderer.renderStill(resolveState(mono, *dataset));
    const auto monoLimb = limbOnCentreRow(monoStill.frames[0]);
    const auto monoPredicted = predictedLimb(mono, 0, 0, coreKm);
    expect(std::abs(monoLimb.first - monoPredicted.first) < 0.15 && std::abs(monoLimb.second - monoPredicted.second) < 0.15,
           fmt::format("mono limb at {:.3f}, {:.3f}; predicted {:.3f}, {:.3f}", monoLimb.first, monoLimb.second,
                       monoPredicted.first, monoPredicted.second));

    struct Case {
        double separationKm;
        std::optional<float> convergenceKm;
    };
    for (const Case c : {Case{0, std::nullopt}, Case{1200, std::nullopt}, Case{1200, 11000.0f}, Case{2500, 40000.0f},
                         Case{800, 12400.0f}}) {
        state::RenderState s = coreOnly();
        s.stereo.mode = StereoMode::SideBySide;
        s.stereo.eyeSeparationKm = float(c.separationKm);
        s.stereo.convergenceKm = c.convergenceKm;
        const double convergence = c.convergenceKm ? *c.convergenceKm : s.camera.distanceKm;
        const auto still = renderer.renderStill(resolveState(s, *dataset));
        if (still.frames.size() != 2) {
            expect(false, "a side-by-side state did not render two eyes");
            continue;
        }
        const auto left = limbOnCentreRow(still.frames[0]), right = limbOnCentreRow(still.frames[1]);
        const auto pl = predictedLimb(s, -c.separationKm / 2, convergence, coreKm);
        const auto pr = predictedLimb(s, c.separationKm / 2, convergence, coreKm);
        const std::string name = fmt::format("separation {} km, convergence {} km", c.separationKm, convergence);
        expect(std::abs(left.first - pl.first) < 0.15 && std::abs(left.second - pl.second) < 0.15,
               fmt::format("{}: left eye's limb at {:.3f}, {:.3f}; predicted {:.3f}, {:.3f}", name, left.first,
                           left.second, pl.first, pl.second));
        expect(std::abs(right.first - pr.first) < 0.15 && std::abs(right.second - pr.second) < 0.15,
               fmt::format("{}: right eye's limb at {:.3f}, {:.3f}; predicted {:.3f}, {:.3f}", name, right.first,
                           right.second, pr.first, pr.second));
        const double parallax = right.first - left.first, predicted = pr.first - pl.first;
        expect(std::abs(parallax - predicted) < 0.2,
               fmt::format("{}: parallax of the left limb {:.3f} px, predicted {:.3f} px", name, parallax, predicted));
        fmt::print("{}: left limb parallax {:+.3f} px (predicted {:+.3f}), right limb {:+.3f} px (predicted {:+.3f})\n",
                   name, parallax, predicted, right.second - left.second, pr.second - pl.second);
        if (c.separationKm == 0) {
            const auto monoPixels = monoStill.frames[0].averagedRgba();
            expect(still.frames[0].averagedRgba() == monoPixels && still.frames[1].averagedRgba() == monoPixels,
                   "with no separation the eyes differ from the mono picture");
        }
    }
}

state::RenderState pairState(StereoMode mode)
{
    state::RenderState s = coreOnly();
    s.width = 160;
    s.height = 96;
    s.passes = 2;
    s.shading.ambient = 0.35f;  // a shaded core: the eyes' colours differ
    s.shading.diffuse = 0.65f;
    s.core.color = {0.9f, 0.6f, 0.3f};
    s.stereo.mode = mode;
    s.stereo.eyeSeparationKm = 3000;
    return s;
}

uint8_t luma(const uint8_t* p)
{
    return uint8_t(std::lround(0.299 * p[0] + 0.587 * p[1] + 0.114 * p[2]));
}

void checkAnaglyph(const std::shared_ptr<const dataset::Dataset>& dataset)
{
    StateRenderer renderer(dataset);
    const ResolvedState sbs = resolveState(pairState(StereoMode::SideBySide), *dataset);
    const ResolvedState ana = resolveState(pairState(StereoMode::Anaglyph), *dataset);
    const auto sbsStill = renderer.renderStill(sbs);
    const ImageRgba8 pair = renderer.picture(sbsStill.frames, sbs, true);
    const auto anaStill = renderer.renderStill(ana);
    const ImageRgba8 a = renderer.picture(anaStill.frames, ana, true);
    const int w = sbs.state.width, h = sbs.state.height;
    expect(pair.width == 2 * w && pair.height == h, fmt::format("side-by-side picture {}x{}", pair.width, pair.height));
    expect(a.width == w && a.height == h, fmt::format("anaglyph picture {}x{}", a.width, a.height));
    if (g_failures)
        return;
    int mismatches = 0, leftOnly = 0, leftOnlyNotRed = 0;
    const std::vector<float> leftAlpha = sbsStill.frames[0].averagedRgba(), rightAlpha = sbsStill.frames[1].averagedRgba();
    for (int y = 0; y < h; ++y)
        for (int x = 0; x < w; ++x) {
            const uint8_t* l = &pair.pixels[(size_t(y) * size_t(2 * w) + size_t(x)) * 4];
            const uint8_t* r = &pair.pixels[(size_t(y) * size_t(2 * w) + size_t(w + x)) * 4];
            const uint8_t* p = &a.pixels[(size_t(y) * size_t(w) + size_t(x)) * 4];
            if (p[0] != luma(l) || p[1] != r[1] || p[2] != r[2])
                ++mismatches;
            const size_t i = (size_t(y) * size_t(w) + size_t(x)) * 4 + 3;
            if (leftAlpha[i] > 0.999f && rightAlpha[i] == 0.0f) {
                ++leftOnly;
                if (!(p[0] > 0 && p[1] == 0 && p[2] == 0))
                    ++leftOnlyNotRed;
            }
        }
    expect(mismatches == 0, fmt::format("{} anaglyph pixels are not (left luma, right green, right blue)", mismatches));
    expect(leftOnly > 20, fmt::format("only {} pixels show the core to the left eye alone", leftOnly));
    expect(leftOnlyNotRed == 0, fmt::format("{} of {} pixels seen by the left eye alone are not pure red",
                                            leftOnlyNotRed, leftOnly));
    fmt::print("anaglyph: {} pixels equal (left luma, right green, right blue); {} pixels seen by the left eye alone "
               "are pure red\n",
               w * h - mismatches, leftOnly);
}

void checkCli(const std::shared_ptr<const dataset::Dataset>& dataset, const std::string& raypc, const fs::path& work)
{
    fs::create_directories(work);
    StateRenderer renderer(dataset);
    for (StereoMode mode : {StereoMode::SideBySide, StereoMode::SideBySideHalf, StereoMode::Anaglyph}) {
        state::RenderState s = pairState(mode);
        s.width = 101;  // odd: half width is 2 x 50
        s.height = 64;
        s.legend = true;
        const std::string name(state::stereoModeName(mode));
        const fs::path statePath = work / (name + ".json"), png = work / (name + ".png");
        std::ofstream(statePath) << toJson(s).dump(2);
        const std::string command = fmt::format("'{}' render '{}' --state '{}' -o '{}'", raypc, dataset->dir().string(),
                                                statePath.string(), png.string());
        if (std::system(command.c_str()) != 0) {
            expect(false, "failed: " + command);
            continue;
        }
        const ImageRgba8 written = readPng(png);
        const StereoLayout layout = stereoLayout(mode, s.width, s.height);
        const int expectedWidth = mode == StereoMode::SideBySide ? 202 : mode == StereoMode::SideBySideHalf ? 100 : 101;
        expect(written.width == expectedWidth && written.height == 64 && layout.width == expectedWidth,
               fmt::format("{}: raypc render wrote {}x{}, expected {}x64", name, written.width, written.height,
                           expectedWidth));
        const ResolvedState resolved = resolveState(s, *dataset);
        const auto still = renderer.renderStill(resolved);
        const ImageRgba8 here = renderer.picture(still.frames, resolved, true);
        expect(here.pixels == written.pixels, fmt::format("{}: raypc render's picture differs from StateRenderer's", name));
        fmt::print("{}: raypc render wrote {}x{}\n", name, written.width, written.height);
    }
}

}  // namespace

int main(int argc, char** argv)
{
    if (argc != 4) {
        fmt::print(stderr, "usage: raypc_stereo_check DATASET RAYPC WORKDIR\n");
        return 2;
    }
    try {
        const auto dataset = dataset::Dataset::open(argv[1]);
        checkParallax(dataset);
        checkAnaglyph(dataset);
        checkCli(dataset, argv[2], argv[3]);
    } catch (const std::exception& e) {
        fmt::print("FAIL: {}\n", e.what());
        return 1;
    }
    if (g_failures)
        fmt::print("{} failures\n", g_failures);
    else
        fmt::print("all stereo checks hold\n");
    return g_failures ? 1 : 0;
}
