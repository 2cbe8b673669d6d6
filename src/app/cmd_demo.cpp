// raypc demo: make the built-in demo data set if missing, preprocess it, render a picture of it
// (<dir>/demo.png) and serve it to the browser UI (unless --no-serve).
#include "app/command.h"
#include "app/serve_setup.h"
#include "core/error.h"
#include "preprocess/preprocess.h"
#include "synth/synth.h"
#include "render/image_io.h"
#include "render/state_renderer.h"

#include <fmt/format.h>
#include <cstdio>
#include <spdlog/spdlog.h>

namespace raypc::app {
namespace {

namespace fs = std::filesystem;

struct DemoArgs {
    std::string dir = "demo-data";
    bool noServe = false;
    ServeFlags serve;
};

// The picture of the demo: the UI's first view (render::defaultState: temperature anomaly,
// blue-white-red, opacity on the hot and cold tails) at full resolution, converged.
void renderDemoPicture(std::shared_ptr<const dataset::Dataset> dataset, int step, const fs::path& output)
{
    state::RenderState state = render::defaultState(*dataset);
    state.step = step;
    const render::ResolvedState resolved = render::resolveState(state, *dataset);
    render::StateRenderer renderer(dataset);
    const auto still = renderer.renderStill(resolved);
    double seconds = 0;
    for (const auto& pass : still.passes)
        seconds += pass.seconds;
    const render::ImageRgba8 picture = renderer.picture(still.frames, resolved, true);
    render::writePng(output, picture);
    fmt::print("demo picture {}: step {}, {}x{}, {} passes in {:.2f} s\n", output.string(), step, picture.width,
               picture.height, still.frames.front().passes(), seconds);
}

// True when `ncDir` holds all of the demo's snapshot files (each was written atomically).
bool demoSnapshotsPresent(const fs::path& ncDir, int steps)
{
    for (int s = 1; s <= steps; ++s)
        if (!fs::exists(ncDir / fmt::format("spherical{:03d}.nc", s)))
            return false;
    return true;
}

const CommandRegistration kDemoCommand(
    "demo", "Create the demo data set if missing, preprocess it, render demo.png and serve it",
    [](CLI::App& cmd) {
        auto args = std::make_shared<DemoArgs>();
        cmd.add_option("--dir", args->dir, "Where the demo's snapshots and dataset live")->capture_default_str();
        cmd.add_flag("--no-serve", args->noServe, "Only make the data and the picture, then exit");
        args->serve.add(cmd);
        cmd.callback([args] {
            const fs::path root = args->dir;
            const fs::path ncDir = root / "snapshots", datasetDir = root / "dataset";
            const synth::SynthOptions synth;
            if (!demoSnapshotsPresent(ncDir, synth.steps)) {
                spdlog::info("demo: writing {} synthetic snapshots of {}x{}x{} (lat x r x lon) to {}", synth.steps,
                             synth.nLat, synth.nR, synth.nLon, ncDir.string());
                synth::writeSyntheticSeries(ncDir, synth);
            }
            preprocess::PreprocessOptions options;
            options.dtMyr = synth.dtMyr;
            const auto summary = preprocess::preprocess(io::listSnapshotFiles({ncDir}), datasetDir, options);
            const auto dataset = dataset::Dataset::open(datasetDir);
            const auto& g = dataset->levels().front().grid;
            fmt::print("demo dataset {}: {} steps ({} preprocessed now, {} already done), {}x{}x{} (lat x r x lon), "
                       "{:.0f} Myr\n",
                       datasetDir.string(), dataset->steps().size(), summary.stepsWritten, summary.stepsSkipped,
                       g.nLat(), g.nR(), g.nLon(), dataset->steps().back().timeMyr);
            for (const auto& v : dataset->variables())
                fmt::print("  {:<42} [{:<7}] {:>11.4g} .. {:<11.4g}\n", v.name, v.units, v.global.range.min,
                           v.global.range.max);
            renderDemoPicture(dataset, int(dataset->steps().size()) / 2, root / "demo.png");
            if (args->noServe)
                return;
            serveDataset(datasetDir, args->serve);
        });
    },
    5, Ranks::OneProcess);

}  // namespace
}  // namespace raypc::app
