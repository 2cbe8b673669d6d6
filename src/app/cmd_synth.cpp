// `raypc synth`: writes a synthetic mantle-convection time series in the contest layout.
#include "app/command.h"
#include "core/clock.h"
#include "core/atomic_file.h"
#include "core/error.h"
#include "synth/synth.h"

#include <cmath>
#include <chrono>
#include <cstdio>
#include <filesystem>
#include <string>
#include <stdexcept>

namespace raypc::app {
namespace {

io::NetcdfFlavour parseFormat(const std::string& text)
{
    if (text == "classic")
        return io::NetcdfFlavour::Classic64;
    if (text == "netcdf4")
        return io::NetcdfFlavour::Netcdf4;
    fail("--format '{}': expected classic or netcdf4", text);
}

struct SynthArgs {
    std::string outDir;
    int steps = synth::SynthOptions{}.steps;
    std::string grid;
    uint64_t seed = synth::SynthOptions{}.seed;
    double dtMyr = synth::SynthOptions{}.dtMyr;
    std::string format = "classic";
    std::string truth;  // --truth FILE
    std::string avalanche;  // --avalanche T[:D] (Myr)
};

// "--avalanche T[:D]": an avalanche from T Myr for D Myr (default: one step).
void parseAvalanche(const std::string& text, synth::SynthOptions& options)
{
    const size_t colon = text.find(':');
    double start = 0, duration = options.dtMyr;
    size_t used = 0;
    try {
        start = std::stod(text.substr(0, colon), &used);
        if (used != (colon == std::string::npos ? text.size() : colon))
            throw std::invalid_argument("trailing text");
        if (colon != std::string::npos) {
            const std::string d = text.substr(colon + 1);
            duration = std::stod(d, &used);
            if (used != d.size())
                throw std::invalid_argument("trailing text");
        }
    } catch (const std::exception&) {
        fail("--avalanche '{}': expected START or START:DURATION in Myr (e.g. 11 or 11:2)", text);
    }
    if (!std::isfinite(start) || start < 0)
        fail("--avalanche '{}': the start {} Myr is not a time of the series (>= 0)", text, start);
    if (!std::isfinite(duration) || duration <= 0)
        fail("--avalanche '{}': the duration {} Myr is not positive", text, duration);
    options.avalancheMyr = start;
    options.avalancheDurationMyr = duration;
}

void run(const SynthArgs& args)
{
    synth::SynthOptions options;
    if (args.steps < 1)
        fail("--steps {}: expected at least 1", args.steps);
    options.steps = args.steps;
    if (!args.grid.empty()) {
        const auto sizes = synth::parseSynthGridSize(args.grid, "--grid");
        options.nLat = sizes[0];
        options.nR = sizes[1];
        options.nLon = sizes[2];
    }
    options.seed = args.seed;
    if (!(args.dtMyr > 0.0) || !std::isfinite(args.dtMyr))
        fail("--dt-myr {}: expected a positive number of Myr", args.dtMyr);
    options.dtMyr = args.dtMyr;
    options.flavour = parseFormat(args.format);
    if (!args.avalanche.empty())
        parseAvalanche(args.avalanche, options);

    const auto start = std::chrono::steady_clock::now();
    // The truth before the series: a truth file that cannot be written leaves no series behind.
    if (!args.truth.empty()) {
        const std::filesystem::path dir = std::filesystem::absolute(args.truth).parent_path();
        if (!std::filesystem::is_directory(dir))
            fail("--truth {}: the directory {} does not exist", args.truth, dir.string());
    }
    const std::string truth = args.truth.empty() ? std::string() : synth::syntheticTruthTable(options);
    synth::writeSyntheticSeries(args.outDir, options);
    if (!args.truth.empty())
        writeFileAtomic(args.truth, truth);
    const double seconds = secondsSince(start);
    uintmax_t bytes = 0;
    for (int step = 1; step <= options.steps; ++step) {
        std::error_code ec;
        const auto size = std::filesystem::file_size(std::filesystem::path(args.outDir) / fmt::format("spherical{:03d}.nc", step), ec);
        if (!ec)
            bytes += size;
    }
    std::printf("synth: wrote %d steps (%dx%dx%d, %.3g Myr apart, seed %llu, %s) to %s: %.1f MB in %.1f s\n",
                options.steps, options.nLat, options.nR, options.nLon, options.dtMyr,
                static_cast<unsigned long long>(options.seed), args.format.c_str(), args.outDir.c_str(),
                bytes / 1e6, seconds);
}

const CommandRegistration kSynthCommand(
    "synth", "Write a synthetic mantle-convection time series in the contest's netCDF layout",
    [](CLI::App& cmd) {
        auto args = std::make_shared<SynthArgs>();
        cmd.add_option("-o,--output", args->outDir, "Output directory (created if missing)")->required();
        cmd.add_option("--steps", args->steps, "Number of time steps")->capture_default_str();
        cmd.add_option("--grid", args->grid, "Grid size LATxRxLON (default 64x81x128; contest: 180x201x360)");
        cmd.add_option("--seed", args->seed, "Seed of the feature placement")->capture_default_str();
        cmd.add_option("--dt-myr", args->dtMyr, "Time between steps in Myr")->capture_default_str();
        cmd.add_option("--truth", args->truth,
                       "CSV: the generator's plumes and slabs in every step (front depth, stall depth, core volumes), "
                       "the ground truth of raypc features");
        cmd.add_option("--avalanche", args->avalanche,
                       "START[:DURATION] in Myr: the first slab stalled at 660 km breaks through it then "
                       "(default duration: one step); the truth file marks it (breaking_through)");
        cmd.add_option("--format", args->format, "netCDF flavour: classic (64-bit offset) or netcdf4")
            ->capture_default_str();
        cmd.callback([args] { run(*args); });
    },
    10);

}  // namespace
}  // namespace raypc::app
