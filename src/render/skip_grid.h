// Internal to raypc_render: a Cartesian grid over the planet's bounding cube for empty-space
// skipping (docs/rendering.md, "Empty-space skipping").
//
// Bricks live in (lat, r, lon) index space; a ray is a line in Cartesian space. Locating a point in
// a brick takes a square root and two arctangents, so probing brick by brick costs almost as much
// as sampling. A cubic cell grid is probed with three multiplies and a byte load. For every cell
// the geometry (per grid, built once and shared) records which bricks a sample inside the cell —
// grown by kSkipCellPadKm on every side — can fall into: a box of brick indices (lon cyclic), or
// "none" (the cell lies outside the shell, where no sample is taken), or "always" (the cell reaches
// into a pole cap, which is always sampled). Per parameter change, a cell is occupied when any
// brick of its box is active, and each cell gets its Chebyshev distance, in cells, to the nearest
// occupied cell; a ray at a cell with distance D >= 1 may advance to the exit of the (2D - 1)^3
// block of cells around it without meeting an active sample.
#pragma once

#include "grid/grid.h"
#include "render/render_kernel.h"

#include <cstdint>
#include <memory>
#include <vector>

namespace raypc::render {

// Cells are grown by this much (km) when their bricks are found: it covers the float rounding of
// sample positions and lets a probe step just past a cell face (render_kernel.h, cellSkipKm).
inline constexpr float kSkipCellPadKm = 0.05f;

struct SkipGridGeometry {
    enum Kind : uint8_t { None = 0, Box = 1, Always = 2 };
    int n = 0;  // cells per axis
    float originKm = 0, cellKm = 1;
    std::vector<uint8_t> kind;   // per cell, x fastest, then y, then z
    std::vector<uint16_t> box;   // per cell: lat brick first, last; r brick first, last; lon brick first, count (cyclic)
    int bricksLat = 0, bricksR = 0, bricksLon = 0;
};

// The geometry of a grid whose kernel view (axis maps, caps, radii, brick shift and counts) is
// `gridPart`, with cells about `cellKm` wide; built in parallel and cached by grid (the levels of a
// dataset share their grids across steps).
std::shared_ptr<const SkipGridGeometry> skipGridGeometry(const grid::SphericalGrid& grid, const grid::BrickLayout& bricks,
                                                         const kernel::KernelParams& gridPart, float cellKm);

// Chebyshev distance, in cells, from each cell to the nearest cell that may hold an active sample
// (0 there; capped at 255), from the brick flags of one parameter set.
void skipGridDistance(const SkipGridGeometry& geometry, const std::vector<int32_t>& brickActive,
                      std::vector<uint8_t>& distance);

}  // namespace raypc::render
