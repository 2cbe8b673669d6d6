// VTK XML files as mantle-convection codes write them: ASPECT (deal.II's DataOut) writes a time
// series as a .pvd collection of .pvtu records, each naming its .vtu UnstructuredGrid pieces (one
// per MPI rank of the model). This is the file layer only: it decodes what the files say into
// points, cells and point data; putting those onto the spherical grid is the resampler's work.
//
// What is read (the VTK file formats document, "XML File Formats"; what VTK 9 and deal.II 9.4 write):
// - DataArray formats ascii, binary (base64) and appended (raw or base64 AppendedData);
//   vtkZLibDataCompressor blocks; header_type UInt32 or UInt64; LittleEndian or BigEndian;
// - every numeric DataArray type (Float32/64, Int8…Int64, UInt8…UInt64);
// - cells: tetrahedra (VTK type 10), hexahedra (12), wedges (13) and Lagrange hexahedra (72) of any
//   degree, with points repeated per cell (DataOut's patches) or shared;
// - FieldData TIME and CYCLE.
// Every count is checked against the file's own sizes before anything is allocated for it, so a
// truncated or corrupt file gives one raypc::Error naming the file and what is wrong, never a crash.
// Thread safety: the functions share no state; pieces may be read on several threads at once.
#pragma once

#include <cstdint>
#include <filesystem>
#include <optional>
#include <string>
#include <vector>

namespace raypc::io::vtk {

// VTK's cell type numbers for the cells RayPC reads.
enum class CellType : uint8_t { Tetra = 10, Hexahedron = 12, Wedge = 13, LagrangeHexahedron = 72 };

// One point-data array: `components` values per point, point-major.
struct PointArray {
    std::string name;
    int components = 1;
    std::vector<float> values;
};

// One .vtu file. Coordinates are as written (ASPECT: Cartesian metres).
struct Piece {
    std::vector<double> points;          // x, y, z per point
    std::vector<int64_t> connectivity;   // point indices of all cells, cell after cell
    std::vector<int64_t> offsets;        // end of each cell's points in `connectivity`
    std::vector<CellType> types;         // one per cell
    std::vector<PointArray> pointData;
    std::optional<double> time;          // FieldData TIME, in the model's unit (ASPECT: years)
    std::optional<int64_t> cycle;        // FieldData CYCLE

    size_t pointCount() const { return points.size() / 3; }
    size_t cellCount() const { return types.size(); }
    int64_t cellBegin(size_t cell) const { return cell == 0 ? 0 : offsets[cell - 1]; }
    const PointArray* find(const std::string& name) const;
};

// Reads one UnstructuredGrid file. Throws raypc::Error naming `path` and what is wrong: not a VTK
// XML UnstructuredGrid, a missing or malformed element or attribute, an unsupported cell type or
// compressor, a truncated or corrupt data block, counts that disagree, a point index out of range,
// or a non-finite point coordinate.
Piece readVtu(const std::filesystem::path& path);
// The same for a file's bytes in memory; `file` names them in messages.
Piece parseVtu(const std::string& bytes, const std::string& file);

// A .pvtu record: its pieces' paths (resolved against the record's folder) and the point arrays
// it announces (name and components).
struct PieceRecord {
    std::vector<std::filesystem::path> pieces;
    std::vector<std::pair<std::string, int>> pointArrays;
};

// Throws raypc::Error naming `path` when it is not a PUnstructuredGrid record or names no piece.
PieceRecord readPvtu(const std::filesystem::path& path);

// One step of a .pvd collection: its `timestep` (the model's unit, ASPECT: years unless told to
// write seconds) and the file it names (resolved against the collection's folder).
struct CollectionStep {
    double time = 0;
    std::filesystem::path file;
};

// The steps in time order (DataSets of one time with several `part`s are refused: RayPC reads one
// mesh per step). Throws raypc::Error naming `path` on a malformed collection, a non-finite or
// repeated time, or no DataSet at all.
std::vector<CollectionStep> readPvd(const std::filesystem::path& path);

// The number of points of a cell of `type` with `count` points in the file, checked: 4, 8, 6, or
// (p+1)³ for a Lagrange hexahedron of degree p ≥ 1. Returns the degree (1 for linear cells, p for
// Lagrange), or 0 when `count` is not valid for `type`.
int cellDegree(CellType type, int64_t count);

}  // namespace raypc::io::vtk
