// raypc demo: make the built-in demo data set if missing, preprocess it, and show it.
#include "app/command.h"
#include "core/error.h"
#include "data/preprocess.h"
#include "data/synth.h"

#include <fmt/format.h>
#include <spdlog/spdlog.h>

namespace raypc::app {
namespace {

namespace fs = std::filesystem;

struct DemoArgs {
    std::string dir = "demo-data";
};

// True when `ncDir` holds all of the demo's snapshot files (each was written atomically).
bool demoSnapshotsPresent(const fs::path& ncDir, int steps)
{
    for (int s = 1; s <= steps; ++s)
        if (!fs::exists(ncDir / fmt::format("spherical{:03d}.nc", s)))
            return false;
    return true;
}

const CommandRegistration kRegistration(
    "demo", "Create the demo data set if missing, preprocess it and show it",
    [](CLI::App& cmd) {
        auto args = std::make_shared<DemoArgs>();
        cmd.add_option("--dir", args->dir, "Where the demo's snapshots and dataset live")->capture_default_str();
        cmd.callback([args] {
            const fs::path root = args->dir;
            const fs::path ncDir = root / "snapshots", datasetDir = root / "dataset";
            const SynthOptions synth;
            if (!demoSnapshotsPresent(ncDir, synth.steps)) {
                spdlog::info("demo: writing {} synthetic snapshots of {}x{}x{} (lat x r x lon) to {}", synth.steps,
                             synth.nLat, synth.nR, synth.nLon, ncDir.string());
                writeSyntheticSeries(ncDir, synth);
            }
            PreprocessOptions options;
            options.dtMyr = synth.dtMyr;
            const auto summary = preprocess(listSnapshotFiles({ncDir}), datasetDir, options);
            const auto dataset = Dataset::open(datasetDir);
            const auto& g = dataset->levels().front().grid;
            fmt::print("demo dataset {}: {} steps ({} preprocessed now, {} already done), {}x{}x{} (lat x r x lon), "
                       "{:.0f} Myr\n",
                       datasetDir.string(), dataset->steps().size(), summary.stepsWritten, summary.stepsSkipped,
                       g.nLat(), g.nR(), g.nLon(), dataset->steps().back().timeMyr);
            for (const auto& v : dataset->variables())
                fmt::print("  {:<42} [{:<7}] {:>11.4g} .. {:<11.4g}\n", v.name, v.units, v.global.range.min,
                           v.global.range.max);
        });
    },
    5);

}  // namespace
}  // namespace raypc::app
