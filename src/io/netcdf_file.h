// Internal to raypc_io: a netCDF file open for reading, as the netCDF reader's files share it
// (netcdf_reader.h): the lock every call into netCDF-C holds, the file's variables, dims and
// attributes, and what netCDF gives a cell never written.
//
// Thread safety: netCDF-C is not thread-safe; hold netcdfMutex() while a file is open.
#pragma once

#include "core/error.h"
#include "core/strings.h"

#include <netcdf.h>

#include <algorithm>
#include <cctype>
#include <filesystem>
#include <mutex>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

namespace raypc::io::netcdf {

// netCDF-C is not thread-safe; every call into it holds this lock.
std::mutex& netcdfMutex();

inline std::string errorText(int status) { return nc_strerror(status); }

// Attribute text (units, standard names) compares without regard to case.
inline std::string lowerCase(std::string text)
{
    std::transform(text.begin(), text.end(), text.begin(), [](unsigned char c) { return char(std::tolower(c)); });
    return text;
}

// An open file that closes itself. Opening checks first that the file is there, that a classic
// file is as long as its header says, and silences HDF5's error stack on this thread; throws
// raypc::Error naming the file when it cannot be opened as netCDF.
class NcFile {
public:
    explicit NcFile(const std::filesystem::path& path);
    ~NcFile() { nc_close(m_id); }
    NcFile(const NcFile&) = delete;
    NcFile& operator=(const NcFile&) = delete;

    int id() const { return m_id; }
    const std::filesystem::path& path() const { return m_path; }
    std::string name() const { return m_path.filename().string(); }

    void check(int status, std::string_view what) const
    {
        if (status != NC_NOERR)
            fail("{}: {}: {}", m_path.string(), what, errorText(status));
    }

    std::optional<int> findVar(const std::string& name) const
    {
        int varId = -1;
        if (nc_inq_varid(m_id, name.c_str(), &varId) != NC_NOERR)
            return std::nullopt;
        return varId;
    }

    std::string varName(int varId) const
    {
        char name[NC_MAX_NAME + 1] = {};
        check(nc_inq_varname(m_id, varId, name), "reading a variable name");
        return name;
    }

    std::vector<int> varDims(int varId) const
    {
        int nDims = 0;
        check(nc_inq_varndims(m_id, varId, &nDims), "reading variable dims");
        std::vector<int> dims(nDims);
        check(nc_inq_vardimid(m_id, varId, dims.data()), "reading variable dims");
        return dims;
    }

    std::string dimName(int dimId) const
    {
        char name[NC_MAX_NAME + 1] = {};
        check(nc_inq_dimname(m_id, dimId, name), "reading a dimension name");
        return name;
    }

    size_t dimLength(int dimId) const
    {
        size_t n = 0;
        check(nc_inq_dimlen(m_id, dimId, &n), "reading a dimension length");
        return n;
    }

    // A text attribute, NC_CHAR (classic files) or NC_STRING (netCDF-4 writes these, e.g. Python's
    // netCDF4 for str values); the first string of an NC_STRING array. Trimmed of blanks and NULs.
    std::optional<std::string> textAttribute(int varId, const char* name) const
    {
        nc_type type;
        size_t len = 0;
        if (nc_inq_att(m_id, varId, name, &type, &len) != NC_NOERR)
            return std::nullopt;
        std::string value;
        if (type == NC_CHAR) {
            value.resize(len);
            check(nc_get_att_text(m_id, varId, name, value.data()), std::string("reading attribute ") + name);
        } else if (type == NC_STRING) {
            if (len == 0)
                return std::string();
            std::vector<char*> strings(len, nullptr);
            check(nc_get_att_string(m_id, varId, name, strings.data()), std::string("reading attribute ") + name);
            value = strings[0] ? strings[0] : "";
            nc_free_string(len, strings.data());
        } else {
            return std::nullopt;
        }
        while (!value.empty() && value.back() == '\0')
            value.pop_back();
        return trim(value);
    }

    std::optional<double> numberAttribute(int varId, const char* name) const
    {
        nc_type type;
        size_t len = 0;
        if (nc_inq_att(m_id, varId, name, &type, &len) != NC_NOERR || len < 1 || type == NC_CHAR ||
            type == NC_STRING)
            return std::nullopt;
        std::vector<double> values(len);
        check(nc_get_att_double(m_id, varId, name, values.data()), std::string("reading attribute ") + name);
        return values[0];
    }

    std::string formatName() const
    {
        int fmt = 0;
        check(nc_inq_format(m_id, &fmt), "reading the format");
        switch (fmt) {
        case NC_FORMAT_CLASSIC: return "classic";
        case NC_FORMAT_64BIT_OFFSET: return "64-bit offset";
        case NC_FORMAT_CDF5: return "CDF-5";
        case NC_FORMAT_NETCDF4: return "netCDF-4";
        case NC_FORMAT_NETCDF4_CLASSIC: return "netCDF-4 classic model";
        default: return "unknown";
        }
    }

private:
    std::filesystem::path m_path;
    int m_id = -1;
};

// The value netCDF gives a cell of variable `varId` that was never written when the variable
// has no _FillValue (NC_FILL_FLOAT etc.), or nothing for a type without one.
std::optional<double> defaultFillValue(const NcFile& file, int varId);

}  // namespace raypc::io::netcdf
