// raypc correlate A[:VAR] B[:VAR] -o corr.csv [--lmax L] [--time T] [--time-b T] [--png corr.png]: the
// area-weighted correlation of two fields per depth (per radius shell of A's grid), their RMS and its
// ratio, optionally after low-pass filtering both to degree L (docs/compare.md, "Correlation").
#include "app/command.h"
#include "app/compare_fields.h"
#include "app/options.h"
#include "core/atomic_file.h"
#include "core/error.h"
#include "render/image_io.h"

#include <fmt/format.h>

#include <cmath>
#include <optional>

namespace raypc::app {
namespace {

struct CorrelateArgs {
    std::string a, b, output, png, time = "0", timeB, size = "640x800";
    int lmax = -1;
    bool lmaxGiven = false;
    bool quiet = false;
};

void run(const CorrelateArgs& args)
{
    checkOutputExtension(args.output, {".csv", ".txt"}, "CSV", "-o");
    if (args.lmaxGiven && args.lmax < 0)
        fail("--lmax: {} is negative; expected a spherical-harmonic degree, 0 or more", args.lmax);
    if (!args.png.empty())
        checkOutputExtension(args.png, {".png"}, "PNG", "--png");
    const auto [width, height] = parseSize(args.size);
    const ComparedField a = openComparedField(parseFieldSpec(args.a), args.time, "A", "--time", args.quiet);
    const ComparedField b =
        openComparedField(parseFieldSpec(args.b), args.timeB.empty() ? args.time : args.timeB, "B",
                          args.timeB.empty() ? "--time (B's step; --time-b to choose another)" : "--time-b", args.quiet);
    analysis::CorrelationOptions options;
    if (args.lmax >= 0)
        options.lmax = args.lmax;
    const std::vector<analysis::ShellCorrelation> rows = correlateFields(a, b, options);
    // The picture first: a picture that cannot be drawn leaves no file written.
    std::optional<render::ImageRgba8> picture;
    if (!args.png.empty())
        picture = correlationPicture(rows, a, b, options, width, height);
    writeFileAtomic(args.output, analysis::correlationCsv(rows, a.title(), a.info().units, b.title(), b.info().units, options));
    if (picture)
        render::writePng(args.png, *picture);
    size_t given = 0;
    double lo = INFINITY, hi = -INFINITY;
    for (const analysis::ShellCorrelation& row : rows)
        if (std::isfinite(row.correlation))
            ++given, lo = std::min(lo, row.correlation), hi = std::max(hi, row.correlation);
    const bool regridded = !b.volume->grid().sameAs(a.volume->grid());
    fmt::print("{}: correlation at {} of {} depths{}{}{}{}\n", args.output, given, rows.size(),
               given ? fmt::format(" ({:.3f}..{:.3f})", lo, hi) : std::string(),
               options.lmax ? fmt::format(", both filtered to degree <= {}", *options.lmax) : std::string(),
               regridded ? "; B resampled onto A's grid" : "", args.png.empty() ? "" : fmt::format("; picture in {}", args.png));
}

const CommandRegistration kCorrelateCommand(
    "correlate",
    "Correlation of two fields per depth (area-weighted Pearson), their RMS and its ratio; optionally filtered to degree L",
    [](CLI::App& cmd) {
        auto args = std::make_shared<CorrelateArgs>();
        cmd.add_option("A", args->a,
                       "The first field: INPUT[:VARIABLE], INPUT a dataset or netCDF files (preprocessed beside them); the "
                       "default variable is the temperature anomaly (else the first shell anomaly). Its grid's shells are "
                       "the depths")
            ->required();
        cmd.add_option("B", args->b, "The second field, the same way; resampled onto A's grid when the grids differ")->required();
        cmd.add_option("-o,--output", args->output,
                       "CSV: per depth the correlation, the RMS of each, their ratio, the points and area both cover")
            ->required();
        const auto* lmax = cmd.add_option("--lmax", args->lmax,
                       "Low-pass filter both fields to spherical-harmonic degree <= L first (global grids; a shell with "
                       "missing values is then left empty, said in the note column)");
        cmd.add_option("-t,--time", args->time, "The step of A (and of B unless --time-b): an index or a time like 24Myr")
            ->capture_default_str();
        cmd.add_option("--time-b", args->timeB, "The step of B when it differs from A's");
        cmd.add_option("--png", args->png, "PNG: the correlation against depth (depth down, 410 and 660 km marked)");
        cmd.add_option("--size", args->size, "The picture's size WIDTHxHEIGHT")->capture_default_str();
        cmd.add_flag("-q,--quiet", args->quiet, "No progress output (while preprocessing netCDF inputs)");
        cmd.callback([args, lmax] {
            args->lmaxGiven = lmax->count() > 0;
            run(*args);
        });
    },
    74);

}  // namespace
}  // namespace raypc::app
