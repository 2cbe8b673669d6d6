// Per-brick value bounds for empty-space skipping (see BrickLayout in grid.h).
#pragma once

#include "grid/grid.h"

#include <span>

namespace raypc::dataset {

// Fills `bounds` (layout.brickCount() pairs min, max) with the bounds of `values` over every
// brick's points, one point of overlap included (lon wrapping), so that every trilinear
// interpolation inside a brick lies within its bounds. Parallel over bricks.
void computeBrickBounds(const grid::SphericalGrid& grid, const grid::BrickLayout& layout, std::span<const float> values,
                        std::span<float> bounds);

}  // namespace raypc::dataset
