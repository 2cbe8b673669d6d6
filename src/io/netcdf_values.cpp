// A netCDF variable's values read into a field (netcdf_values.h): its rules for missing and packed
// values (CF conventions, section 8.1), and the file's order turned into the canonical one in parallel
// over lat rows.
#include "io/netcdf_values.h"

#include <fmt/format.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <mutex>
#include <numeric>
#include <optional>
#include <type_traits>

namespace raypc::io::netcdf {
namespace {

// One step of the variable in file order into `out`, netCDF converting its type to float or double.
void readValues(const NcFile& file, const VariableLayout& layout, const std::string& fileName, float* out)
{
    if (const int status = nc_get_vara_float(file.id(), layout.id, layout.start.data(), layout.count.data(), out);
        status != NC_NOERR)
        fail("{}: {}: cannot read the values ({}); the file may be truncated or damaged", file.path().string(),
             fileName, errorText(status));
}

void readValues(const NcFile& file, const VariableLayout& layout, const std::string& fileName, double* out)
{
    if (const int status = nc_get_vara_double(file.id(), layout.id, layout.start.data(), layout.count.data(), out);
        status != NC_NOERR)
        fail("{}: {}: cannot read the values ({}); the file may be truncated or damaged", file.path().string(),
             fileName, errorText(status));
}

// How a variable's stored numbers become values (CF conventions, section 8.1, and the NUG's
// _Unsigned): which are missing, how they are unpacked. Comparisons are on the stored numbers.
struct ValueRule {
    std::optional<double> fill;  // _FillValue, or without one netCDF's default fill value of the type
    bool fillIsDefault = false;
    std::optional<double> missing;  // missing_value
    double scale = 1.0, offset = 0.0;
    // For an integer variable with _Unsigned = "true": 2^bits, added to negative stored numbers.
    double unsignedWrap = 0.0;

