// libFuzzer target: the command line's numeric and text options as `raypc preprocess` (and serve,
// render, info of inputs) parse them (app/options.h: PreprocessFlags, ReaderFlags, parseSize), on
// arbitrary argument lists (the input split at newlines). Any input must give options or one
// CLI11 parse error or raypc::Error; never a crash, a hang or a huge allocation, and the options it
// gives hold only what the commands may take: finite numbers, a sample within its bounds, a
// picture size within 1..16384.
#include "app/options.h"
#include "core/error.h"

#include <CLI/CLI.hpp>

#include <cmath>
#include <cstddef>
#include <cstdint>
#include <string>
#include <vector>

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size)
{
    if (size > 4096)
        return 0;
    std::vector<std::string> args;
    std::string current;
    for (size_t i = 0; i < size; ++i) {
        if (data[i] == '\n') {
            args.push_back(current);
            current.clear();
        } else {
            current += char(data[i]);
        }
    }
    args.push_back(current);
    if (args.size() > 64)
        return 0;

    // The first argument, when it has an 'x', is also a picture size (--size WxH).
    try {
        const auto [w, h] = raypc::app::parseSize(args.front());
        if (w < 1 || h < 1 || w > 16384 || h > 16384)
            __builtin_trap();
    } catch (const raypc::Error&) {
    }

    CLI::App app{"fuzz"};
    raypc::app::PreprocessFlags flags;
    flags.add(app);
    raypc::app::requireFiniteNumbers(app);
    app.allow_extras();
    std::vector<std::string> reversed(args.rbegin(), args.rend());  // CLI11 parses a reversed vector
    try {
        app.parse(reversed);
        const raypc::preprocess::PreprocessOptions o = flags.toOptions(app);
        if (!std::isfinite(o.dtMyr) || o.sampleRows < 1 || o.sampleRows > raypc::preprocess::kMaxSampleRows ||
            !std::isfinite(o.reader.temperatureScaleK) || o.reader.temperatureScaleK < 0 ||
            (o.reader.planetRadiusKm && !(*o.reader.planetRadiusKm > 0)) ||
            (o.reader.diffusivityM2s && !(*o.reader.diffusivityM2s > 0)))
            __builtin_trap();
    } catch (const CLI::Error&) {
    } catch (const raypc::Error&) {
    }
    return 0;
}
