// libFuzzer target: the netCDF reader on small classic files (docs/reliability.md).
//
// Each input is written to a file and read as `raypc preprocess` reads it: the classic header
// walk (truncation check), then the header, then the whole snapshot, with and without
// --fill-missing. Bad input must give raypc::Error; anything else (a crash, a sanitizer
// report, another exception, an allocation beyond libFuzzer's limit) is a finding.
// Only classic files (CDF-1/2/5): netCDF-4 files are HDF5, a parser of its own that this
// target does not aim at.
#include "core/error.h"
#include "io/netcdf_classic.h"
#include "io/netcdf_reader.h"

#include <unistd.h>

#include <cstddef>
#include <cstdint>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>

namespace {

// One file per fuzzing process, on a RAM disk where there is one.
std::filesystem::path inputPath()
{
    static const std::filesystem::path path = [] {
        const std::filesystem::path shm = "/dev/shm";
        const auto dir = std::filesystem::is_directory(shm) ? shm : std::filesystem::temp_directory_path();
        return dir / ("raypc-fuzz-" + std::to_string(::getpid()) + ".nc");
    }();
    return path;
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size)
{
    const std::string bytes(reinterpret_cast<const char*>(data), size);
    // The header walk on its own, also on what netCDF-C would refuse to open.
    try {
        std::istringstream in(bytes);
        raypc::io::classicDataEndBytes(in, "input");
    } catch (const raypc::Error&) {
    }
    if (size < 4 || bytes.compare(0, 3, "CDF") != 0)
        return 0;
    const auto path = inputPath();
    {
        std::ofstream out(path, std::ios::binary | std::ios::trunc);
        out.write(bytes.data(), static_cast<std::streamsize>(bytes.size()));
    }
    for (const bool fillMissing : {false, true}) {
        raypc::io::ReaderOptions options;
        options.fillMissing = fillMissing;
        try {
            raypc::io::readHeader(path, options);
            raypc::io::readSnapshot(path, options);
        } catch (const raypc::Error&) {
        }
    }
    // Also with the axes named explicitly and one variable mapped, as --lat-name and --map do.
    raypc::io::ReaderOptions named;
    named.latName = "lat";
    named.variables = {"temperature"};
    named.variableNames["temperature"] = "T";
    try {
        raypc::io::readSnapshot(path, named);
    } catch (const raypc::Error&) {
    }
    return 0;
}
