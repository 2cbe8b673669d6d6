// Where the data of a netCDF classic file ends (CDF-1 classic, CDF-2 64-bit offset, CDF-5).
//
// netCDF-C opens a classic file whose data was cut short and reads the missing bytes as zeros
// without an error, and it does not tell where a variable's data begins. The header says it
// (every variable's `begin` offset), so the reader walks the header as the netCDF Classic
// Format Specification lays it out and compares the end of the last variable's data with the
// file's size.
#pragma once

#include <cstdint>
#include <istream>
#include <string>

namespace raypc::io {

// The number of bytes a classic file needs: the largest end of a variable's data (for record
// variables, of its last record), as the header at the start of `in` describes. `what` names
// the file in messages. Throws raypc::Error naming `what` when the stream does not start with
// a classic header, the header ends early or is malformed, or its sizes overflow 64 bits.
uint64_t classicDataEndBytes(std::istream& in, const std::string& what);

}  // namespace raypc::io
