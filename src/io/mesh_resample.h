// Resampling an unstructured mesh of the mantle shell (ASPECT's output: vtk::Piece) onto RayPC's
// spherical grid (grid.h), with every cell's own map and shape functions, so that the resampled
// steps go through the dataset pipeline as netCDF steps do.
//
// How (docs/format.md, "ASPECT's output"): for every cell, the grid points inside a padded box of
// the cell's nodes in (lat, r, lon) are candidates (a cell across the lon seam wraps; a cell around
// the polar axis takes every longitude); each candidate's reference coordinates are found by
// Newton's method on the cell's map (trilinear for hexahedra, tensor-product Lagrange of degree p
// for VTK's Lagrange hexahedra, linear for tetrahedra and wedges), and a point inside the cell
// takes the values of the cell's shape functions there. The first cell that holds a point gives
// its values (cells that share a face agree up to the mesh's own discontinuities, e.g. at hanging
// nodes). Grid points in no cell, which a mesh of flat-faced cells leaves between its nodes on the
// curved inner and outer boundary, take the values of the nearest cell's boundary (reference
// coordinates clamped) when they lie within kSnapReference of a cell in reference units; they
// are counted as "snapped". Points farther from every cell are missing (NaN) and counted.
//
// Grid rows are shared out over threads (TBB), each writing only its own rows, so the result does
// not depend on the thread count.
#pragma once

#include "grid/grid.h"
#include "io/vtk_xml.h"

#include <array>
#include <cstdint>
#include <optional>
#include <string>
#include <vector>

namespace raypc::io {

// How far outside a cell (in its reference coordinates, a cell being [0, 1]³) a grid point may lie
// and still take the values of the cell's nearest boundary.
inline constexpr double kSnapReference = 0.5;

// The mesh of one step: its pieces, with points converted to km (`kmPerUnit` times the file's
// coordinates; ASPECT writes metres).
struct ShellMesh {
    std::vector<vtk::Piece> pieces;
    double kmPerUnit = 1e-3;
    // Radii of the nodes (km): the shell the mesh covers.
    double rMinKm = 0, rMaxKm = 0;
    // The finest cell: its extent along a shell (degrees of arc) and across radii (km), divided
    // by the cell's degree (a Lagrange cell's nodes are that far apart).
    double finestArcDeg = 0, finestRadialKm = 0;
    double coarsestArcDeg = 0;  // the largest arc between two nodes of one cell (degrees)
    size_t cellCount = 0, pointCount = 0;
    // A regional mesh (a CitcomS regional cap, a chunk of an ASPECT model): the extent of its nodes'
    // latitudes (south, north; none: within two of its coarsest cells of both poles) and longitudes
    // (west, east in degrees east within [0, 360), west > east across 0°; none: no gap wider than two
    // of its coarsest cells).
    std::optional<std::array<double, 2>> latExtentDeg, lonExtentDeg;
    bool regional() const { return latExtentDeg.has_value() || lonExtentDeg.has_value(); }
};

// Gathers the pieces and measures them. Throws raypc::Error naming `what` when the mesh is empty
// or is not a spherical shell around the origin within 3000..7000 km after conversion (with the
// radii found), e.g. a non-dimensional model.
ShellMesh makeShellMesh(std::vector<vtk::Piece> pieces, double kmPerUnit, const std::string& what);

// The grid a mesh is resampled onto by default: spacings as fine as the mesh's finest cell (arc
// and radial), lat at cell centres (no point on a pole), lon from 0° in equal steps, r from the
// inner to the outer radius; coarsened evenly when it would have more than `maxPoints` points. A
// regional mesh's grid spans its extent (its first and last points on the extent's edges) and is
// padded to the globe with points of no data (grid::padToGlobe).
grid::SphericalGrid defaultResampleGrid(const ShellMesh& mesh, uint64_t maxPoints);
// A grid of the given sizes over the mesh's shell (a regional mesh's: over its extent, then padded),
// laid out as defaultResampleGrid's.
grid::SphericalGrid resampleGrid(const ShellMesh& mesh, size_t nLat, size_t nR, size_t nLon);

struct ResampleCounts {
    size_t points = 0;   // grid points
    size_t inside = 0;   // inside a cell
    size_t snapped = 0;  // within kSnapReference of a cell: its nearest boundary's values
    size_t missing = 0;  // in no cell and near none, within a regional grid's extent: NaN (a hole)
    size_t outside = 0;  // in no cell, outside a regional grid's extent (grid.h): NaN, padding
};

// The values of point arrays `arrays` (name and component; -1 for a scalar) at every grid point
// (canonical order, grid.h), one vector per array. Throws raypc::Error naming `what` when an array
// is missing from a piece or has another number of components.
struct ArrayComponent {
    std::string name;
    int component = -1;
};
std::vector<std::vector<float>> resampleOntoGrid(const ShellMesh& mesh, const grid::SphericalGrid& grid,
                                                 const std::vector<ArrayComponent>& arrays, const std::string& what,
                                                 ResampleCounts* counts = nullptr);

// VTK's numbering of a Lagrange hexahedron's (p+1)³ points (VTK's vtkHigherOrderHexahedron, as
// deal.II's DataOut writes it): for the point at lattice position (i, j, k), 0 ≤ i, j, k ≤ p, its
// index among the cell's points. Vertices first (in the linear hexahedron's order), then the edges'
// inner points, the faces', the interior's.
int lagrangeHexPointIndex(int i, int j, int k, int p);

}  // namespace raypc::io
