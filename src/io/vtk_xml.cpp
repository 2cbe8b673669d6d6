#include "io/vtk_xml.h"

#include "core/atomic_file.h"
#include "core/error.h"

#include <fmt/format.h>
#include <pugixml.hpp>
#include <zlib.h>

#include <algorithm>
#include <array>
#include <bit>
#include <charconv>
#include <cmath>
#include <cstring>
#include <limits>
#include <map>
#include <string_view>
#include <type_traits>

namespace raypc::io::vtk {

namespace fs = std::filesystem;

const PointArray* Piece::find(const std::string& name) const
{
    for (const auto& a : pointData)
        if (a.name == name)
            return &a;
    return nullptr;
}

int cellDegree(CellType type, int64_t count)
{
    switch (type) {
    case CellType::Tetra: return count == 4 ? 1 : 0;
    case CellType::Hexahedron: return count == 8 ? 1 : 0;
    case CellType::Wedge: return count == 6 ? 1 : 0;
    case CellType::LagrangeHexahedron:
        for (int p = 1; p <= 10; ++p)
            if (int64_t(p + 1) * (p + 1) * (p + 1) == count)
                return p;
        return 0;
    }
    return 0;
}

namespace {

// ---- what an array's bytes are -------------------------------------------------------------

enum class Scalar { Int8, UInt8, Int16, UInt16, Int32, UInt32, Int64, UInt64, Float32, Float64 };

struct ScalarInfo {
    const char* name;
    Scalar type;
    size_t size;
    bool integer;
};

constexpr ScalarInfo kScalars[] = {
    {"Int8", Scalar::Int8, 1, true},        {"UInt8", Scalar::UInt8, 1, true},
    {"Int16", Scalar::Int16, 2, true},      {"UInt16", Scalar::UInt16, 2, true},
    {"Int32", Scalar::Int32, 4, true},      {"UInt32", Scalar::UInt32, 4, true},
    {"Int64", Scalar::Int64, 8, true},      {"UInt64", Scalar::UInt64, 8, true},
    {"Float32", Scalar::Float32, 4, false}, {"Float64", Scalar::Float64, 8, false},
};

// What every array of one file shares: its name for messages, and how its binary data is laid out.
struct FileContext {
    std::string file;
    bool bigEndian = false;
    size_t headerSize = 4;  // header_type UInt32 or UInt64
    bool zlib = false;      // compressor="vtkZLibDataCompressor"
    // The bytes after AppendedData's '_' (raw), or its base64 text.
    std::string_view appended;
    bool appendedBase64 = false;
};

// ---- base64, decoded a quantum (4 characters) at a time ------------------------------------
// VTK encodes an array's header and its data either as one base64 stream or as two, each padded;
// decoding quantum by quantum yields the same bytes for both, so one decoder reads every writer.

int base64Value(char c)
{
    static const auto table = [] {
        std::array<int8_t, 256> t{};
        t.fill(-1);
        for (int i = 0; i < 26; ++i)
            t[size_t('A' + i)] = int8_t(i), t[size_t('a' + i)] = int8_t(26 + i);
        for (int i = 0; i < 10; ++i)
            t[size_t('0' + i)] = int8_t(52 + i);
        t[size_t('+')] = 62, t[size_t('/')] = 63;
        return t;
    }();
    return table[uint8_t(c)];
}

// The bytes of one array, read as far as they are needed: from raw bytes, or decoding base64 text.
class ByteSource {
public:
    ByteSource(std::string_view data, bool base64, const std::string& what) : m_in(data), m_base64(base64), m_what(what)
    {
    }

