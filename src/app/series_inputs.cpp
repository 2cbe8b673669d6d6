#include "app/series_inputs.h"

#include "core/clock.h"
#include "core/error.h"
#include "core/error_kinds.h"
#include "core/mpi.h"
#include "dataset/dataset.h"
#include "dataset/dataset_format.h"
#include "io/netcdf_reader.h"
#include "io/series_input.h"

#include <fmt/format.h>
#include <spdlog/spdlog.h>

#include <algorithm>
#include <cctype>
#include <chrono>
#include <system_error>

#include <unistd.h>

namespace raypc::app {

namespace fs = std::filesystem;

namespace {

// "spherical001", "spherical002" -> "spherical"; one file keeps its stem. Never empty.
std::string seriesName(const std::vector<fs::path>& files)
{
    std::string name = files.front().stem().string();
    for (const auto& f : files) {
        const std::string stem = f.stem().string();
        size_t n = 0;
        while (n < name.size() && n < stem.size() && name[n] == stem[n])
            ++n;
        name.resize(n);
    }
    if (files.size() > 1)
        while (!name.empty() && std::isdigit(static_cast<unsigned char>(name.back())))
            name.pop_back();
    while (!name.empty() && (name.back() == '_' || name.back() == '-' || name.back() == '.'))
        name.pop_back();
    return name.empty() ? "series" : name;
}

// The directories a run is about to create for a dataset: `dir` and those of its parents that do not
// exist yet. When the run fails before writing anything that stays (preprocess() removes what it
// wrote itself, docs/format.md "What a failed run leaves"), removeIfEmpty() takes them away again,
// so that a failed open leaves no empty directory behind. Only directories this run created go, and
// only while empty: a directory that existed before, or one holding anything, is never touched, and
// fs::remove does not follow a symbolic link.
class CreatedDirectories {
public:
    explicit CreatedDirectories(const fs::path& dir)
    {
        std::error_code ec;
        const fs::path absolute = fs::absolute(dir, ec);
        if (ec)
            return;
        for (fs::path p = absolute; !p.empty() && p != p.parent_path(); p = p.parent_path()) {
            std::error_code statusError;  // set for a path that does not exist: that is the answer here
            if (fs::symlink_status(p, statusError).type() != fs::file_type::not_found)
                break;
            m_missing.push_back(p);  // innermost first
        }
    }
    void removeIfEmpty() const
    {
        for (const fs::path& p : m_missing) {
            std::error_code ec;
            if (!fs::is_directory(fs::symlink_status(p, ec)) || !fs::is_empty(p, ec) || ec || !fs::remove(p, ec))
                return;  // not ours to remove any more (something was put there): keep it and its parents
        }
    }

private:
    std::vector<fs::path> m_missing;
};

// Runs `work`, which may create `dir`; if it throws, the directories it created and left empty go.
template <typename Work>
void leavingNothingOnFailure(const fs::path& dir, Work&& work)
{
    const CreatedDirectories created(dir);
    try {
        work();
    } catch (...) {
        created.removeIfEmpty();
        throw;
    }
}

// The dataset directory of files exists and can be written, or one error that says where to write.
void checkWritable(const fs::path& dir)
{
    std::error_code ec;
    fs::create_directories(dir, ec);
    if (ec || ::access(dir.c_str(), W_OK) != 0)
        fail("{}: cannot write the dataset of the netCDF files here ({}); give --dataset DIR to write it elsewhere",
             dir.string(), ec ? ec.message() : std::string("not writable"));
}

}  // namespace

SeriesInputs resolveSeriesInputs(const std::vector<std::string>& args, const std::string& datasetOption,
                                 const io::ReaderOptions& reader)
{
    if (args.empty())
        fail("no input: give a dataset directory or netCDF files");
    if (args.size() == 1 && isDatasetDirectory(args.front())) {
        if (!datasetOption.empty())
            fail("--dataset: only for netCDF inputs; '{}' is a dataset already", args.front());
        return {fs::path(args.front()), {}, {}};
    }
    SeriesInputs inputs;
    io::SeriesListing listing;
    try {
        listing = io::listSeries(std::vector<fs::path>(args.begin(), args.end()), reader);
    } catch (const Error& e) {
        failLike(e, fmt::format("{} (expected a RayPC dataset directory, which holds {}, netCDF files or an ASPECT "
                                ".pvd collection)",
                                e.what(), dataset::format::kManifest));
    }
    inputs.files = listing.steps;
    inputs.timesMyr = listing.timesMyr;
    const fs::path beside = listing.collection.empty() ? inputs.files.front() : listing.collection;
    inputs.dataset = datasetOption.empty()
                         ? fs::absolute(beside).parent_path() / (seriesName(inputs.files) + ".raypc")
                         : fs::path(datasetOption);
    return inputs;
}

bool isDatasetDirectory(const fs::path& path)
{
    return fs::is_directory(path) && fs::exists(path / dataset::format::kManifest);
}

bool datasetOfFiles(const fs::path& dir, const std::vector<fs::path>& files)
{
    if (!fs::exists(dir / dataset::format::kManifest))
        return false;
    std::shared_ptr<const dataset::Dataset> dataset;
    try {
        dataset = dataset::Dataset::open(dir);
    } catch (const Error&) {
        return false;  // unfinished or unreadable: preprocessing resumes or says what is wrong
    }
    const auto& steps = dataset->steps();
    if (steps.size() != files.size())
        return false;
    for (size_t s = 0; s < files.size(); ++s)
        if (steps[s].source != files[s].filename().string())
            return false;
    return true;
}

double preparePreview(const SeriesInputs& inputs, preprocess::PreprocessOptions options)
{
    const auto start = std::chrono::steady_clock::now();
    const std::vector<fs::path> first = {inputs.files.front()};
    const fs::path dir = inputs.previewDir();
    if (!datasetOfFiles(dir, first)) {
        std::error_code ec;
        fs::remove_all(dir, ec);  // a preview of other files, or of other options: ours to replace
        options.pathlines.enabled = false;
        options.quiet = true;
        options.stepsFrom = inputs.dataset;  // the series' step 0, when it is written: not made twice
        if (!options.timesMyr.empty())
            options.timesMyr.resize(1);
        leavingNothingOnFailure(inputs.dataset, [&] {
            checkWritable(inputs.dataset);
            preprocess::preprocess(first, dir, options);
        });
    }
    return secondsSince(start);
}

void prepareSeries(const SeriesInputs& inputs, const preprocess::PreprocessOptions& options, bool keepPreview)
{
    leavingNothingOnFailure(inputs.dataset, [&] {
        checkWritable(inputs.dataset);
        preprocess::preprocess(inputs.files, inputs.dataset, options);
    });
    if (!keepPreview)
        removePreview(inputs);
}

void removePreview(const SeriesInputs& inputs)
{
    std::error_code ec;
    fs::remove_all(inputs.previewDir(), ec);
}

void SeriesFlags::add(CLI::App& cmd, const std::string& inputsHelp)
{
    cmd.add_option("inputs", inputs,
                   "A dataset directory (raypc preprocess), or netCDF files / directories of *.nc, or ASPECT's output "
                   "(solution.pvd or its directory): " + inputsHelp)
        ->required();
    cmd.add_option("--dataset", dataset,
                   "Where the dataset of netCDF or ASPECT inputs is written and found again (default: beside the first file, "
                   "e.g. spherical.raypc)");
    m_group = cmd.add_option_group("preprocessing", "For netCDF inputs: as raypc preprocess");
    preprocess.add(*m_group, false);
}

std::pair<SeriesInputs, preprocess::PreprocessOptions> SeriesFlags::resolve() const
{
    std::pair<SeriesInputs, preprocess::PreprocessOptions> result;
    mpi::together([&] {
        result.second = preprocess.toOptions(*m_group);
        result.first = resolveSeriesInputs(inputs, dataset, result.second.reader);
        result.second.timesMyr = result.first.timesMyr;
    });
    return result;
}

std::vector<fs::path> SeriesFlags::pair() const
{
    if (inputs.size() != 2 || !isDatasetDirectory(inputs[0]) || !isDatasetDirectory(inputs[1]))
        return {};
    if (!dataset.empty())
        fail("--dataset: only for netCDF inputs; '{}' and '{}' are datasets already", inputs[0], inputs[1]);
    return {fs::path(inputs[0]), fs::path(inputs[1])};
}

}  // namespace raypc::app

