// raypc export DATASET --time T --what sample -o FILE.csv
#include "app/command.h"
#include "app/options.h"
#include "core/atomic_file.h"
#include "core/error.h"
#include "data/dataset.h"

#include <fmt/format.h>

namespace raypc::app {
namespace {

struct ExportArgs {
    std::string dataset, time = "0", what = "sample", output;
};

std::string csvQuote(const std::string& s)
{
    if (s.find_first_of(",\"\n") == std::string::npos)
        return s;
    std::string out = "\"";
    for (char c : s)
        out += c == '"' ? std::string("\"\"") : std::string(1, c);
    return out + "\"";
}

std::string sampleCsv(const SampleTable& table)
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

const CommandRegistration kRegistration(
    "export", "Export data of one step (the parallel-coordinates sample as CSV)",
    [](CLI::App& cmd) {
        auto args = std::make_shared<ExportArgs>();
        cmd.add_option("dataset", args->dataset, "Dataset directory")->required();
        cmd.add_option("-t,--time", args->time, "Step index (0-based) or time like 24Myr")->capture_default_str();
        cmd.add_option("--what", args->what, "What to export: sample")->capture_default_str();
        cmd.add_option("-o,--output", args->output, "Output file (.csv)")->required();
        cmd.callback([args] {
            if (args->what != "sample")
                fail("--what: unknown export '{}', expected: sample", args->what);
            const auto dataset = Dataset::open(args->dataset);
            const int step = parseStep(*dataset, args->time);
            const auto table = dataset->loadSample(step);
            writeFileAtomic(args->output, sampleCsv(table));
            fmt::print("{}: {} rows x {} columns of step {} ({} Myr)\n", args->output, table.rows,
                       table.columns.size(), step, dataset->steps()[step].timeMyr);
        });
    },
    50);

}  // namespace
}  // namespace raypc::app
