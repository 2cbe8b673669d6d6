#include "dataset/bricks.h"

#include "core/error.h"

#include <tbb/parallel_for.h>

#include <algorithm>
#include <array>
#include <limits>

namespace raypc::dataset {

namespace {

// The lowest and highest of values [begin, end) of a row, added into lo and hi as std::min and
// std::max would one value after another (a NaN is passed over).
struct RowExtremes {
    // Four running extremes, each of every fourth value: chains a quarter as long, which the
    // compiler turns into vector minimum and maximum. Their lowest is the sequential one's value; it
    // has the same bits unless it is a zero, whose sign depends on the order (then recomputed).
    std::array<float, 4> lo, hi;
    RowExtremes()
    {
        lo.fill(std::numeric_limits<float>::infinity());
        hi.fill(-std::numeric_limits<float>::infinity());
    }
    void add(const float* row, size_t begin, size_t end)
    {
        size_t i = begin;
        for (; i + 4 <= end; i += 4)
            for (size_t j = 0; j < 4; ++j) {
                const float x = row[i + j];
                lo[j] = x < lo[j] ? x : lo[j];
                hi[j] = hi[j] < x ? x : hi[j];
            }
        for (; i < end; ++i) {
            lo[0] = std::min(lo[0], row[i]);
            hi[0] = std::max(hi[0], row[i]);
        }
    }
};

// computeBrickBounds' bounds of one brick, value after value in its order (the rule where the
// order matters: a zero's sign).
void brickBoundsInOrder(const grid::SphericalGrid& grid, std::span<const float> values, size_t lat0, size_t lat1,
                        size_t r0, size_t r1, size_t lon0, size_t lonCount, float& lo, float& hi)
{
    const size_t nLon = grid.nLon();
    lo = std::numeric_limits<float>::infinity();
    hi = -lo;
    for (size_t iLat = lat0; iLat <= lat1; ++iLat)
        for (size_t iR = r0; iR <= r1; ++iR) {
            const float* row = values.data() + grid.index(iLat, iR, 0);
            for (size_t k = 0; k < lonCount; ++k) {
                size_t iLon = lon0 + k;
                if (iLon >= nLon)
                    iLon -= nLon;
                lo = std::min(lo, row[iLon]);
                hi = std::max(hi, row[iLon]);
            }
        }
}

}  // namespace

void computeBrickBounds(const grid::SphericalGrid& grid, const grid::BrickLayout& layout, std::span<const float> values,
                        std::span<float> bounds)
{
    RAYPC_CHECK_EQ(values.size(), grid.cellCount());
    RAYPC_CHECK_EQ(bounds.size(), 2 * layout.brickCount());
    const size_t nLat = grid.nLat(), nR = grid.nR(), nLon = grid.nLon(), s = layout.size;
    tbb::parallel_for(tbb::blocked_range<size_t>(0, layout.brickCount()), [&](const auto& range) {
        for (size_t b = range.begin(); b != range.end(); ++b) {
            const size_t bLon = b % layout.count[2];
            const size_t bR = (b / layout.count[2]) % layout.count[1];
            const size_t bLat = b / (size_t(layout.count[2]) * layout.count[1]);
            // Points [b*s, (b+1)*s] inclusive; lat and r clamp at the grid's ends, lon wraps.
            const size_t lat0 = bLat * s, lat1 = std::min((bLat + 1) * s, nLat - 1);
            const size_t r0 = bR * s, r1 = std::min((bR + 1) * s, nR - 1);
            const size_t lon0 = bLon * s, lonCount = std::min(s + 1, nLon);
            // The brick's columns: lon0 … up to the grid's end, then from column 0 when it wraps.
            const size_t lonEnd = std::min(lon0 + lonCount, nLon), wrapped = lon0 + lonCount - lonEnd;
            RowExtremes extremes;
            for (size_t iLat = lat0; iLat <= lat1; ++iLat)
                for (size_t iR = r0; iR <= r1; ++iR) {
                    const float* row = values.data() + grid.index(iLat, iR, 0);
                    extremes.add(row, lon0, lonEnd);
                    extremes.add(row, 0, wrapped);
                }
            float lo = extremes.lo[0], hi = extremes.hi[0];
            for (size_t j = 1; j < 4; ++j) {
                lo = std::min(lo, extremes.lo[j]);
                hi = std::max(hi, extremes.hi[j]);
            }
            if (lo == 0 || hi == 0)
                brickBoundsInOrder(grid, values, lat0, lat1, r0, r1, lon0, lonCount, lo, hi);
            bounds[2 * b] = lo;
            bounds[2 * b + 1] = hi;
        }
    });
}

}  // namespace raypc::dataset
