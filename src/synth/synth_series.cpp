// Writing the synthetic series (synth.h): one contest-layout netCDF file per step.
#include "synth/synth.h"

#include "core/error.h"
#include "core/progress.h"

#include <fmt/format.h>

#include <cmath>

namespace raypc::synth {

void writeSyntheticSeries(const std::filesystem::path& outDir, const SynthOptions& options)
{
    if (options.steps < 1)
        fail("synthetic series: {} steps, expected at least 1", options.steps);
    if (!(options.dtMyr > 0.0) || !std::isfinite(options.dtMyr))
        fail("synthetic series: time step {} Myr, expected a positive number", options.dtMyr);
    std::error_code ec;
    std::filesystem::create_directories(outDir, ec);
    if (ec)
        fail("{}: cannot create output directory: {}", outDir.string(), ec.message());
    Progress progress("synth", options.steps, "steps");
    for (int step = 0; step < options.steps; ++step) {
        const grid::Snapshot snap = synthesizeSnapshot(options, step * options.dtMyr);
        io::writeContestFile(outDir / fmt::format("spherical{:03d}.nc", step + 1), snap, options.flavour);
        progress.advance();
    }
    progress.finish();
}

}  // namespace raypc::synth
