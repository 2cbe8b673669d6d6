// The golden images' comparer. Each golden case is a state document (cases/NAME.json) that
// `raypc render` draws through the one path from a state to pixels (render/state_renderer.h) from a
// small dataset written at test time (CMakeLists.txt); this program compares its picture:
//
//   raypc_golden compare NAME ACTUAL.png GOLDEN_DIR OUT_DIR
//     Pass: at most 0.5% of pixels differ from GOLDEN_DIR/NAME.png by more than 10/255 in any
//     channel and the mean difference is below 1/255 (SIMD widths and libm differ slightly between
//     machines). On failure writes OUT_DIR/NAME.png (actual) and OUT_DIR/NAME.diff.png
//     (differences x8). With RAYPC_UPDATE_GOLDEN=1 the golden is (re)written instead.
//   raypc_golden same A.png B.png CONTROL.png
//     Two pictures of one view drawn two ways (an explicit camera view equal to the orbit's frame)
//     must match within 1/255, and CONTROL (the view changed a little) must differ from A by at
//     least 32/255 somewhere: the view is used.
#include "core/error.h"
#include "render/image_io.h"

#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <string>

using namespace raypc;
using namespace raypc::render;

namespace {

// The largest channel difference of two pictures of one size, and how many channel values differ.
int largestDifference(const ImageRgba8& a, const ImageRgba8& b, const std::string& what, size_t& differing)
{
    if (a.width != b.width || a.height != b.height)
        fail("{}: pictures of {}x{} and {}x{}", what, a.width, a.height, b.width, b.height);
    int worst = 0;
    differing = 0;
    for (size_t i = 0; i < a.pixels.size(); ++i) {
        const int d = std::abs(int(a.pixels[i]) - int(b.pixels[i]));
        worst = std::max(worst, d);
        differing += d > 0;
    }
    return worst;
}

int same(const std::filesystem::path& aFile, const std::filesystem::path& bFile, const std::filesystem::path& controlFile)
{
    const ImageRgba8 a = readPng(aFile), b = readPng(bFile), control = readPng(controlFile);
    size_t differing = 0, controlDiffering = 0;
    const int worst = largestDifference(a, b, "same", differing);
    const int controlWorst = largestDifference(a, control, "same (control)", controlDiffering);
    std::printf("%s vs %s: largest difference %d/255, %zu channel values differ; the control %s: %d/255, %zu differ\n",
                aFile.filename().c_str(), bFile.filename().c_str(), worst, differing, controlFile.filename().c_str(),
                controlWorst, controlDiffering);
    if (controlWorst < 32)
        fail("{}: the changed view gives the same picture as {}: the view is not used", controlFile.string(),
             aFile.string());
    if (worst > 1) {
        std::fprintf(stderr, "%s differs from %s\n", bFile.c_str(), aFile.c_str());
        return 1;
    }
    return 0;
}

int compare(const std::string& name, const std::filesystem::path& actualFile, const std::filesystem::path& goldenDir,
            const std::filesystem::path& outDir)
{
    const ImageRgba8 actual = readPng(actualFile);
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
    std::printf("%s: %.3f%% pixels off by > 10/255, mean difference %.3f/255\n", name.c_str(), 100 * badFraction, mean);
    if (badFraction > 0.005 || mean > 1.0) {
        writePng(outDir / (name + ".png"), actual);
        writePng(outDir / (name + ".diff.png"), diff);
        std::fprintf(stderr, "%s: differs from the golden; see %s\n", name.c_str(),
                     (outDir / (name + ".diff.png")).string().c_str());
        return 1;
    }
    return 0;
}

}  // namespace

int main(int argc, char** argv)
{
    try {
        const std::string mode = argc > 1 ? argv[1] : "";
        if (mode == "compare" && argc == 6)
            return compare(argv[2], argv[3], argv[4], argv[5]);
        if (mode == "same" && argc == 5)
            return same(argv[2], argv[3], argv[4]);
        std::fprintf(stderr, "usage: raypc_golden compare NAME ACTUAL.png GOLDEN_DIR OUT_DIR\n"
                             "       raypc_golden same A.png B.png CONTROL.png\n");
        return 2;
    } catch (const std::exception& e) {
        std::fprintf(stderr, "raypc_golden: error: %s\n", e.what());
        return 1;
    }
}
