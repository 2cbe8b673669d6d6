// raypc flux DATASET --depth 660 -o flux.csv [--heat-flux [--density 3300] [--heat-capacity 1250]]:
// the volume flux across shells in every step, down and up, over the whole shell and within a
// selection, with the avalanche steps marked, and the advective heat flux (analysis/flux.h).
#include "app/command.h"
#include "grid/variable_names.h"
#include "app/options.h"
#include "core/atomic_file.h"
#include "core/error.h"
#include "core/progress.h"
#include "dataset/dataset.h"
#include "analysis/feature_csv.h"
#include "analysis/flux.h"

#include <fmt/format.h>

#include <algorithm>
#include <optional>

namespace raypc::app {
namespace {

struct FluxArgs {
    SeriesSelectionFlags selection;
    std::string output;
    std::vector<double> depths{660};
    double sigmas = 2;
    bool heatFlux = false, heatConstantsGiven = false;  // --density or --heat-capacity on the command line
    double densityKgM3 = analysis::HeatFluxInputs{}.densityKgM3, heatCapacity = analysis::HeatFluxInputs{}.heatCapacityJPerKgK;
    bool quiet = false;
};

void run(const FluxArgs& args)
{
    checkOutputExtension(args.output, {".csv", ".txt"}, "CSV", "-o");
    const SeriesSelection sel = resolveSeriesSelection(args.selection);
    const dataset::Dataset& dataset = *sel.dataset;
    const std::vector<std::string> names = dataset.variableNames();
    const auto vr = std::find(names.begin(), names.end(), varname::kRadialVelocity);
    if (vr == names.end())
        fail("flux: the dataset has no '{}' variable (preprocessing derives it from the velocity components)",
             varname::kRadialVelocity);
    if (!(args.sigmas >= 0))
        fail("--sigmas: {} is negative", args.sigmas);
    for (const double depth : args.depths)
        analysis::checkShellDepth(dataset.levels()[size_t(args.selection.level)].grid, depth);
    std::optional<analysis::HeatFluxInputs> heat;
    if (args.heatFlux) {
        const auto anomaly = std::find(names.begin(), names.end(), varname::kTemperatureAnomaly);
        if (anomaly == names.end())
            fail("--heat-flux: the dataset has no '{}' variable (T' of Q = rho c_p T' v_r)", varname::kTemperatureAnomaly);
        if (!(args.densityKgM3 > 0))
            fail("--density: {} kg/m3 is not positive", args.densityKgM3);
        if (!(args.heatCapacity > 0))
            fail("--heat-capacity: {} J/(kg K) is not positive", args.heatCapacity);
        // Bounds far beyond any rock (about 3300 kg/m³, 1250 J/(kg K)) keep the product finite.
        if (args.densityKgM3 > 1e5)
            fail("--density: {} kg/m3, expected at most 100000 (rock is about 3300)", args.densityKgM3);
        if (args.heatCapacity > 1e5)
            fail("--heat-capacity: {} J/(kg K), expected at most 100000 (rock is about 1250)", args.heatCapacity);
        heat = analysis::HeatFluxInputs{size_t(anomaly - names.begin()), args.densityKgM3, args.heatCapacity};
    } else if (args.heatConstantsGiven) {
        fail("--density, --heat-capacity: need --heat-flux (the flux they enter)");
    }

    // The mass flux where the data have a density (ASPECT writes one; the contest's files do not).
    std::optional<size_t> density;
    if (const auto rho = std::find(names.begin(), names.end(), analysis::kDensityVariable); rho != names.end())
        density = size_t(rho - names.begin());
    std::vector<std::vector<analysis::ShellFlux>> bySteps;  // [step - first][depth]
    std::optional<Progress> progress;
    if (!args.quiet)
        progress.emplace("flux", sel.last - sel.first + 1, "steps");
    for (int step = sel.first; step <= sel.last; ++step) {
        bySteps.push_back(analysis::shellFluxes(*dataset.load(step, args.selection.level), size_t(vr - names.begin()),
                                      args.depths, sel.filters, heat, density));
        if (progress)
            progress->advance();
    }
    if (progress)
        progress->finish();

    // Avalanches per depth, over the series' steps.
    const auto perShell = analysis::avalancheStepsPerShell(bySteps, args.sigmas);
    size_t avalanches = 0;
    for (const auto& steps : perShell)
        avalanches += steps.size();
    const std::string csv = analysis::fluxCsv(dataset, sel.first, bySteps, args.depths, perShell, heat.has_value(), density.has_value());
    writeFileAtomic(args.output, csv);
    fmt::print("{}: flux across {} shell(s) in {} steps ({}..{}); {} avalanche step(s) (downward flux over mean + {:g} sigma)\n",
               args.output, args.depths.size(), bySteps.size(), sel.first, sel.last, avalanches, args.sigmas);
}

const CommandRegistration kFluxCommand(
    "flux",
    "Volume flux across shells (km³/yr, down and up, whole shell and selection) in every step, avalanches marked",
    [](CLI::App& cmd) {
        auto args = std::make_shared<FluxArgs>();
        args->selection.add(cmd);
        cmd.add_option("-o,--output", args->output,
                       "CSV: a row per step and depth (down, up, net; the selection's down and up; avalanche)")
            ->required();
        cmd.add_option("--depth", args->depths, "Depth of a shell, km; repeatable")->capture_default_str();
        cmd.add_option("--sigmas", args->sigmas, "Avalanche: downward flux over the series' mean + this many standard deviations")
            ->capture_default_str();
        cmd.add_flag("--heat-flux", args->heatFlux,
                     "Also the advective heat flux Q = rho c_p T' v_r over the shell and the selection, W (positive upward; "
                     "T' is the temperature anomaly)");
        const auto* density =
            cmd.add_option("--density", args->densityKgM3, "rho of the heat flux, kg/m3 (a constant)")->capture_default_str();
        const auto* heatCapacity = cmd.add_option("--heat-capacity", args->heatCapacity,
                                                  "c_p of the heat flux, J/(kg K) (a constant)")
                                       ->capture_default_str();
        cmd.add_flag("-q,--quiet", args->quiet, "No progress output");
        cmd.callback([args, density, heatCapacity] {
            args->heatConstantsGiven = density->count() > 0 || heatCapacity->count() > 0;
            run(*args);
        });
    },
    72);

}  // namespace
}  // namespace raypc::app
