// How a dataset stores its level arrays (docs/format.md, "Encoding of the level arrays").
//
// Uint16: every grid point is quantised with the (min, max) of the brick that owns it (the
// brick whose cells start at or before the point along every axis, BrickLayout's
// index(i / size, …)): u = round((v − min) / (max − min) · 65535), 0 when max == min. Decoding
// gives min + u · (max − min) / 65535, clamped into the bounds of every brick whose stored bounds
// include the point (computeBrickBounds' rule: one point of overlap, lon wrapping), so
// - |decoded − v| ≤ (max − min) / 131070 of the owning brick, plus the float32 rounding of the
//   decoded value (half an ulp), and
// - every decoded value lies within the stored bounds of every brick that covers it: skipping a
//   brick by its bounds stays exact for the decoded field.
// A variable with missing values (NaN) encodes them as u = 65535 and quantises the others into 0 …
// 65534 (`missing`: the step's missing_points > 0 in the manifest); a brick whose values are all
// missing has the bounds (+inf, −inf).
// Float32: the values as they are (NaN where missing).
#pragma once

#include "grid/grid.h"

#include <cstdint>
#include <memory>
#include <span>
#include <string_view>
#include <vector>

namespace raypc::dataset {

enum class ValueEncoding { Float32, Uint16 };

// "float32" or "u16": the manifest's `encoding` and `raypc preprocess --encoding`.
std::string_view encodingName(ValueEncoding encoding);
// Throws raypc::Error "<what>: encoding 'x' is unknown, expected float32 or u16".
ValueEncoding parseEncoding(std::string_view name, std::string_view what);

// The largest quantisation error of a point owned by a brick with bounds [min, max], without the
// float32 rounding of the decoded value: (max − min) / 131070.
double uint16ErrorBound(float min, float max, bool missing = false);

// Encodes `values` (grid.cellCount(), canonical order, finite) with the brick bounds `bounds`
// (layout.brickCount() pairs, as computeBrickBounds writes them) into `out`. Parallel over rows.
void encodeUint16(const grid::SphericalGrid& grid, const grid::BrickLayout& layout, std::span<const float> values,
                  std::span<const float> bounds, std::span<uint16_t> out, bool missing = false);

// Decodes what encodeUint16 wrote, with the same bounds. Bounds must be finite with min <= max
// (Dataset::load checks them). Parallel over rows (oneTBB); allocates only per-axis tables.
void decodeUint16(const grid::SphericalGrid& grid, const grid::BrickLayout& layout, std::span<const uint16_t> encoded,
                  std::span<const float> bounds, std::span<float> out, bool missing = false);

// shellMeans (shell_anomaly.h) of what decodeUint16 gives, bit for bit, decoding one shell at a time
// instead of the whole array (what a writer stores for the readers' shell anomalies).
std::vector<double> shellMeansOfUint16(const grid::SphericalGrid& grid, const grid::BrickLayout& layout,
                                       std::span<const uint16_t> encoded, std::span<const float> bounds,
                                       bool missing = false);

// The value decodeUint16 gives point (iLat, iR, iLon), bit for bit, decoding that point alone (for
// sparse reads: a few samples of a variable that is not decoded).
float decodeUint16Point(const grid::SphericalGrid& grid, const grid::BrickLayout& layout, const uint16_t* encoded,
                        const float* bounds, size_t iLat, size_t iR, size_t iLon, bool missing = false);

// decodeUint16Point for many points of one grid and brick layout (a step's sparse reads: a
// selection's features), with the bricks that cover each index along each axis found once (the
// tables decodeUint16 builds) instead of per point: the same bits. Immutable and thread-safe; cheap to
// copy (the tables are shared).
class Uint16PointDecoder {
public:
    Uint16PointDecoder(const grid::SphericalGrid& grid, const grid::BrickLayout& layout);
    // The value of point (iLat, iR, iLon), `index` = grid.index(iLat, iR, iLon), of the variable
    // `encoded` with brick bounds `bounds` (as decodeUint16Point takes them).
    float decode(const uint16_t* encoded, const float* bounds, size_t index, size_t iLat, size_t iR, size_t iLon,
                 bool missing) const;

private:
    struct Tables;
    grid::BrickLayout m_layout;
    std::shared_ptr<const Tables> m_tables;
};

}  // namespace raypc::dataset
