// raypc spectrum A[:VAR] -o spectrum.csv [--lmax L] [--time T] [--png spectrum.png]: the
// spherical-harmonic power per degree of a field on every shell (the degree–depth "spectral
// heterogeneity map"); with --with B[:VAR] --depth D, the per-degree correlation of two fields at one
// depth (docs/compare.md, "Spectra").
#include "app/command.h"
#include "app/compare_fields.h"
#include "app/options.h"
#include "core/atomic_file.h"
#include "core/error.h"
#include "render/image_io.h"

#include <fmt/format.h>

#include <optional>

namespace raypc::app {
namespace {

struct SpectrumArgs {
    std::string a, with, output, png, time = "0", timeB, size = "960x540";
    int lmax = -1;
    bool lmaxGiven = false;
    double depthKm = -1;
    bool depthGiven = false, quiet = false;
};

void run(const SpectrumArgs& args)
{
    checkOutputExtension(args.output, {".csv", ".txt"}, "CSV", "-o");
    if (args.lmaxGiven && args.lmax < 0)
        fail("--lmax: {} is negative; expected a spherical-harmonic degree, 0 or more", args.lmax);
    if (!args.png.empty())
        checkOutputExtension(args.png, {".png"}, "PNG", "--png");
    if (args.with.empty() && args.depthGiven)
        fail("--depth: needs --with B (the per-degree correlation at that depth); the spectrum is of every depth");
    if (!args.with.empty() && !args.depthGiven)
        fail("--with: needs --depth D (km), the depth of the per-degree correlation");
    if (!args.with.empty() && !args.png.empty())
        fail("--png: the degree-depth picture is of one field's spectrum; drop --with (the per-degree correlation is a table)");
    if (args.with.empty() && !args.timeB.empty())
        fail("--time-b: needs --with B");
    const auto [width, height] = parseSize(args.size);
    const ComparedField a = openComparedField(parseFieldSpec(args.a), args.time, "A", "--time", args.quiet);
    if (!args.with.empty()) {
        const ComparedField b =
            openComparedField(parseFieldSpec(args.with), args.timeB.empty() ? args.time : args.timeB, "B",
                              args.timeB.empty() ? "--time (B's step; --time-b to choose another)" : "--time-b", args.quiet);
        const analysis::DegreeCorrelation c = fieldDegreeCorrelation(a, b, args.depthKm, args.lmax);
        writeFileAtomic(args.output, analysis::degreeCorrelationCsv(c, a.title(), a.info().units, b.title(), b.info().units));
        fmt::print("{}: per-degree correlation of A and B at depth {:g} km (the shell nearest {:g} km), degrees 0..{}\n",
                   args.output, c.depthKm, args.depthKm, c.lmax);
        return;
    }
    const analysis::ShellSpectra s = fieldSpectra(a, args.lmax);
    std::optional<render::ImageRgba8> picture;
    if (!args.png.empty())
        picture = spectrumPicture(s, a, width, height);
    writeFileAtomic(args.output, analysis::spectrumCsv(s, a.title(), a.info().units));
    if (picture)
        render::writePng(args.png, *picture);
    fmt::print("{}: power per degree 0..{} at {} depths ({}){}\n", args.output, s.lmax, s.radiiKm.size(),
               analysis::quadratureName(s.quadrature), args.png.empty() ? "" : fmt::format("; picture in {}", args.png));
}

const CommandRegistration kSpectrumCommand(
    "spectrum",
    "Spherical-harmonic power per degree of a field at every depth; --with B --depth D: per-degree correlation at a depth",
    [](CLI::App& cmd) {
        auto args = std::make_shared<SpectrumArgs>();
        cmd.add_option("A", args->a,
                       "The field: INPUT[:VARIABLE], INPUT a dataset or netCDF files (preprocessed beside them); the default "
                       "variable is the temperature anomaly (else the first shell anomaly). A global grid without missing "
                       "values")
            ->required();
        cmd.add_option("-o,--output", args->output, "CSV: per depth and degree the power (4pi-normalised, units squared)")
            ->required();
        const auto* lmax = cmd.add_option("--lmax", args->lmax, "The largest degree (default: the grid's largest, at most 60)");
        cmd.add_option("-t,--time", args->time, "The step: an index or a time like 24Myr")->capture_default_str();
        cmd.add_option("--png", args->png, "PNG: log power per degree (1..L, right) and depth (down), with a colour bar");
        cmd.add_option("--size", args->size, "The picture's size WIDTHxHEIGHT")->capture_default_str();
        cmd.add_option("--with", args->with, "B[:VARIABLE]: the per-degree correlation of A and B (on A's grid) at --depth");
        const auto* depth = cmd.add_option("--depth", args->depthKm, "With --with: the depth, km (the nearest shell of A's grid)");
        cmd.add_option("--time-b", args->timeB, "With --with: the step of B when it differs from A's");
        cmd.add_flag("-q,--quiet", args->quiet, "No progress output (while preprocessing netCDF inputs)");
        cmd.callback([args, depth, lmax] {
            args->depthGiven = depth->count() > 0;
            args->lmaxGiven = lmax->count() > 0;
            run(*args);
        });
    },
    75);

}  // namespace
}  // namespace raypc::app
