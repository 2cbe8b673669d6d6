#include "io/netcdf_classic.h"

#include "core/error.h"

#include <algorithm>
#include <array>
#include <vector>

namespace raypc::io {
namespace {

// Tags and sizes of the netCDF Classic Format Specification.
constexpr uint32_t kTagDimension = 0x0A, kTagVariable = 0x0B, kTagAttribute = 0x0C;

// Reads the header's big-endian fields; every read checks that the bytes are there, and nothing
// is allocated from a count the header claims (names and attribute values are skipped).
class HeaderCursor {
public:
    HeaderCursor(std::istream& in, const std::string& what) : m_in(in), m_what(what) {}

    uint64_t unsignedBytes(int n)
    {
        std::array<unsigned char, 8> b{};
        m_in.read(reinterpret_cast<char*>(b.data()), n);
        if (m_in.gcount() != n)
            fail("{}: truncated: the netCDF header ends at byte {}", m_what, m_offset + m_in.gcount());
        m_offset += n;
        uint64_t v = 0;
        for (int i = 0; i < n; ++i)
            v = v << 8 | b[i];
        return v;
    }
    void skip(uint64_t n)
    {
        while (n > 0) {
            const auto chunk = static_cast<std::streamsize>(std::min<uint64_t>(n, 1 << 20));
            m_in.ignore(chunk);
            if (m_in.gcount() != chunk)
                fail("{}: truncated: the netCDF header ends at byte {}", m_what, m_offset + m_in.gcount());
            m_offset += chunk;
            n -= chunk;
        }
    }
    uint64_t offset() const { return m_offset; }
    const std::string& what() const { return m_what; }

private:
    std::istream& m_in;
    const std::string& m_what;
    uint64_t m_offset = 0;
};

uint64_t checkedMul(uint64_t a, uint64_t b, const std::string& what)
{
    uint64_t r = 0;
    if (__builtin_mul_overflow(a, b, &r))
        fail("{}: the netCDF header describes more data than 2^64 bytes", what);
    return r;
}

uint64_t checkedAdd(uint64_t a, uint64_t b, const std::string& what)
{
    uint64_t r = 0;
    if (__builtin_add_overflow(a, b, &r))
        fail("{}: the netCDF header describes more data than 2^64 bytes", what);
    return r;
}

uint64_t paddedTo4(uint64_t n, const std::string& what) { return checkedAdd(n, 3, what) / 4 * 4; }

// Bytes of one value of an external type (1 byte .. 11 uint64).
uint64_t typeBytes(uint64_t type, const HeaderCursor& c)
{
    static constexpr std::array<uint64_t, 12> kBytes = {0, 1, 1, 2, 4, 4, 8, 1, 2, 4, 8, 8};
    if (type == 0 || type >= kBytes.size())
        fail("{}: malformed netCDF header: unknown type {} at byte {}", c.what(), type, c.offset());
    return kBytes[type];
}

struct Variable {
    std::vector<uint64_t> dims;  // dimension ids
    uint64_t typeBytes = 0;
    uint64_t begin = 0;
};

}  // namespace

uint64_t classicDataEndBytes(std::istream& in, const std::string& what)
{
    HeaderCursor c(in, what);
    const uint64_t magic = c.unsignedBytes(4);
    const uint64_t version = magic & 0xFF;
    if (magic >> 8 != 0x434446 || (version != 1 && version != 2 && version != 5))
        fail("{}: not a netCDF classic file (no CDF-1, CDF-2 or CDF-5 signature)", what);
    // CDF-5 widens counts and lengths to 64 bits; CDF-2 and CDF-5 widen data offsets.
    const int countBytes = version == 5 ? 8 : 4;
    const int offsetBytes = version == 1 ? 4 : 8;
    const uint64_t streaming = countBytes == 8 ? ~uint64_t(0) : 0xFFFFFFFFu;

    const uint64_t numRecords = c.unsignedBytes(countBytes);
    // A list is a tag and a count; an absent list is two zeros.
    auto listCount = [&](uint32_t expectedTag, const char* name) {
        const uint64_t tag = c.unsignedBytes(4);
        const uint64_t count = c.unsignedBytes(countBytes);
        if (tag == 0 && count == 0)
            return uint64_t(0);
        if (tag != expectedTag)
            fail("{}: malformed netCDF header: expected the {} list at byte {}", what, name, c.offset() - 4 - countBytes);
        return count;
    };
    auto skipName = [&] { c.skip(paddedTo4(c.unsignedBytes(countBytes), what)); };
    auto skipAttributes = [&] {
        const uint64_t n = listCount(kTagAttribute, "attribute");
        for (uint64_t a = 0; a < n; ++a) {
            skipName();
            const uint64_t bytes = typeBytes(c.unsignedBytes(4), c);
            c.skip(paddedTo4(checkedMul(c.unsignedBytes(countBytes), bytes, what), what));
        }
    };

    std::vector<uint64_t> dimLengths;  // 0: the record dimension
    for (uint64_t n = listCount(kTagDimension, "dimension"), d = 0; d < n; ++d) {
        skipName();
        dimLengths.push_back(c.unsignedBytes(countBytes));
    }
    skipAttributes();
    std::vector<Variable> vars;
    for (uint64_t n = listCount(kTagVariable, "variable"), v = 0; v < n; ++v) {
        skipName();
        Variable var;
        for (uint64_t nd = c.unsignedBytes(countBytes), d = 0; d < nd; ++d) {
            var.dims.push_back(c.unsignedBytes(countBytes));
            if (var.dims.back() >= dimLengths.size())
                fail("{}: malformed netCDF header: variable {} names dimension {} of {}", what, v, var.dims.back(),
                     dimLengths.size());
        }
        skipAttributes();
        var.typeBytes = typeBytes(c.unsignedBytes(4), c);
        c.unsignedBytes(countBytes);  // vsize: recomputed below, it saturates for large variables
        var.begin = c.unsignedBytes(offsetBytes);
        vars.push_back(std::move(var));
    }

    // Bytes of one variable (of one record, for a record variable: its first dim is the record dim).
    auto isRecord = [&](const Variable& v) { return !v.dims.empty() && dimLengths[v.dims[0]] == 0; };
    auto valueBytes = [&](const Variable& v) {
        uint64_t bytes = v.typeBytes;
        for (size_t d = isRecord(v) ? 1 : 0; d < v.dims.size(); ++d)
            bytes = checkedMul(bytes, dimLengths[v.dims[d]], what);
        return bytes;
    };
    // One record holds every record variable's slice, each padded to 4 bytes unless it is the only one.
    uint64_t recordBytes = 0, recordVars = 0;
    for (const auto& v : vars)
        if (isRecord(v)) {
            recordBytes = checkedAdd(recordBytes, paddedTo4(valueBytes(v), what), what);
            ++recordVars;
        }
    if (recordVars == 1)
        for (const auto& v : vars)
            if (isRecord(v))
                recordBytes = valueBytes(v);

    uint64_t end = c.offset();
    for (const auto& v : vars) {
        uint64_t last = checkedAdd(v.begin, valueBytes(v), what);
        if (isRecord(v)) {
            if (numRecords == 0 || numRecords == streaming)
                continue;  // no records, or a count only the file's size gives
            last = checkedAdd(last, checkedMul(numRecords - 1, recordBytes, what), what);
        }
        end = std::max(end, last);
    }
    return end;
}

}  // namespace raypc::io
