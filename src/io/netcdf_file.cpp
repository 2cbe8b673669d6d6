// A netCDF file open for reading (netcdf_file.h): the checks before netCDF-C opens it, and the
// values it gives cells never written.
#include "io/netcdf_file.h"

#include "io/netcdf_classic.h"

#include <hdf5.h>

#include <fstream>

namespace raypc::io::netcdf {
namespace {

// netCDF-C reads past the end of a truncated classic file without an error (the missing bytes
// come back as zeros), and allocates what a header claims (a variable of 10^9 dimensions) before
// reading it. So a classic file's header is walked first, allocating nothing it claims, and the
// file's size compared with where the header says the data ends.
void checkClassicFileSize(const std::filesystem::path& path)
{
    std::ifstream in(path, std::ios::binary);
    if (!in)
        fail("{}: cannot open for reading", path.string());
    char magic[4] = {};
    in.read(magic, 4);
    if (in.gcount() != 4 || std::string_view(magic, 3) != "CDF")
        return;  // netCDF-4 (HDF5) or not netCDF: nc_open says which
    in.seekg(0);
    const uint64_t needed = classicDataEndBytes(in, path.string());
    std::error_code ec;
    const uintmax_t size = std::filesystem::file_size(path, ec);
    if (ec)
        fail("{}: cannot read the file size: {}", path.string(), ec.message());
    if (size < needed)
        fail("{}: truncated: the file has {} bytes, its header places data up to byte {}", path.string(), size,
             needed);
}

// HDF5 prints its error stack (HDF5-DIAG lines) for every failed call, also for the calls netCDF-C
// makes expecting them to fail while it opens a netCDF-4 file. netCDF-C switches that printing off
// when it initialises, but in a thread-safe HDF5 (Debian's) the setting is per thread: a thread
// other than the first to open a file (`raypc serve FILES` preprocesses on a background thread)
// printed hundreds of stacks. So every thread switches it off for itself before it opens a file.
void silenceHdf5ErrorStack()
{
    thread_local bool silenced = false;
    if (!silenced) {
        H5Eset_auto2(H5E_DEFAULT, nullptr, nullptr);
        silenced = true;
    }
}

}  // namespace

std::mutex& netcdfMutex()
{
    static std::mutex m;
    return m;
}

NcFile::NcFile(const std::filesystem::path& path) : m_path(path)
{
    std::error_code ec;
    if (!std::filesystem::exists(path, ec))
        fail("{}: no such file", path.string());
    if (std::filesystem::is_directory(path, ec))
        fail("{}: is a directory, expected a netCDF file", path.string());
    checkClassicFileSize(path);
    silenceHdf5ErrorStack();
    const int status = nc_open(path.c_str(), NC_NOWRITE, &m_id);
    if (status != NC_NOERR) {
        if (status == NC_ENOTNC)
            fail("{}: not a netCDF file (or an unsupported variant)", path.string());
        fail("{}: cannot open as netCDF: {}", path.string(), errorText(status));
    }
}

std::optional<double> defaultFillValue(const NcFile& file, int varId)
{
    nc_type type = 0;
    file.check(nc_inq_vartype(file.id(), varId, &type), "reading a variable type");
    switch (type) {
    case NC_BYTE: return NC_FILL_BYTE;
    case NC_UBYTE: return NC_FILL_UBYTE;
    case NC_SHORT: return NC_FILL_SHORT;
    case NC_USHORT: return NC_FILL_USHORT;
    case NC_INT: return NC_FILL_INT;
    case NC_UINT: return NC_FILL_UINT;
    case NC_INT64: return static_cast<double>(NC_FILL_INT64);
    case NC_UINT64: return static_cast<double>(NC_FILL_UINT64);
    case NC_FLOAT: return NC_FILL_FLOAT;
    case NC_DOUBLE: return NC_FILL_DOUBLE;
    default: return std::nullopt;
    }
}

}  // namespace raypc::io::netcdf