    bool packed() const { return scale != 1.0 || offset != 0.0; }
    bool isFill(double stored) const { return fill && stored == *fill; }
};

ValueRule valueRule(const NcFile& file, int varId)
{
    ValueRule rule;
    nc_type type = 0;
    file.check(nc_inq_vartype(file.id(), varId, &type), "reading a variable type");
    const auto isUnsigned = file.textAttribute(varId, "_Unsigned");
    if (isUnsigned && (*isUnsigned == "true" || *isUnsigned == "True" || *isUnsigned == "TRUE")) {
        switch (type) {
        case NC_BYTE: rule.unsignedWrap = 0x1p8; break;
        case NC_SHORT: rule.unsignedWrap = 0x1p16; break;
        case NC_INT: rule.unsignedWrap = 0x1p32; break;
        case NC_INT64: rule.unsignedWrap = 0x1p64; break;
        default: break;
        }
    }
    // A fill or missing value given as the unsigned number (65535) matches the stored one (-1).
    auto stored = [&](std::optional<double> v) {
        if (v && rule.unsignedWrap > 0 && *v >= rule.unsignedWrap / 2)
            *v -= rule.unsignedWrap;
        return v;
    };
    rule.fill = stored(file.numberAttribute(varId, "_FillValue"));
    if (!rule.fill) {
        rule.fill = defaultFillValue(file, varId);
        rule.fillIsDefault = rule.fill.has_value();
    }
    rule.missing = stored(file.numberAttribute(varId, "missing_value"));
    rule.scale = file.numberAttribute(varId, "scale_factor").value_or(1.0);
    rule.offset = file.numberAttribute(varId, "add_offset").value_or(0.0);
    return rule;
}

// What turning one variable into canonical order found.
struct ConversionReport {
    std::vector<size_t> missingPerShell;
    size_t firstMissing = SIZE_MAX;  // canonical index, for the message
    double firstMissingValue = 0;
    size_t firstBeyondFloat = SIZE_MAX;  // canonical index of the first value beyond float32
    double beyondFloatValue = 0;
};

// A fill or missing value as the buffer's type T holds it: none when T cannot hold it (a
// missing_value of 1e300 on a float variable matches nothing).
template <typename T>
std::optional<T> asStored(std::optional<double> v)
{
    if (!v || (std::isfinite(*v) && std::abs(*v) > double(std::numeric_limits<T>::max())))
        return std::nullopt;
    return static_cast<T>(*v);
}

// Reorders `buffer` (one variable in the file's order) into canonical order in `out`, marking missing
// values (fill value, missing_value, NaN, Inf) as NaN, unpacking the others, and noting values that
// float32 cannot hold.
template <typename T>
ConversionReport toCanonical(const std::vector<T>& buffer, const OpenedHeader& h, const VariableLayout& layout,
                             const ValueRule& rule, std::vector<float>& out)
{
    const auto fill = asStored<T>(rule.fill), missing = asStored<T>(rule.missing);
    const auto& stride = layout.stride;
    const auto& latIdx = h.axes[kLat].fileIndex;
    const auto& rIdx = h.axes[kR].fileIndex;
    const auto& lonIdx = h.axes[kLon].fileIndex;
    const grid::SphericalGrid& grid = h.grid;
    const size_t nR = grid.nR(), nLon = grid.nLon();
    const bool convert = rule.packed() || rule.unsignedWrap > 0;
    constexpr double kFloatMax = std::numeric_limits<float>::max();
    ConversionReport report;
    report.missingPerShell.assign(nR, 0);
    // Float values kept as they are, whose rows the file holds whole and in order (lon contiguous,
    // no padding): a row without a missing value is copied as it is, found by one loop without a
    // branch, which the compiler vectorises; a row with one goes value by value as any other.
    bool copyRows = std::is_same_v<T, float> && !convert && stride[kLon] == 1 && lonIdx[0] != kNoData;
    for (size_t iLon = 0; copyRows && iLon < nLon; ++iLon)
        copyRows = lonIdx[iLon] == lonIdx[0] + iLon;
    // NaN: never equal, so an absent fill or missing value matches nothing.
    const float fillOrNaN = fill ? float(*fill) : std::numeric_limits<float>::quiet_NaN();
    const float missingOrNaN = missing ? float(*missing) : std::numeric_limits<float>::quiet_NaN();
    std::mutex reportMutex;
    tbb::parallel_for(size_t(0), grid.nLat(), [&](size_t iLat) {
        ConversionReport local;
        local.missingPerShell.assign(nR, 0);
        for (size_t iR = 0; iR < nR; ++iR) {
            float* row = out.data() + grid.index(iLat, iR, 0);
            if (latIdx[iLat] == kNoData) {
                std::fill(row, row + nLon, std::numeric_limits<float>::quiet_NaN());
                continue;
            }
            const size_t base = latIdx[iLat] * stride[kLat] + rIdx[iR] * stride[kR];
            if (copyRows) {
                const T* from = buffer.data() + base + lonIdx[0];
                int special = 0;
                for (size_t iLon = 0; iLon < nLon; ++iLon) {
                    const float v = float(from[iLon]);
                    special |= (v == fillOrNaN) | (v == missingOrNaN) | !(std::abs(v) <= std::numeric_limits<float>::max());
                }
                if (!special) {
                    std::copy(from, from + nLon, row);
                    continue;
                }
            }
            for (size_t iLon = 0; iLon < nLon; ++iLon) {
                if (lonIdx[iLon] == kNoData) {
                    row[iLon] = std::numeric_limits<float>::quiet_NaN();
                    continue;
                }
                const T v = buffer[base + lonIdx[iLon] * stride[kLon]];
                if ((fill && v == *fill) || (missing && v == *missing) || !std::isfinite(v)) {
                    if (local.firstMissing == SIZE_MAX) {
                        local.firstMissing = grid.index(iLat, iR, iLon);
                        local.firstMissingValue = double(v);
                    }
                    row[iLon] = std::numeric_limits<float>::quiet_NaN();
                    ++local.missingPerShell[iR];
                    continue;
                }
                double value = double(v);
                if (convert) {
                    if (value < 0 && rule.unsignedWrap > 0)
                        value += rule.unsignedWrap;
                    value = value * rule.scale + rule.offset;
                }
                if (std::is_same_v<T, float> && !convert) {
                    row[iLon] = float(v);
                } else if (std::abs(value) <= kFloatMax) {
                    row[iLon] = static_cast<float>(value);
                } else {
                    if (local.firstBeyondFloat == SIZE_MAX) {
                        local.firstBeyondFloat = grid.index(iLat, iR, iLon);
                        local.beyondFloatValue = value;
                    }
                    row[iLon] = std::numeric_limits<float>::quiet_NaN();
                }
            }
        }
        std::lock_guard l(reportMutex);
        for (size_t iR = 0; iR < nR; ++iR)
            report.missingPerShell[iR] += local.missingPerShell[iR];
        if (local.firstMissing < report.firstMissing) {
            report.firstMissing = local.firstMissing;
            report.firstMissingValue = local.firstMissingValue;
        }
        if (local.firstBeyondFloat < report.firstBeyondFloat) {
            report.firstBeyondFloat = local.firstBeyondFloat;
            report.beyondFloatValue = local.beyondFloatValue;
        }
    });
    return report;
}


// Reads the variable into `buffer` in file order, releasing `other` first so that only one buffer
// holds memory at a time (what readSnapshot checks fits), and turns it into canonical order in `out`.
template <typename T, typename Other>
ConversionReport readThrough(std::vector<T>& buffer, std::vector<Other>& other, const NcFile& file,
                             const OpenedHeader& h, const VariableLayout& layout, const std::string& fileName,
                             const ValueRule& rule, std::vector<float>& out)
{
    std::vector<Other>().swap(other);
    buffer.resize(h.fileCount());
    readValues(file, layout, fileName, buffer.data());
    return toCanonical(buffer, h, layout, rule, out);
}

// The grid points that the file holds (those that pad a regional grid aside).
size_t dataPoints(const OpenedHeader& h)
{
    size_t n = 1;
    for (const auto& axis : h.axes)
        n *= size_t(std::count_if(axis.fileIndex.begin(), axis.fileIndex.end(), [](size_t i) { return i != kNoData; }));
    return n;
}

}  // namespace

bool readsAsDouble(const NcFile& file, int varId)
{
    nc_type type = 0;
    file.check(nc_inq_vartype(file.id(), varId, &type), "reading a variable type");
    return type == NC_DOUBLE || type == NC_INT || type == NC_UINT || type == NC_INT64 || type == NC_UINT64;
}

grid::Field readField(const NcFile& file, const OpenedHeader& h, const std::string& name, const std::string& fileName,
                const VariableLayout& layout, const ReaderOptions& options, FileOrderBuffers& buffers)
{
    const size_t n = h.grid.cellCount();
    const ValueRule rule = valueRule(file, layout.id);
    grid::Field field;
    field.name = name;
    field.units = file.textAttribute(layout.id, "units").value_or("");
    field.values.resize(n);
    const ConversionReport report =
        readsAsDouble(file, layout.id)
            ? readThrough(buffers.doubles, buffers.floats, file, h, layout, fileName, rule, field.values)
            : readThrough(buffers.floats, buffers.doubles, file, h, layout, fileName, rule, field.values);
    if (report.firstBeyondFloat < n)
        fail("{}: {}: the value {:g} at {} is beyond float32's range (±{:g}), in which RayPC keeps values; if it "
             "marks missing cells, give it as the variable's _FillValue or missing_value",
             file.path().string(), fileName, report.beyondFloatValue,
             grid::describeGridPoint(h.grid, report.firstBeyondFloat), double(std::numeric_limits<float>::max()));
    const size_t missing =
        std::accumulate(report.missingPerShell.begin(), report.missingPerShell.end(), size_t(0));
    if (missing > 0 && missing == dataPoints(h)) {
        const double first = report.firstMissingValue;
        fail("{}: {}: every value of the step is missing (the first, at {}, is {})", file.path().string(), fileName,
             grid::describeGridPoint(h.grid, report.firstMissing),
             !std::isfinite(first) ? fmt::format("{}", first)
             : rule.isFill(first)  ? fmt::format("{} {:g}",
                                                  rule.fillIsDefault ? "netCDF's default fill value (never written)"
                                                                     : "the _FillValue",
                                                  *rule.fill)
                                   : fmt::format("missing_value {:g}", *rule.missing));
    }
    // Missing values stay missing (NaN) unless the user asks to fill them; points that pad a
    // regional grid are never filled.
    if (missing > 0 && options.fillMissing)
        grid::fillMissingByShellMean(h.grid, field.values, fmt::format("{}: {}", file.path().string(), fileName),
                                     [&](size_t iLat, size_t iLon) { return h.grid.holdsData(iLat, iLon); });
    return field;
}

}  // namespace raypc::io::netcdf
