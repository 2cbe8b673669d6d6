#include "analysis/pathline_export.h"

#include "core/spherical.h"
#include "core/strings.h"

#include <fmt/format.h>

#include <cmath>

namespace raypc::analysis {
namespace {

std::string xmlEscape(const std::string& s)
{
    std::string out;
    for (char c : s) {
        switch (c) {
        case '&': out += "&amp;"; break;
        case '<': out += "&lt;"; break;
        case '>': out += "&gt;"; break;
        case '"': out += "&quot;"; break;
        default: out += c;
        }
    }
    return out;
}

std::string header(const std::string& name, const std::string& units)
{
    return csvQuote(units.empty() ? name : fmt::format("{} [{}]", name, units));
}

// Points of line `i` as a span of 4-float records.
struct LineRange {
    size_t begin, end;
};
LineRange lineRange(const PathlineSet& set, size_t i) { return {set.offsets[i], set.offsets[i + 1]}; }

}  // namespace

std::string pathlinesCsv(const PathlineSet& set)
{
    // The stored values x, y, z and time as src/grid/names.json names them; lat, lon, radius and age
    // follow from them.
    const auto& stored = columns::kPathlinePoints;
    std::string out = "line,point";
    for (size_t k = 0; k < 3; ++k)
        out += "," + header(stored[k].name, stored[k].units);
    out += ",lat [degrees_north],lon [degrees_east],radius [km]," + header(stored[3].name, stored[3].units) + ",age [Myr]";
    for (size_t c = 0; c < set.columns.size(); ++c)
        out += "," + header(set.columns[c], set.units[c]);
    out += '\n';
    auto it = std::back_inserter(out);
    for (size_t i = 0; i < set.lineCount(); ++i) {
        const auto [begin, end] = lineRange(set, i);
        for (size_t p = begin; p < end; ++p) {
            const float* q = &set.points[4 * p];
            const SphericalPoint s = cartesianToSpherical({q[0], q[1], q[2]});
            fmt::format_to(it, "{},{},{:.7g},{:.7g},{:.7g},{:.7g},{:.7g},{:.7g},{:.7g},{:.7g}", i, p - begin, q[0],
                           q[1], q[2], s.latDeg, s.lonDeg, s.rKm, q[3], q[3] - set.injectionTimeMyr);
            for (size_t c = 0; c < set.columns.size(); ++c)
                fmt::format_to(it, ",{:.7g}", set.attribute(i, c));
            out += '\n';
        }
    }
    return out;
}

std::string criticalPointsCsv(const PathlineSet& set)
{
    std::string out = "kind,x [km],y [km],z [km]";
    for (size_t c = 0; c < set.columns.size(); ++c)
        out += "," + header(set.columns[c], set.units[c]);
    out += '\n';
    auto it = std::back_inserter(out);
    for (size_t i = 0; i < set.lineCount(); ++i) {
        const float* q = &set.points[4 * set.offsets[i]];
        fmt::format_to(it, "{},{:.7g},{:.7g},{:.7g}", criticalKindName(static_cast<CriticalKind>(set.attribute(i, 0))),
                       q[0], q[1], q[2]);
        for (size_t c = 0; c < set.columns.size(); ++c)
            fmt::format_to(it, ",{:.7g}", set.attribute(i, c));
        out += '\n';
    }
    return out;
}

namespace {

template <typename F>
void xmlArray(std::string& out, const char* type, const std::string& name, int components, size_t count, F value)
{
    auto it = std::back_inserter(out);
    fmt::format_to(it, "        <DataArray type=\"{}\"", type);
    if (!name.empty())
        fmt::format_to(it, " Name=\"{}\"", xmlEscape(name));
    if (components > 1)
        fmt::format_to(it, " NumberOfComponents=\"{}\"", components);
    out += " format=\"ascii\">\n";
    for (size_t i = 0; i < count; ++i) {
        value(it, i);
        out += (i + 1) % 12 == 0 || i + 1 == count ? '\n' : ' ';
    }
    out += "        </DataArray>\n";
}

// The points of `set` selected by `index(i)` for i < n, and per-point data.
std::string vtpDocument(const PathlineSet& set, bool linesNotSeeds)
{
    const size_t nLines = set.lineCount();
    const size_t nPoints = linesNotSeeds ? set.pointCount() : nLines;
    auto pointIndex = [&](size_t i) { return linesNotSeeds ? i : static_cast<size_t>(set.offsets[i]); };
    std::string out = "<?xml version=\"1.0\"?>\n"
                      "<VTKFile type=\"PolyData\" version=\"1.0\" byte_order=\"LittleEndian\" header_type=\"UInt64\">\n"
                      "  <PolyData>\n";
    auto it = std::back_inserter(out);
    fmt::format_to(it,
                   "    <Piece NumberOfPoints=\"{}\" NumberOfVerts=\"{}\" NumberOfLines=\"{}\" NumberOfStrips=\"0\" "
                   "NumberOfPolys=\"0\">\n",
                   nPoints, linesNotSeeds ? 0 : nLines, linesNotSeeds ? nLines : 0);
    out += "      <PointData>\n";
    if (linesNotSeeds) {
        xmlArray(out, "Float32", "time", 1, nPoints, [&](auto o, size_t i) { fmt::format_to(o, "{:.7g}", set.points[4 * i + 3]); });
        xmlArray(out, "Float32", "age", 1, nPoints,
                 [&](auto o, size_t i) { fmt::format_to(o, "{:.7g}", set.points[4 * i + 3] - set.injectionTimeMyr); });
    } else {
        for (size_t c = 0; c < set.columns.size(); ++c)
            xmlArray(out, "Float32", set.columns[c], 1, nPoints,
                     [&](auto o, size_t i) { fmt::format_to(o, "{:.7g}", set.attribute(i, c)); });
    }
    out += "      </PointData>\n      <CellData>\n";
    if (linesNotSeeds)
        for (size_t c = 0; c < set.columns.size(); ++c)
            xmlArray(out, "Float32", set.columns[c], 1, nLines,
                     [&](auto o, size_t i) { fmt::format_to(o, "{:.7g}", set.attribute(i, c)); });
    out += "      </CellData>\n      <Points>\n";
    xmlArray(out, "Float32", "", 3, nPoints, [&](auto o, size_t i) {
        const float* q = &set.points[4 * pointIndex(i)];
        fmt::format_to(o, "{:.7g} {:.7g} {:.7g}", q[0], q[1], q[2]);
    });
    out += "      </Points>\n";
    const char* cells = linesNotSeeds ? "Lines" : "Verts";
    fmt::format_to(it, "      <{}>\n", cells);
    xmlArray(out, "Int64", "connectivity", 1, nPoints, [&](auto o, size_t i) { fmt::format_to(o, "{}", i); });
    xmlArray(out, "Int64", "offsets", 1, nLines,
             [&](auto o, size_t i) { fmt::format_to(o, "{}", linesNotSeeds ? set.offsets[i + 1] : i + 1); });
    fmt::format_to(it, "      </{}>\n", cells);
    out += "    </Piece>\n  </PolyData>\n</VTKFile>\n";
    return out;
}

std::string legacyDocument(const PathlineSet& set, bool linesNotSeeds)
{
    const size_t nLines = set.lineCount();
    const size_t nPoints = linesNotSeeds ? set.pointCount() : nLines;
    auto pointIndex = [&](size_t i) { return linesNotSeeds ? i : static_cast<size_t>(set.offsets[i]); };
    std::string out;
    auto it = std::back_inserter(out);
    fmt::format_to(it, "# vtk DataFile Version 3.0\nRayPC {} injected at step {} ({} Myr)\nASCII\nDATASET POLYDATA\n",
                   linesNotSeeds ? "pathlines" : "critical points (pathline seeds)", set.injectionStep,
                   set.injectionTimeMyr);
    fmt::format_to(it, "POINTS {} float\n", nPoints);
    for (size_t i = 0; i < nPoints; ++i) {
        const float* q = &set.points[4 * pointIndex(i)];
        fmt::format_to(it, "{:.7g} {:.7g} {:.7g}\n", q[0], q[1], q[2]);
    }
    // Legacy array names cannot hold spaces.
    auto fieldArrays = [&](size_t count, auto value) {
        fmt::format_to(it, "FIELD FieldData {}\n", set.columns.size());
        for (size_t c = 0; c < set.columns.size(); ++c) {
            fmt::format_to(it, "{} 1 {} float\n", fileSafeName(set.columns[c]), count);
            for (size_t i = 0; i < count; ++i)
                fmt::format_to(it, "{:.7g}{}", value(i, c), (i + 1) % 12 == 0 || i + 1 == count ? '\n' : ' ');
        }
    };
    auto attr = [&](size_t i, size_t c) { return set.attribute(i, c); };
    if (linesNotSeeds) {
        fmt::format_to(it, "LINES {} {}\n", nLines, nLines + nPoints);
        for (size_t i = 0; i < nLines; ++i) {
            const auto [begin, end] = lineRange(set, i);
            fmt::format_to(it, "{}", end - begin);
            for (size_t p = begin; p < end; ++p)
                fmt::format_to(it, " {}", p);
            out += '\n';
        }
        fmt::format_to(it, "CELL_DATA {}\n", nLines);
        fieldArrays(nLines, attr);
        fmt::format_to(it, "POINT_DATA {}\nFIELD FieldData 2\ntime 1 {} float\n", nPoints, nPoints);
        for (size_t i = 0; i < nPoints; ++i)
            fmt::format_to(it, "{:.7g}{}", set.points[4 * i + 3], (i + 1) % 12 == 0 || i + 1 == nPoints ? '\n' : ' ');
        fmt::format_to(it, "age 1 {} float\n", nPoints);
        for (size_t i = 0; i < nPoints; ++i)
            fmt::format_to(it, "{:.7g}{}", set.points[4 * i + 3] - set.injectionTimeMyr,
                           (i + 1) % 12 == 0 || i + 1 == nPoints ? '\n' : ' ');
    } else {
        fmt::format_to(it, "VERTICES {} {}\n", nLines, 2 * nLines);
        for (size_t i = 0; i < nLines; ++i)
            fmt::format_to(it, "1 {}\n", i);
        fmt::format_to(it, "POINT_DATA {}\n", nPoints);
        fieldArrays(nPoints, attr);
    }
    return out;
}

}  // namespace

std::string pathlinesVtp(const PathlineSet& set) { return vtpDocument(set, true); }
std::string criticalPointsVtp(const PathlineSet& set) { return vtpDocument(set, false); }
std::string pathlinesLegacyVtk(const PathlineSet& set) { return legacyDocument(set, true); }
std::string criticalPointsLegacyVtk(const PathlineSet& set) { return legacyDocument(set, false); }

}  // namespace raypc::analysis
