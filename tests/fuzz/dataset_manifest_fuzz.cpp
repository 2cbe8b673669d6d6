// libFuzzer target: bytes as the manifest (dataset.json) of a small real dataset, whose arrays stay
// beside it, to Dataset::open (every field, every array's size), then, when it opens, a
// load of every step and level, every variable's values, and the sample. Only raypc::Error may come
// out. The dataset (2 steps of an 8 x 5 x 8 synthetic grid, u16, 50 sample rows, no pathlines) is
// written once at start by the project's synth and preprocess, as corpus/dataset_manifest/valid.json
// was by `raypc synth --steps 2 --grid 8x5x8` and `raypc preprocess --sample-rows 50 --no-pathlines`.
#include "core/error.h"
#include "dataset/dataset.h"
#include "io/netcdf_reader.h"
#include "preprocess/preprocess.h"
#include "synth/synth.h"

#include <cstddef>
#include <cstdint>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <string>

namespace {

std::filesystem::path g_dir;

void removeDataset()
{
    std::error_code ec;
    std::filesystem::remove_all(g_dir, ec);
}

}  // namespace

extern "C" int LLVMFuzzerInitialize(int*, char***)
{
    std::string pattern = (std::filesystem::temp_directory_path() / "raypc-fuzz-manifest.XXXXXX").string();
    if (!::mkdtemp(pattern.data()))
        std::abort();
    g_dir = pattern;
    std::atexit(removeDataset);
    raypc::synth::SynthOptions synth;
    synth.steps = 2;
    synth.nLat = 8;
    synth.nR = 5;
    synth.nLon = 8;
    raypc::synth::writeSyntheticSeries(g_dir / "nc", synth);
    raypc::preprocess::PreprocessOptions options;
    options.quiet = true;
    options.sampleRows = 50;
    options.pathlines.enabled = false;
    raypc::preprocess::preprocess(raypc::io::listSnapshotFiles({g_dir / "nc"}), g_dir / "ds", options);
    return 0;
}

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size)
{
    const auto dir = g_dir / "ds";
    {
        std::ofstream out(dir / "dataset.json", std::ios::binary | std::ios::trunc);
        out.write(reinterpret_cast<const char*>(data), static_cast<std::streamsize>(size));
    }
    try {
        const auto dataset = raypc::dataset::Dataset::open(dir);
        for (size_t step = 0; step < dataset->steps().size(); ++step)
            for (size_t level = 0; level < dataset->levels().size(); ++level) {
                const auto volume = dataset->load(static_cast<int>(step), static_cast<int>(level));
                for (size_t var = 0; var < volume->variableCount(); ++var)
                    volume->values(var);
            }
        dataset->loadSample(0);
    } catch (const raypc::Error&) {
        // A refused manifest: the expected outcome for most inputs.
    }
    return 0;
}
