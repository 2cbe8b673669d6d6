#include "dataset/bricks.h"

#include "core/error.h"

#include <tbb/parallel_for.h>

#include <algorithm>
#include <limits>

namespace raypc::dataset {

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
            float lo = std::numeric_limits<float>::infinity(), hi = -lo;
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
            bounds[2 * b] = lo;
            bounds[2 * b + 1] = hi;
        }
    });
}

}  // namespace raypc::dataset
