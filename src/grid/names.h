// The names of the variables the program derives or looks for, and the columns of the tables it
// writes that Python and the UI name too, as C++ constants generated from src/grid/names.json (the
// one table the UI and Python read as well): raypc::varname::k* and raypc::columns::k*.
// variable_names.h adds what the C++ code asks of the names.
#pragma once

#include <array>
#include <cstddef>
#include <string>

namespace raypc::columns {

// A column of a table the program writes: its name, the units of its values ("" for none or a
// count) and, for a value that some tables name with its units folded in, that name ("x_km" for x
// in km), else "".
struct TableColumn {
    const char* name;
    const char* units;
    const char* column;
};

}  // namespace raypc::columns

#include "grid/names_table.inc"

namespace raypc::columns {

// The names of `table` joined by commas: the header of a CSV file, without its line end.
template <std::size_t N>
std::string csvHeader(const std::array<TableColumn, N>& table)
{
    std::string header;
    for (const TableColumn& c : table)
        header += (header.empty() ? "" : ",") + std::string(c.name);
    return header;
}

}  // namespace raypc::columns
