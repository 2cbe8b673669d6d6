// raypc export DATASET --time T --what sample|pathlines|critical-points|persistence -o FILE.{csv,vtp,vtk}
#include "app/command.h"
#include "grid/variable_names.h"
#include "app/options.h"
#include "core/atomic_file.h"
#include "core/error.h"
#include "core/strings.h"
#include "dataset/dataset.h"
#include "analysis/pathline_export.h"
#include "analysis/pathline_storage.h"
#include "analysis/pathlines.h"
#include "analysis/persistence.h"

#include <fmt/format.h>
#include <fmt/ranges.h>

#include <cctype>
#include <filesystem>
#include <numeric>
#include <span>

namespace raypc::app {
namespace {

struct ExportArgs {
    std::string dataset, time = "0", what = "sample", output, var;  // var: empty, varname::anomalyToShow
};


std::string sampleCsv(const dataset::SampleTable& table)
{
    std::string out;
    out.reserve(table.rows * table.columns.size() * 12);
    for (size_t c = 0; c < table.columns.size(); ++c)
        out += (c ? "," : "") + csvQuote(fmt::format("{} [{}]", table.columns[c], table.units[c]));
    out += '\n';
    for (size_t r = 0; r < table.rows; ++r) {
        for (size_t c = 0; c < table.columns.size(); ++c) {
            if (c)
                out += ',';
            fmt::format_to(std::back_inserter(out), "{:.7g}", table.at(r, c));
        }
        out += '\n';
    }
    return out;
}

// The format of `output` from its extension: csv, vtp (VTK XML PolyData) or vtk (legacy VTK).
std::string formatOf(const std::string& output)
{
    std::string ext = std::filesystem::path(output).extension().string();
    for (char& c : ext)
        c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
    if (ext == ".csv" || ext == ".vtp" || ext == ".vtk")
        return ext.substr(1);
    fail("-o: '{}' has no known extension; expected .csv, .vtp (VTK XML PolyData) or .vtk (legacy VTK)", output);
}

const CommandRegistration kExportCommand(
    "export",
    "Export data of one step: the parallel-coordinates sample (CSV), or the pathlines injected at the step "
    "and their seeds, the critical points (CSV, VTK .vtp or legacy .vtk), or the persistence diagram (CSV)",
    [](CLI::App& cmd) {
        auto args = std::make_shared<ExportArgs>();
        cmd.add_option("dataset", args->dataset, "Dataset directory")->required();
        cmd.add_option("-t,--time", args->time, "Step index (0-based) or time like 24Myr")->capture_default_str();
        cmd.add_option("--what", args->what, "What to export: sample, pathlines, critical-points or persistence")
            ->capture_default_str();
        cmd.add_option("--var", args->var,
                       "persistence: the variable whose persistence pairs are exported (default: the temperature "
                       "anomaly, else the first variable's shell anomaly)");
        cmd.add_option("-o,--output", args->output,
                       "Output file: .csv; for pathlines and critical-points also .vtp (VTK XML) or .vtk (legacy VTK)")
            ->required();
        cmd.callback([args] {
            if (args->what != "sample" && args->what != "pathlines" && args->what != "critical-points" &&
                args->what != "persistence")
                fail("--what: unknown export '{}', expected: sample, pathlines, critical-points, persistence",
                     args->what);
            // The sample is always CSV (whatever the extension, as before pathlines existed).
            const std::string format = args->what == "sample" ? "csv" : formatOf(args->output);
            if (args->what == "persistence" && format != "csv")
                fail("-o: '{}': the persistence diagram is written as CSV only (.csv)", args->output);
            const auto dataset = dataset::Dataset::open(args->dataset);
            const int step = parseStep(*dataset, args->time);
            if (args->what == "sample") {
                const auto table = dataset->loadSample(step);
                writeFileAtomic(args->output, sampleCsv(table));
                fmt::print("{}: {} rows x {} columns of step {} ({} Myr)\n", args->output, table.rows,
                           table.columns.size(), step, dataset->steps()[step].timeMyr);
                return;
            }
            if (args->what == "persistence") {
                if (args->var.empty())
                    args->var = varname::anomalyToShow(dataset->variableNames());
                const int var = dataset->variableIndex(args->var);
                if (var < 0)
                    fail("--var: no variable '{}' in {}; variables are {}", args->var, args->dataset,
                         fmt::join(dataset->variableNames(), ", "));
                const auto volume = dataset->load(step, 0);
                const std::span<const float> values(volume->values(var), volume->grid().cellCount());
                const auto pairs = analysis::persistencePairs(volume->grid(), values);
                writeFileAtomic(args->output,
                                analysis::persistenceDiagramCsv(volume->grid(), pairs, dataset->variables()[var].units));
                fmt::print("{}: {} persistence pairs of {} at step {} ({} Myr), the largest {:.4g} {}\n", args->output,
                           pairs.size(), args->var, step, dataset->steps()[step].timeMyr,
                           pairs.front().persistence(), dataset->variables()[var].units);
                return;
            }
            const analysis::PathlineSet set = analysis::loadPathlineSet(dataset->dir(), step);
            const bool lines = args->what == "pathlines";
            std::string text;
            if (format == "csv")
                text = lines ? analysis::pathlinesCsv(set) : analysis::criticalPointsCsv(set);
            else if (format == "vtp")
                text = lines ? analysis::pathlinesVtp(set) : analysis::criticalPointsVtp(set);
            else
                text = lines ? analysis::pathlinesLegacyVtk(set) : analysis::criticalPointsLegacyVtk(set);
            writeFileAtomic(args->output, text);
            if (lines)
                fmt::print("{}: {} pathlines ({} points) injected at step {} ({} Myr), traced to step {}\n",
                           args->output, set.lineCount(), set.pointCount(), step, set.injectionTimeMyr, set.endStep);
            else
                fmt::print("{}: {} critical points of {} at step {} ({} Myr), threshold {:.4g} (of {} found)\n",
                           args->output, set.lineCount(), set.seedField, step, set.injectionTimeMyr, set.threshold,
                           std::accumulate(set.criticalCounts.begin(), set.criticalCounts.end(), size_t(0)));
        });
    },
    50);

}  // namespace
}  // namespace raypc::app
