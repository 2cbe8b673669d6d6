// The spherical grid of a mantle snapshot, in RayPC's canonical order.
//
// Canonical order (after reading, whatever order the file had):
//   lat ascending (south to north, degrees north), r ascending (km), lon ascending in [0, 360)
//   (degrees east) without a repeated 360° seam; arrays are indexed
//   index = (iLat * nR + iR) * nLon + iLon   (lon fastest, as in the contest files).
// The grid is global and periodic in lon: the neighbour of the last lon column is column 0.
// Values live on the grid points; between grid points, fields are trilinear in index space.
// Rows do not need to reach the poles; the region between the outermost lat row and the pole
// is covered by that row's dual cell (see cellVolumeKm3).
//
// Thread safety: immutable after construction.
#pragma once

#include "core/spare_blocks.h"

#include <array>
#include <cstddef>
#include <cstdint>
#include <memory>
#include <optional>
#include <utility>
#include <string>
#include <vector>

namespace raypc::grid {

struct SphericalGrid {
    std::vector<double> latDeg;  // ascending, within [-90, 90]
    std::vector<double> rKm;     // ascending
    std::vector<double> lonDeg;  // ascending, within [0, 360), periodic

    // A regional grid, padded to the globe by its reader with points that hold no data (NaN in every
    // field), keeps the extent of its data: the latitudes south..north, the longitudes west..east
    // (degrees east in [0, 360); west > east when the region crosses 0°). Points outside have no
    // volume (volumeFactors): statistics, selections and features count the region the data cover.
    std::optional<std::array<double, 2>> dataLatDeg, dataLonDeg;
    bool regional() const { return dataLatDeg.has_value() || dataLonDeg.has_value(); }
    // Whether latitude `latDeg` (of a row) and longitude `lonDeg` (of a column) lie within the data's extent.
    bool latHoldsData(double latDeg) const;
    bool lonHoldsData(double lonDeg) const;
    // Whether the column of grid points (iLat, iLon) lies within the data's extent (every column of a
    // global grid).
    bool holdsData(size_t iLat, size_t iLon) const { return latHoldsData(latDeg[iLat]) && lonHoldsData(lonDeg[iLon]); }

    size_t nLat() const { return latDeg.size(); }
    size_t nR() const { return rKm.size(); }
    size_t nLon() const { return lonDeg.size(); }
    size_t cellCount() const { return nLat() * nR() * nLon(); }
    size_t index(size_t iLat, size_t iR, size_t iLon) const { return (iLat * nR() + iR) * nLon() + iLon; }

    // Edges of the dual cell around each grid point along one axis: midpoints between
    // neighbours; lat ends extend by half a spacing, clamped to the poles; r ends are the
    // shell's boundaries r.front() and r.back(); lon wraps. Each has n + 1 entries.
    std::vector<double> latEdgesDeg() const;
    std::vector<double> rEdgesKm() const;
    std::vector<double> lonEdgesDeg() const;  // first edge may be negative, last may exceed 360
    // Width of each lon column's dual cell in degrees (differences of lonEdgesDeg; they sum to 360).
    std::vector<double> lonWidthsDeg() const;

    // The mean of row iLat at radius iR over the whole ring, each point weighted by its lon width
    // (`lonWidthsDeg`, passed so that callers compute it once): the value every longitude meets at
    // the pole in the cap between the outermost row and its pole. Probe, pathlines and the ray
    // caster all blend towards it.
    double ringMean(const float* values, size_t iLat, size_t iR, const std::vector<double>& lonWidthsDeg) const;

    // Volume of the dual cell of every grid point, in km³, as three separable factors:
    // volume(iLat, iR, iLon) = latFactor[iLat] * rFactor[iR] * lonFactor[iLon], with
    // latFactor = sin(edge+) - sin(edge-), rFactor = (r+³ - r-³)/3, lonFactor = Δlon in radians; 0 for a
    // row or column outside a regional grid's data (dataLatDeg, dataLonDeg).
    struct VolumeFactors {
        std::vector<double> lat, r, lon;
        double at(size_t iLat, size_t iR, size_t iLon) const { return lat[iLat] * r[iR] * lon[iLon]; }
    };
    VolumeFactors volumeFactors() const;
    double totalVolumeKm3() const;

    // The grid of the next coarser level of detail: every 2 points along each axis are
    // merged (an odd count keeps a last point alone); coordinates are the means of the
    // merged points (lon averaged on the circle). The outermost coarse coordinates lie inside
    // the fine grid's extent; samplers clamp (constant extension) up to the shell boundaries.
    SphericalGrid coarsened() const;

    // Throws raypc::Error naming `what` unless the coordinates are strictly ascending and in range.
    // Spacings may vary: a regional grid's reader pads it to the globe with points that hold no data.
    void validate(const std::string& what) const;

    // True when both grids have the same sizes and coordinates within `toleranceDeg/Km`.
    bool sameAs(const SphericalGrid& other, double tolerance = 1e-6) const;
};

// A regional axis made global (docs/format.md, "Regional and partial grids"): latitudes that stop more
// than two spacings short of a pole, or longitudes that leave a gap of more than two spacings, get
// points that hold no data: rows toward each pole (the last on it), columns from both sides into the
// gap, at spacings of 1, 2, 4 ... times the data's median spacing, so that few are added however
// small the region. Nothing interpolates into them but from the data's last points.
struct PaddedAxis {
    static constexpr size_t kPadding = SIZE_MAX;
    std::vector<double> deg;     // ascending (lon within [0, 360))
    std::vector<size_t> source;  // per point its index in the input, or kPadding
    // The data's extent (south, north; or west, east, west > east across 0°), or none: no padding.
    std::optional<std::array<double, 2>> extent;
};
// `ascendingDeg`: latitudes (degrees north) or longitudes (degrees east within [0, 360)), ascending.
PaddedAxis padToGlobe(const std::vector<double>& ascendingDeg, bool latitude);

// The gradient of a field at every grid point in the grid's own directions, per degree of latitude,
// per km of radius and per degree of longitude: central differences over the two neighbours
// (x[i+1] - x[i-1] apart), one-sided at the outermost rows and radii, wrapped across the lon seam.
// Trilinear interpolation of these (as of the field itself) gives the gradient between grid points;
// the ray caster's shading maps it to Cartesian with the local unit vectors.
struct NodeGradient {
    size_t count = 0;                // grid.cellCount()
    SpareArray<float> values;  // 3 * count: per degree lat, then per km r, then per degree lon (core/spare_blocks.h)
    const float* perDegLat() const { return values.get(); }
    const float* perKmR() const { return values.get() + count; }
    const float* perDegLon() const { return values.get() + 2 * count; }
};
NodeGradient nodeGradient(const SphericalGrid& grid, const float* values);

// Bricks partition the index space of one level for empty-space skipping. Brick (bLat, bR, bLon)
// covers grid points [b * size, (b + 1) * size) along each axis; its bounds are taken over the
// points [b * size, (b + 1) * size] inclusive (one point of overlap, lon wrapping), so that they
// contain every trilinear value a ray can sample inside the brick.
struct BrickLayout {
    uint32_t size = 8;  // grid points per brick along each axis
    std::array<uint32_t, 3> count{};  // bricks along lat, r, lon

    static BrickLayout forGrid(const SphericalGrid& grid, uint32_t size = 8);
    size_t brickCount() const { return size_t(count[0]) * count[1] * count[2]; }
    size_t index(uint32_t bLat, uint32_t bR, uint32_t bLon) const
    {
        return (size_t(bLat) * count[1] + bR) * count[2] + bLon;
    }
};

}  // namespace raypc::grid