    // At least `total` bytes from the start, or an error saying the data ends early.
    std::string_view need(size_t total)
    {
        if (!m_base64) {
            if (m_in.size() < total)
                fail("{}: data ends after {} of {} bytes (truncated file?)", m_what, m_in.size(), total);
            return m_in.substr(0, total);
        }
        // Room for what is asked, but never more than the rest of the input can decode to: a header
        // claiming gigabytes in a small file ends with "data ends", not with that allocation.
        const size_t decodable = m_out.size() + (m_in.size() - m_pos) / 4 * 3 + 3;
        if (m_out.capacity() < std::min(total, decodable))
            m_out.reserve(std::min(std::max(total, 2 * m_out.capacity()), decodable));
        // The common case first: whole quanta of plain base64 characters, decoded four at a time.
        while (m_out.size() + 3 <= total && m_pos + 4 <= m_in.size()) {
            const int a = base64Value(m_in[m_pos]), b = base64Value(m_in[m_pos + 1]),
                      c = base64Value(m_in[m_pos + 2]), d = base64Value(m_in[m_pos + 3]);
            if ((a | b | c | d) < 0)
                break;  // whitespace, padding, the end or a bad character: the careful loop below
            const uint32_t bits = uint32_t(a) << 18 | uint32_t(b) << 12 | uint32_t(c) << 6 | uint32_t(d);
            const char bytes[3] = {char(bits >> 16), char(bits >> 8 & 0xff), char(bits & 0xff)};
            m_out.append(bytes, 3);
            m_pos += 4;
        }
        while (m_out.size() < total) {
            char quad[4];
            int n = 0;
            while (n < 4 && m_pos < m_in.size()) {
                const char c = m_in[m_pos++];
                if (c == ' ' || c == '\n' || c == '\r' || c == '\t')
                    continue;
                if (c == '<')  // the end of the element (or of AppendedData)
                    break;
                quad[n++] = c;
            }
            if (n == 0)
                fail("{}: data ends after {} of {} bytes (truncated file?)", m_what, m_out.size(), total);
            if (n < 4)
                fail("{}: base64 data ends inside a quantum (truncated file?)", m_what);
            int v[4];
            int valid = 4;
            for (int i = 0; i < 4; ++i) {
                if (quad[i] == '=' && i >= 2) {
                    v[i] = 0;
                    valid = std::min(valid, i);
                    continue;
                }
                v[i] = base64Value(quad[i]);
                if (v[i] < 0 || i >= valid)
                    fail("{}: not base64 data (character '{}')", m_what, quad[i] == '=' ? std::string("=")
                                                                                             : std::string(1, quad[i]));
            }
            const uint32_t bits = uint32_t(v[0]) << 18 | uint32_t(v[1]) << 12 | uint32_t(v[2]) << 6 | uint32_t(v[3]);
            m_out.push_back(char(bits >> 16));
            if (valid >= 3)
                m_out.push_back(char(bits >> 8 & 0xff));
            if (valid == 4)
                m_out.push_back(char(bits & 0xff));
        }
        return std::string_view(m_out).substr(0, total);
    }

private:
    std::string_view m_in;
    bool m_base64;
    const std::string& m_what;
    size_t m_pos = 0;
    std::string m_out;
};

uint64_t readUnsigned(const char* p, size_t size, bool bigEndian)
{
    uint64_t v = 0;
    for (size_t i = 0; i < size; ++i) {
        const uint8_t b = uint8_t(p[bigEndian ? i : size - 1 - i]);
        v = v << 8 | b;
    }
    return v;
}

// The array's uncompressed bytes (in the file's byte order), `expectedBytes` of them.
std::string decodeBinary(ByteSource& source, const FileContext& ctx, uint64_t expectedBytes, const std::string& what)
{
    const size_t h = ctx.headerSize;
    if (!ctx.zlib) {
        const uint64_t n = readUnsigned(source.need(h).data(), h, ctx.bigEndian);
        if (n != expectedBytes)
            fail("{}: the data block holds {} bytes, expected {}", what, n, expectedBytes);
        return std::string(source.need(h + n).substr(h));
    }
    // vtkZLibDataCompressor: [blocks, block size, last block's size, compressed size of each block],
    // then the compressed blocks one after the other.
    const std::string_view head = source.need(3 * h);
    const uint64_t blocks = readUnsigned(head.data(), h, ctx.bigEndian);
    const uint64_t blockSize = readUnsigned(head.data() + h, h, ctx.bigEndian);
    const uint64_t lastSize = readUnsigned(head.data() + 2 * h, h, ctx.bigEndian);
    const uint64_t lastBytes = lastSize == 0 ? blockSize : lastSize;
    if (blocks > 0 && blockSize == 0)
        fail("{}: the compressed data's header gives {} blocks of 0 bytes each (corrupt header?)", what, blocks);
    if (blocks == 0 ? expectedBytes != 0
                    : (lastBytes > blockSize || blockSize == 0 || blocks - 1 > expectedBytes / blockSize ||
                       (blocks - 1) * blockSize + lastBytes != expectedBytes))
        fail("{}: compressed blocks of {} bytes ({} blocks of {}, the last {}), expected {} bytes", what,
             blocks == 0 ? 0 : (blocks - 1) * blockSize + lastBytes, blocks, blockSize, lastBytes, expectedBytes);
    const std::string_view sizes = source.need((3 + blocks) * h).substr(3 * h);
    uint64_t compressedTotal = 0;
    std::vector<uint64_t> compressed(blocks);
    for (uint64_t b = 0; b < blocks; ++b) {
        compressed[b] = readUnsigned(sizes.data() + b * h, h, ctx.bigEndian);
        if (compressed[b] > std::numeric_limits<uint32_t>::max() * uint64_t(2))
            fail("{}: compressed block {} claims {} bytes", what, b, compressed[b]);
        compressedTotal += compressed[b];
    }
    // zlib expands at most about 1032:1: a header claiming more is corrupt (checked before allocating).
    if (expectedBytes / 1032 > compressedTotal + blocks)
        fail("{}: {} compressed bytes cannot hold {} bytes (corrupt header?)", what, compressedTotal, expectedBytes);
    const std::string_view all = source.need((3 + blocks) * h + compressedTotal).substr((3 + blocks) * h);
    std::string out(expectedBytes, '\0');
    uint64_t in = 0;
    for (uint64_t b = 0; b < blocks; ++b) {
        uLongf outLen = uLongf(b + 1 == blocks ? lastBytes : blockSize);
        const uLongf want = outLen;
        const int rc = uncompress(reinterpret_cast<Bytef*>(out.data() + b * blockSize), &outLen,
                                  reinterpret_cast<const Bytef*>(all.data() + in), uLong(compressed[b]));
        if (rc != Z_OK || outLen != want)
            fail("{}: zlib block {} of {} does not decompress ({}; corrupt file?)", what, b + 1, blocks,
                 rc == Z_OK ? fmt::format("{} of {} bytes", outLen, want) : std::string(zError(rc)));
        in += compressed[b];
    }
    return out;
}

template <typename T>
T convertOne(const char* p, Scalar type, bool bigEndian)
{
    const auto load = [&](auto zero) {
        using S = decltype(zero);
        uint8_t b[sizeof(S)];
        std::memcpy(b, p, sizeof(S));
        if (bigEndian != (std::endian::native == std::endian::big))
            std::reverse(b, b + sizeof(S));
        S v;
        std::memcpy(&v, b, sizeof(S));
        return v;
    };
    switch (type) {
    case Scalar::Int8: return T(load(int8_t{}));
    case Scalar::UInt8: return T(load(uint8_t{}));
    case Scalar::Int16: return T(load(int16_t{}));
    case Scalar::UInt16: return T(load(uint16_t{}));
    case Scalar::Int32: return T(load(int32_t{}));
    case Scalar::UInt32: return T(load(uint32_t{}));
    case Scalar::Int64: return T(load(int64_t{}));
    case Scalar::UInt64: return T(load(uint64_t{}));
    case Scalar::Float32: return T(load(float{}));
    case Scalar::Float64: return T(load(double{}));
    }
    return T{};
}

std::string excerpt(std::string_view text)
{
    std::string s(text.substr(0, 40));
    std::replace_if(s.begin(), s.end(), [](char c) { return c == '\n' || c == '\r' || c == '\t'; }, ' ');
    return text.size() > 40 ? s + "…" : s;
}

// An attribute that holds a whole number (a count, an offset): digits only, or `fallback` when the
// attribute is absent. pugixml's as_llong reads "abc" as 0 and "-1" as a huge unsigned count.
uint64_t wholeNumber(const pugi::xml_attribute& a, uint64_t fallback, const std::string& file, const std::string& what)
{
    if (!a)
        return fallback;
    const std::string text = a.as_string();
    uint64_t value = 0;
    const auto [end, ec] = std::from_chars(text.data(), text.data() + text.size(), value);
    if (text.empty() || ec != std::errc() || end != text.data() + text.size())
        fail("{}: {} \"{}\", expected a whole number", file, what, excerpt(text));
    return value;
}

// A DataArray's `count` values (tuples × components) as T. Integer destinations take integer types
// only; float destinations any type.
template <typename T>
std::vector<T> readArray(const pugi::xml_node& node, uint64_t count, const FileContext& ctx, const std::string& what)
{
    const std::string typeName = node.attribute("type").as_string();
    const ScalarInfo* info = nullptr;
    for (const auto& s : kScalars)
        if (typeName == s.name)
            info = &s;
    if (!info)
        fail("{}: {}: type \"{}\", expected one of Int8 … UInt64, Float32, Float64", ctx.file, what, excerpt(typeName));
    if (std::is_integral_v<T> && !info->integer)
        fail("{}: {}: type {}, expected an integer type", ctx.file, what, typeName);
    const std::string format = node.attribute("format").as_string();
    const std::string label = fmt::format("{}: {}", ctx.file, what);
    std::vector<T> out;
    if (format == "ascii") {
        const char* p = node.child_value();
        out.reserve(std::min<uint64_t>(count, std::strlen(p) / 2 + 1));
        while (true) {
            while (*p == ' ' || *p == '\n' || *p == '\r' || *p == '\t')
                ++p;
            if (!*p)
                break;
            char* end = nullptr;
            const double v = std::strtod(p, &end);
            if (end == p)
                fail("{}: not a number in ascii data: \"{}\"", label, excerpt(p));
            if (out.size() == count)
                fail("{}: more than the {} values expected in ascii data", label, count);
            if constexpr (std::is_integral_v<T>) {
                if (!(v >= double(std::numeric_limits<T>::lowest()) && v <= double(std::numeric_limits<T>::max())) ||
                    v != std::floor(v))
                    fail("{}: {} is not a valid {}", label, excerpt(std::string_view(p, size_t(end - p))), typeName);
            }
            out.push_back(T(v));
            p = end;
        }
        if (out.size() != count)
            fail("{}: {} values in ascii data, expected {}", label, out.size(), count);
        return out;
    }
    if (count > std::numeric_limits<uint64_t>::max() / 16)
        fail("{}: {} values is more than a file can hold", label, count);
    const uint64_t bytes = count * info->size;
    std::string raw;
    if (format == "binary") {
        const char* text = node.child_value();
        ByteSource source(std::string_view(text), true, label);
        raw = decodeBinary(source, ctx, bytes, label);
    } else if (format == "appended") {
        const auto offsetAttr = node.attribute("offset");
        if (!offsetAttr)
            fail("{}: appended data without an offset", label);
        const uint64_t offset = wholeNumber(offsetAttr, 0, ctx.file, what + " offset");
        if (offset > ctx.appended.size())
            fail("{}: offset {} is past the end of the appended data ({} bytes; truncated file?)", label,
                 offsetAttr.as_string(), ctx.appended.size());
        ByteSource source(ctx.appended.substr(offset), ctx.appendedBase64, label);
        raw = decodeBinary(source, ctx, bytes, label);
    } else {
        fail("{}: format \"{}\", expected ascii, binary or appended", label, excerpt(format));
    }
    out.resize(count);
    for (uint64_t i = 0; i < count; ++i)
        out[i] = convertOne<T>(raw.data() + i * info->size, info->type, ctx.bigEndian);
    return out;
}

int components(const pugi::xml_node& node)
{
    const auto a = node.attribute("NumberOfComponents");
    if (!a)
        return 1;
    const std::string text = a.as_string();
    int value = 0;
    const auto [end, ec] = std::from_chars(text.data(), text.data() + text.size(), value);
    return text.empty() || ec != std::errc() || end != text.data() + text.size() ? -1 : value;
}

// Loads `text` (the file without its appended data) as XML; `root` is the VTKFile element of `type`.
pugi::xml_node loadVtkFile(pugi::xml_document& doc, std::string_view text, const std::string& file,
                           const std::string& type)
{
    const pugi::xml_parse_result r = doc.load_buffer(text.data(), text.size(), pugi::parse_default, pugi::encoding_utf8);
    if (!r)
        fail("{}: not valid XML ({} at byte {})", file, r.description(), r.offset);
    const pugi::xml_node root = doc.child("VTKFile");
    if (!root)
        fail("{}: not a VTK XML file (no VTKFile element)", file);
    const std::string found = root.attribute("type").as_string();
    if (found != type)
        fail("{}: a VTK XML file of type \"{}\", expected {}", file, excerpt(found), type);
    return root;
}

// The XML of a .vtu file's `bytes`: raw appended data may hold any byte, so the XML parser sees the
// file only up to AppendedData. Notes in `ctx` where the appended data starts and how it is encoded.
std::string xmlBeforeAppendedData(const std::string& bytes, FileContext& ctx)
{
    const std::string& file = ctx.file;
    std::string xml = bytes;
    const size_t appendedAt = bytes.find("<AppendedData");
    if (appendedAt != std::string::npos) {
        const size_t tagEnd = bytes.find('>', appendedAt);
        const size_t underscore = tagEnd == std::string::npos ? tagEnd : bytes.find('_', tagEnd);
        if (underscore == std::string::npos)
            fail("{}: AppendedData without its '_' marker (truncated file?)", file);
        const std::string tag = bytes.substr(appendedAt, tagEnd - appendedAt);
        const size_t enc = tag.find("encoding=\"");
        const std::string encoding =
            enc == std::string::npos ? "" : tag.substr(enc + 10, tag.find('"', enc + 10) - (enc + 10));
        if (encoding == "base64")
            ctx.appendedBase64 = true;
        else if (encoding != "raw")
            fail("{}: AppendedData encoding \"{}\", expected raw or base64", file, excerpt(encoding));
        ctx.appended = std::string_view(bytes).substr(underscore + 1);
        xml = bytes.substr(0, appendedAt) + "</VTKFile>";
    }
    return xml;
}

// How the file's binary data is laid out (VTKFile's byte_order, header_type, compressor), into `ctx`.
void readBinaryLayout(const pugi::xml_node& root, FileContext& ctx)
{
    const std::string& file = ctx.file;
    const std::string order = root.attribute("byte_order").as_string("LittleEndian");
    if (order != "LittleEndian" && order != "BigEndian")
        fail("{}: byte_order \"{}\", expected LittleEndian or BigEndian", file, excerpt(order));
    ctx.bigEndian = order == "BigEndian";
    const std::string header = root.attribute("header_type").as_string("UInt32");
    if (header != "UInt32" && header != "UInt64")
        fail("{}: header_type \"{}\", expected UInt32 or UInt64", file, excerpt(header));
    ctx.headerSize = header == "UInt64" ? 8 : 4;
    const std::string compressor = root.attribute("compressor").as_string();
    if (!compressor.empty() && compressor != "vtkZLibDataCompressor")
        fail("{}: compressor \"{}\", RayPC reads vtkZLibDataCompressor only (write the output uncompressed or "
             "with zlib)",
             file, excerpt(compressor));
    ctx.zlib = !compressor.empty();
}

// The grid's FieldData: its TIME and CYCLE (deal.II writes them) into `piece`.
void readFieldData(const pugi::xml_node& grid, const FileContext& ctx, Piece& piece)
{
    const std::string& file = ctx.file;
    for (const pugi::xml_node a : grid.child("FieldData").children("DataArray")) {
        const std::string name = a.attribute("Name").as_string();
        if (name != "TIME" && name != "CYCLE")
            continue;
        const uint64_t tuples = wholeNumber(a.attribute("NumberOfTuples"), 1, file, "FieldData " + name + " NumberOfTuples");
        if (tuples != 1)
            fail("{}: FieldData {} has {} tuples, expected 1", file, name, a.attribute("NumberOfTuples").as_string());
        if (name == "TIME") {
            const double t = readArray<double>(a, 1, ctx, "FieldData TIME")[0];
            if (!std::isfinite(t))
                fail("{}: FieldData TIME is {}", file, t);
            piece.time = t;
        } else {
            // deal.II writes CYCLE as Float32: any type, holding a whole number.
            const double cycle = readArray<double>(a, 1, ctx, "FieldData CYCLE")[0];
            if (!(std::abs(cycle) < 9e15) || cycle != std::floor(cycle))
                fail("{}: FieldData CYCLE is {}, expected a whole number", file, cycle);
            piece.cycle = int64_t(cycle);
        }
    }
}

// The grid's one Piece element (deal.II and VTK write one per file).
pugi::xml_node onlyPiece(const pugi::xml_node& grid, const std::string& file)
{
    const auto pieces = grid.children("Piece");
    const pugi::xml_node p = grid.child("Piece");
    if (!p)
        fail("{}: no Piece element", file);
    if (std::distance(pieces.begin(), pieces.end()) != 1)
        fail("{}: {} Piece elements in one file, expected 1 (as deal.II and VTK write)", file,
             std::distance(pieces.begin(), pieces.end()));
    return p;
}

// A Piece's count of points or cells (`attr`), at most what a file of `fileBytes` bytes can hold.
uint64_t pieceCount(const pugi::xml_node& p, const char* attr, size_t fileBytes, const std::string& file)
{
    const auto a = p.attribute(attr);
    if (!a)
        fail("{}: Piece without {}", file, attr);
    const uint64_t n = wholeNumber(a, 0, file, fmt::format("Piece {}", attr));
    // A point or cell takes at least one byte of the file, compressed: more is a corrupt count.
    if (n > fileBytes * 1032)
        fail("{}: Piece {} {} is more than a file of {} bytes can hold", file, attr, n, fileBytes);
    return uint64_t(n);
}

// The Piece's points (x, y, z each), all finite, into `piece`.
void readPoints(const pugi::xml_node& p, uint64_t nPoints, const FileContext& ctx, Piece& piece)
{
    const std::string& file = ctx.file;
    const pugi::xml_node pointsArray = p.child("Points").child("DataArray");
    if (!pointsArray)
        fail("{}: no Points DataArray", file);
    if (components(pointsArray) != 3)
        fail("{}: Points have {} components, expected 3", file, pointsArray.attribute("NumberOfComponents").as_string());
    piece.points = readArray<double>(pointsArray, nPoints * 3, ctx, "Points");
    for (size_t i = 0; i < piece.points.size(); ++i)
        if (!std::isfinite(piece.points[i]))
            fail("{}: point {} has a non-finite coordinate ({})", file, i / 3, piece.points[i]);
}

// The Piece's cells into `piece`: offsets increasing, connectivity within the points, types RayPC
// reads with as many points as the type has.
void readCells(const pugi::xml_node& p, uint64_t nCells, uint64_t nPoints, const FileContext& ctx, Piece& piece)
{
    const std::string& file = ctx.file;
    const pugi::xml_node cells = p.child("Cells");
    pugi::xml_node conn, offs, types;
    for (const pugi::xml_node a : cells.children("DataArray")) {
        const std::string name = a.attribute("Name").as_string();
        if (name == "connectivity")
            conn = a;
        else if (name == "offsets")
            offs = a;
        else if (name == "types")
            types = a;
    }
    if (!conn || !offs || !types)
        fail("{}: Cells lacks its {} DataArray", file, !conn ? "connectivity" : !offs ? "offsets" : "types");
    piece.offsets = readArray<int64_t>(offs, nCells, ctx, "Cells offsets");
    int64_t previous = 0;
    for (size_t c = 0; c < nCells; ++c) {
        if (piece.offsets[c] <= previous)
            fail("{}: Cells offsets: cell {} ends at {}, not after {}", file, c, piece.offsets[c], previous);
        previous = piece.offsets[c];
    }
    piece.connectivity = readArray<int64_t>(conn, uint64_t(previous), ctx, "Cells connectivity");
    for (size_t i = 0; i < piece.connectivity.size(); ++i)
        if (piece.connectivity[i] < 0 || uint64_t(piece.connectivity[i]) >= nPoints)
            fail("{}: Cells connectivity: point index {} at position {}, expected 0 … {}", file, piece.connectivity[i], i,
                 nPoints == 0 ? 0 : nPoints - 1);
    const std::vector<int64_t> typeCodes = readArray<int64_t>(types, nCells, ctx, "Cells types");
    piece.types.resize(nCells);
    for (size_t c = 0; c < nCells; ++c) {
        const int64_t code = typeCodes[c];
        if (code != 10 && code != 12 && code != 13 && code != 72)
            fail("{}: cell {} has VTK type {}, expected tetrahedra (10), hexahedra (12), wedges (13) or Lagrange "
                 "hexahedra (72)",
                 file, c, code);
        piece.types[c] = CellType(code);
        const int64_t n = piece.offsets[c] - piece.cellBegin(c);
        if (cellDegree(piece.types[c], n) == 0)
            fail("{}: cell {} of VTK type {} has {} points", file, c, code, n);
    }
}

// The Piece's PointData arrays into `piece`: uniquely named, 1 to 9 components, a finite value within
// float32's range at every point.
void readPointData(const pugi::xml_node& p, uint64_t nPoints, const FileContext& ctx, Piece& piece)
{
    const std::string& file = ctx.file;
    for (const pugi::xml_node a : p.child("PointData").children("DataArray")) {
        PointArray array;
        array.name = a.attribute("Name").as_string();
        if (array.name.empty())
            fail("{}: a PointData DataArray without a Name", file);
        if (piece.find(array.name))
            fail("{}: two PointData arrays named \"{}\"", file, excerpt(array.name));
        array.components = components(a);
        if (array.components < 1 || array.components > 9)
            fail("{}: PointData {}: NumberOfComponents \"{}\", expected 1 … 9", file, array.name,
                 excerpt(a.attribute("NumberOfComponents").as_string()));
        // Read as double: a Float64 beyond float32's range is named as written, not as the infinity
        // it would become. A value is needed at every point: NaN and infinities are refused here, so
        // that no command (info, preprocess, serve) meets them downstream.
        const std::vector<double> values =
            readArray<double>(a, nPoints * uint64_t(array.components), ctx, "PointData " + array.name);
        array.values.resize(values.size());
        for (size_t i = 0; i < values.size(); ++i) {
            const double v = values[i];
            if (!std::isfinite(v) || std::abs(v) > double(std::numeric_limits<float>::max()))
                fail("{}: PointData {}: {} at point {}{} {}", file, excerpt(array.name), v, i / size_t(array.components),
                     array.components > 1 ? fmt::format(" (component {})", i % size_t(array.components)) : "",
                     std::isfinite(v) ? "is beyond float32's range (±3.4e38)"
                     : std::isnan(v)  ? "is not a number; RayPC needs a finite value at every point"
                                      : "is infinite; RayPC needs a finite value at every point");
            array.values[i] = static_cast<float>(v);
        }
        piece.pointData.push_back(std::move(array));
    }
}

}  // namespace

Piece readVtu(const fs::path& path)
{
    if (!fs::is_regular_file(path))
        fail("{}: no such file", path.string());
    return parseVtu(readFile(path), path.string());
}

Piece parseVtu(const std::string& bytes, const std::string& file)
{
    FileContext ctx;
    ctx.file = file;
    const std::string xml = xmlBeforeAppendedData(bytes, ctx);
    pugi::xml_document doc;
    const pugi::xml_node root = loadVtkFile(doc, xml, file, "UnstructuredGrid");
    readBinaryLayout(root, ctx);
    const pugi::xml_node grid = root.child("UnstructuredGrid");
    if (!grid)
        fail("{}: no UnstructuredGrid element", file);
    Piece piece;
    readFieldData(grid, ctx, piece);
    const pugi::xml_node p = onlyPiece(grid, file);
    const uint64_t nPoints = pieceCount(p, "NumberOfPoints", bytes.size(), file);
    const uint64_t nCells = pieceCount(p, "NumberOfCells", bytes.size(), file);
    readPoints(p, nPoints, ctx, piece);
    readCells(p, nCells, nPoints, ctx, piece);
    readPointData(p, nPoints, ctx, piece);
    return piece;
}

PieceRecord readPvtu(const fs::path& path)
{
    const std::string file = path.string();
    if (!fs::is_regular_file(path))
        fail("{}: no such file", file);
    pugi::xml_document doc;
    const pugi::xml_node root = loadVtkFile(doc, readFile(path), file, "PUnstructuredGrid");
    const pugi::xml_node grid = root.child("PUnstructuredGrid");
    if (!grid)
        fail("{}: no PUnstructuredGrid element", file);
    PieceRecord record;
    for (const pugi::xml_node a : grid.child("PPointData").children("PDataArray"))
        record.pointArrays.emplace_back(a.attribute("Name").as_string(), components(a));
    for (const pugi::xml_node piece : grid.children("Piece")) {
        const std::string source = piece.attribute("Source").as_string();
        if (source.empty())
            fail("{}: a Piece without a Source", file);
        // Pieces lie beside their record or below it (deal.II and VTK write them so): a record that
        // names a file elsewhere (an absolute path, "..") would make RayPC read whatever it names.
        const fs::path p(source);
        if (p.is_absolute() || std::any_of(p.begin(), p.end(), [](const fs::path& part) { return part == ".."; }))
            fail("{}: Piece Source \"{}\" lies outside the record's folder (an absolute path or '..'); pieces are read "
                 "from the record's folder only",
                 file, excerpt(source));
        record.pieces.push_back(path.parent_path() / p);
    }
    if (record.pieces.empty())
        fail("{}: names no Piece", file);
    return record;
}

std::vector<CollectionStep> readPvd(const fs::path& path)
{
    const std::string file = path.string();
    if (!fs::is_regular_file(path))
        fail("{}: no such file", file);
    pugi::xml_document doc;
    const pugi::xml_node root = loadVtkFile(doc, readFile(path), file, "Collection");
    std::vector<CollectionStep> steps;
    for (const pugi::xml_node d : root.child("Collection").children("DataSet")) {
        const std::string name = d.attribute("file").as_string();
        if (name.empty())
            fail("{}: a DataSet without a file", file);
        const pugi::xml_attribute timestep = d.attribute("timestep");
        if (!timestep && root.child("Collection").child("DataSet").next_sibling("DataSet"))
            fail("{}: DataSet {} has no timestep (every DataSet of a collection of several steps needs one)", file,
                 excerpt(name));
        const std::string text = timestep.as_string("0");
        char* end = nullptr;
        const double t = std::strtod(text.c_str(), &end);
        if (end == text.c_str() || *end != '\0' || !std::isfinite(t))
            fail("{}: DataSet {}: timestep \"{}\", expected a finite number", file, excerpt(name), excerpt(text));
        if (!steps.empty() && t <= steps.back().time)
            fail("{}: DataSet {}: timestep {} does not follow {} (one mesh per step, in time order)", file,
                 excerpt(name), text, steps.back().time);
        const fs::path p(name);
        steps.push_back({t, p.is_absolute() ? p : path.parent_path() / p});
    }
    if (steps.empty())
        fail("{}: a collection without any DataSet", file);
    return steps;
}

}  // namespace raypc::io::vtk
