// A field of one spherical grid at every point of another: what a comparison of two datasets
// (a difference, a correlation) reads the second one through, so that both are on the first one's
// grid. One rule of interpolation, the sampler's (grid/sampler.h): trilinear in the source grid's
// own coordinates, periodic in longitude across the seam, blending toward the ring mean in a
// pole cap. Points the source does not cover are missing (NaN), never extrapolated: a radius
// outside the source's shells, and for a regional source the padding outside its data.
//
// Thread safety: pure functions; they use every core (oneTBB) over the target's shells.
#pragma once

#include "grid/grid.h"

#include <cstddef>
#include <functional>
#include <vector>

namespace raypc::grid {

// The value at grid point (iLat, iR, iLon) of the source grid.
using GridValueAt = std::function<float(size_t iLat, size_t iR, size_t iLon)>;

// `source`'s field (values by `valueAt`) at each point of `target`, in `target`'s canonical order.
// When the grids are the same (SphericalGrid::sameAs) the values are copied point for point.
std::vector<float> regrid(const SphericalGrid& source, const GridValueAt& valueAt, const SphericalGrid& target);
// The same for values held in `source`'s canonical order (source.cellCount() of them).
std::vector<float> regrid(const SphericalGrid& source, const float* values, const SphericalGrid& target);

// How much of `target`'s volume the source grid covers with data (radius within its shells and,
// for a regional source, lat and lon within its data's extent), as a fraction in [0, 1]: 0 means
// the grids do not overlap, which a comparison refuses.
double coveredFraction(const SphericalGrid& source, const SphericalGrid& target);

}  // namespace raypc::grid
