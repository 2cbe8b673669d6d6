// Internal to raypc_io: a netCDF variable's values read into a field on the grid (netcdf_reader.h
// says what is missing and how values are unpacked): the file's order turned into the canonical one.
#pragma once

#include "io/netcdf_variables.h"

#include "grid/snapshot.h"

#include <string>
#include <vector>

namespace raypc::io::netcdf {

// netCDF converts integers to float exactly up to 16 bits; doubles and wider integers are read as
// double and converted here, so that a fill value beyond float (1e300) is recognised and a value
// beyond float is named rather than failing the whole read ("Numeric conversion not representable").
bool readsAsDouble(const NcFile& file, int varId);

// The buffers variables are read through in file order, reused from one variable to the next; only
// the one of the type a variable is read as holds memory while it is read.
struct FileOrderBuffers {
    std::vector<float> floats;
    std::vector<double> doubles;
};

// Variable `fileName` of `file`, where `layout` places it, read as the field `name` on h.grid in
// canonical order, with its units attribute: fill value, missing_value, NaN and Inf are missing,
// packed values unpacked (ValueRule). Throws raypc::Error naming the file and the variable for a value
// beyond float32 and, unless options.fillMissing (then each takes its radius shell's mean), for a
// missing value.
grid::Field readField(const NcFile& file, const OpenedHeader& h, const std::string& name, const std::string& fileName,
                const VariableLayout& layout, const ReaderOptions& options, FileOrderBuffers& buffers);

}  // namespace raypc::io::netcdf
