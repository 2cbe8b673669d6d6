#include "dataset/value_encoding.h"

#include "dataset/shell_anomaly.h"

#include "core/error.h"

#include <tbb/blocked_range.h>
#include <tbb/enumerable_thread_specific.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <vector>

namespace raypc::dataset {
// Named rather than anonymous: Uint16PointDecoder's tables (declared in the header) hold its types.
namespace value_encoding_detail {

constexpr double kLevels = 65535.0;
// A variable with missing values keeps the highest code for them (kMissingCode: NaN) and quantises
// into the others.
constexpr uint16_t kMissingCode = 65535;
double levelsOf(bool missing) { return missing ? kLevels - 1 : kLevels; }

// The bricks along one axis whose stored bounds include a point: the owner first (i / size),
// then the others. computeBrickBounds' rule: brick b covers points [b·s, (b+1)·s], clamped at the
// last point, or for lon k = 0 … min(s + 1, n) − 1 points from b·s on, wrapping to column 0.
struct AxisCover {
    std::array<uint32_t, 3> bricks{};
    uint32_t count = 0;
};

AxisCover coverOf(size_t i, size_t n, uint32_t size, uint32_t brickCount, bool wraps)
{
    AxisCover c{{uint32_t(i / size)}, 1};
    if (!wraps) {
        // b·s <= i <= min((b + 1)·s, n − 1): the owner, and the brick before when i starts a brick.
        if (i % size == 0 && i > 0)
            c.bricks[c.count++] = uint32_t(i / size - 1);
        return c;
    }
    // Brick b covers i when i lies less than `points` columns after b·s (mod n): b·s <= i only for the
    // owner and the brick before it, b·s > i (wrapping) only for the last brick. Only those are tried
    // (decodeUint16Point asks this for every point it decodes), in increasing order.
    const size_t points = std::min<size_t>(size + 1, n);
    const uint32_t owner = c.bricks[0];
    for (const uint32_t b : {owner > 0 ? owner - 1 : brickCount, brickCount - 1})
        if (b < brickCount && b != owner && (c.count < 2 || b != c.bricks[1]) &&
            (i + n - (size_t(b) * size) % n) % n < points) {
            RAYPC_CHECK_LT(c.count, 3u);
            c.bricks[c.count++] = b;
        }
    return c;
}

std::vector<AxisCover> axisCover(size_t n, uint32_t size, uint32_t brickCount, bool wraps)
{
    std::vector<AxisCover> cover(n);
    for (size_t i = 0; i < n; ++i)
        cover[i] = coverOf(i, n, size, brickCount, wraps);
    return cover;
}

struct Covers {
    std::vector<AxisCover> lat, r, lon;
    std::vector<uint32_t> lonShared;  // the lon indices covered by more than one brick, ascending
    Covers(const grid::SphericalGrid& g, const grid::BrickLayout& l)
        : lat(axisCover(g.nLat(), l.size, l.count[0], false)), r(axisCover(g.nR(), l.size, l.count[1], false)),
          lon(axisCover(g.nLon(), l.size, l.count[2], true))
    {
        for (size_t i = 0; i < lon.size(); ++i)
            if (lon[i].count > 1)
                lonShared.push_back(uint32_t(i));
    }
};

// Narrows [lo, hi] to the bounds of every brick in lat × r × lon.
void intersectBounds(const grid::BrickLayout& layout, std::span<const float> bounds, const AxisCover& lat,
                     const AxisCover& r, const AxisCover& lon, float& lo, float& hi)
{
    for (uint32_t a = 0; a < lat.count; ++a)
        for (uint32_t b = 0; b < r.count; ++b)
            for (uint32_t c = 0; c < lon.count; ++c) {
                const size_t brick = layout.index(lat.bricks[a], r.bricks[b], lon.bricks[c]);
                lo = std::max(lo, bounds[2 * brick]);
                hi = std::min(hi, bounds[2 * brick + 1]);
            }
}

}  // namespace value_encoding_detail

std::string_view encodingName(ValueEncoding encoding)
{
    return encoding == ValueEncoding::Uint16 ? "u16" : "float32";
}

ValueEncoding parseEncoding(std::string_view name, std::string_view what)
{
    if (name == "u16")
        return ValueEncoding::Uint16;
    if (name == "float32")
        return ValueEncoding::Float32;
    fail("{}: encoding '{}' is unknown, expected float32 or u16", what, name);
}

double uint16ErrorBound(float min, float max, bool missing)
{
    using namespace value_encoding_detail;
    return min <= max ? (double(max) - double(min)) / (2 * levelsOf(missing)) : 0.0;
}

void encodeUint16(const grid::SphericalGrid& grid, const grid::BrickLayout& layout, std::span<const float> values,
                  std::span<const float> bounds, std::span<uint16_t> out, bool missing)
{
    using namespace value_encoding_detail;
    const double levels = levelsOf(missing);
    RAYPC_CHECK_EQ(values.size(), grid.cellCount());
    RAYPC_CHECK_EQ(out.size(), grid.cellCount());
    RAYPC_CHECK_EQ(bounds.size(), 2 * layout.brickCount());
    const size_t nR = grid.nR(), nLon = grid.nLon(), s = layout.size;
    tbb::parallel_for(tbb::blocked_range<size_t>(0, grid.nLat() * nR), [&](const auto& rows) {
        for (size_t row = rows.begin(); row != rows.end(); ++row) {
            const size_t iLat = row / nR, iR = row % nR, first = row * nLon;
            for (uint32_t c = 0; c < layout.count[2]; ++c) {
                // Each point with the bounds of the brick that owns it.
                const size_t brick = layout.index(uint32_t(iLat / s), uint32_t(iR / s), c);
                const double lo = bounds[2 * brick], hi = bounds[2 * brick + 1];
                const size_t end = std::min(size_t(c + 1) * s, nLon);
                // A brick whose values are all missing has the bounds (+inf, -inf).
                RAYPC_CHECK((std::isfinite(lo) && std::isfinite(hi) && lo <= hi) || (missing && lo > hi));
                const double perUnit = hi > lo ? levels / (hi - lo) : 0.0;
                // Points within the brick's bounds (all of them, unless missing or bounds that are
                // not the values' own): t = (x − lo)·perUnit lies in [0, levels] up to rounding, so
                // rounding first and clamping the integer gives the codes of the loop below, in two
                // loops without a branch, which the compiler vectorises (it keeps the loop below's
                // clamp in double as branches).
                const float* x = values.data() + first;
                const float bottom = bounds[2 * brick], top = bounds[2 * brick + 1];
                int outside = 0;
                for (size_t iLon = size_t(c) * s; iLon < end; ++iLon)
                    outside |= !(x[iLon] >= bottom) | !(x[iLon] <= top);
                if (!outside) {
                    const int32_t maxCode = int32_t(levels);
                    for (size_t iLon = size_t(c) * s; iLon < end; ++iLon) {
                        const int32_t code = int32_t((double(x[iLon]) - lo) * perUnit + 0.5);
                        out[first + iLon] = uint16_t(std::min(maxCode, std::max(0, code)));
                    }
                    continue;
                }
                for (size_t iLon = size_t(c) * s; iLon < end; ++iLon) {
                    if (std::isnan(values[first + iLon])) {
                        RAYPC_CHECK(missing);
                        out[first + iLon] = kMissingCode;
                        continue;
                    }
                    const double t = std::clamp((double(values[first + iLon]) - lo) * perUnit, 0.0, levels);
                    // t >= 0: rounding half up is lround's half away from zero, without its call.
                    out[first + iLon] = uint16_t(t + 0.5);
                }
            }
        }
    });
}

namespace value_encoding_detail {

// decodeUint16 of one row (iLat, iR) into `out` (its nLon values).
void decodeRow(const grid::SphericalGrid& grid, const grid::BrickLayout& layout, const Covers& cover,
               std::span<const uint16_t> encoded, std::span<const float> bounds, bool missing, size_t row, float* out)
{
    const double levels = levelsOf(missing);
    const size_t nR = grid.nR(), nLon = grid.nLon(), s = layout.size;
    const size_t iLat = row / nR, iR = row % nR;
    const uint16_t* codes = encoded.data() + row * nLon;
    const AxisCover& lat = cover.lat[iLat];
    const AxisCover& r = cover.r[iR];
    size_t nextShared = 0;  // into cover.lonShared: the first not visited yet
    for (uint32_t c = 0; c < layout.count[2]; ++c) {
        const size_t brick = layout.index(lat.bricks[0], r.bricks[0], c);
        const float min = bounds[2 * brick], max = bounds[2 * brick + 1];
        // Points this row shares with lat or r neighbours' bricks are clamped into theirs too.
        float lo = min, hi = max;
        if (lat.count > 1 || r.count > 1)
            intersectBounds(layout, bounds, lat, r, AxisCover{{c}, 1}, lo, hi);
        const size_t begin = size_t(c) * s, end = std::min(begin + s, nLon);
        // A row that lies in a brick of nothing but missing values is missing too.
        if (missing && !(lo <= hi)) {
            std::fill(out + begin, out + end, NAN);
            continue;
        }
        const double scale = (double(max) - double(min)) / levels;
        // The brick's points in one tight loop (clamped in double, so that rounding to float
        // cannot leave [lo, hi]), then the few shared with lon neighbours' bricks. The clamp is
        // std::clamp's, written as two selects so that the compiler vectorises the loop.
        const double lower = lo, upper = hi;
        for (size_t iLon = begin; iLon < end; ++iLon) {
            const double v = double(min) + double(codes[iLon]) * scale;
            const double atMost = upper < v ? upper : v;
            out[iLon] = float(v < lower ? lower : atMost);
        }
        auto shared = [&](size_t iLon) {
            float l = lo, h = hi;
            intersectBounds(layout, bounds, lat, r, cover.lon[iLon], l, h);
            out[iLon] = l <= h ? std::clamp(out[iLon], l, h) : NAN;
        };
        if (missing) {
            for (size_t iLon = begin; iLon < end; ++iLon)
                if (codes[iLon] == kMissingCode)
                    out[iLon] = NAN;
                else if (cover.lon[iLon].count > 1)
                    shared(iLon);
            continue;
        }
        // Without missing values only the shared points change: visited from their list.
        for (; nextShared < cover.lonShared.size() && cover.lonShared[nextShared] < end; ++nextShared)
            if (cover.lonShared[nextShared] >= begin)
                shared(cover.lonShared[nextShared]);
    }
}

void checkDecodeSizes(const grid::SphericalGrid& grid, const grid::BrickLayout& layout,
                      std::span<const uint16_t> encoded, std::span<const float> bounds)
{
    RAYPC_CHECK_EQ(encoded.size(), grid.cellCount());
    RAYPC_CHECK_EQ(bounds.size(), 2 * layout.brickCount());
}

}  // namespace value_encoding_detail

void decodeUint16(const grid::SphericalGrid& grid, const grid::BrickLayout& layout, std::span<const uint16_t> encoded,
                  std::span<const float> bounds, std::span<float> out, bool missing)
{
    using namespace value_encoding_detail;
    checkDecodeSizes(grid, layout, encoded, bounds);
    RAYPC_CHECK_EQ(out.size(), grid.cellCount());
    const Covers cover(grid, layout);
    tbb::parallel_for(tbb::blocked_range<size_t>(0, grid.nLat() * grid.nR()), [&](const auto& rows) {
        for (size_t row = rows.begin(); row != rows.end(); ++row)
            decodeRow(grid, layout, cover, encoded, bounds, missing, row, out.data() + row * grid.nLon());
    });
}

std::vector<double> shellMeansOfUint16(const grid::SphericalGrid& grid, const grid::BrickLayout& layout,
                                       std::span<const uint16_t> encoded, std::span<const float> bounds, bool missing)
{
    using namespace value_encoding_detail;
    checkDecodeSizes(grid, layout, encoded, bounds);
    const Covers cover(grid, layout);
    const auto w = grid.volumeFactors();
    const size_t nLat = grid.nLat(), nR = grid.nR(), nLon = grid.nLon();
    std::vector<double> means(nR);
    // kShellsAtOnce shells decoded, then their means summed side by side (shellMeansSideBySide).
    tbb::enumerable_thread_specific<std::vector<float>> buffers(
        [&] { return std::vector<float>(kShellsAtOnce * nLat * nLon); });
    const size_t groups = (nR + kShellsAtOnce - 1) / kShellsAtOnce;
    tbb::parallel_for(size_t(0), groups, [&](size_t group) {
        std::vector<float>& buffer = buffers.local();
        const size_t first = group * kShellsAtOnce, count = std::min(kShellsAtOnce, nR - first);
        std::array<const float*, kShellsAtOnce> shells{};
        for (size_t k = 0; k < count; ++k) {
            float* shell = buffer.data() + k * nLat * nLon;
            for (size_t iLat = 0; iLat < nLat; ++iLat)
                decodeRow(grid, layout, cover, encoded, bounds, missing, iLat * nR + first + k, shell + iLat * nLon);
            shells[k] = shell;
        }
        shellMeansSideBySide(w, shells.data(), count, nLon, means.data() + first);
    });
    return means;
}

}  // namespace raypc::dataset

namespace raypc::dataset {

namespace value_encoding_detail {

// decodeUint16's steps for one point, its covers along each axis given, so that both give the same bits.
float decodePoint(const grid::BrickLayout& layout, const float* bounds, uint16_t code, const AxisCover& lat,
                  const AxisCover& r, const AxisCover& lon, bool missing)
{
    if (missing && code == kMissingCode)
        return NAN;
    const size_t brick = layout.index(lat.bricks[0], r.bricks[0], lon.bricks[0]);
    const float min = bounds[2 * brick], max = bounds[2 * brick + 1];
    float lo = min, hi = max;
    const std::span<const float> all(bounds, 2 * layout.brickCount());
    if (lat.count > 1 || r.count > 1)
        intersectBounds(layout, all, lat, r, AxisCover{{lon.bricks[0]}, 1}, lo, hi);
    if (missing && !(lo <= hi))
        return NAN;
    const double scale = (double(max) - double(min)) / levelsOf(missing);
    const double v = double(min) + double(code) * scale;
    float value = float(std::clamp(v, double(lo), double(hi)));
    if (lon.count > 1) {
        intersectBounds(layout, all, lat, r, lon, lo, hi);
        value = lo <= hi ? std::clamp(value, lo, hi) : NAN;
    }
    return value;
}

}  // namespace value_encoding_detail

float decodeUint16Point(const grid::SphericalGrid& grid, const grid::BrickLayout& layout, const uint16_t* encoded,
                        const float* bounds, size_t iLat, size_t iR, size_t iLon, bool missing)
{
    using namespace value_encoding_detail;
    return decodePoint(layout, bounds, encoded[grid.index(iLat, iR, iLon)],
                       coverOf(iLat, grid.nLat(), layout.size, layout.count[0], false),
                       coverOf(iR, grid.nR(), layout.size, layout.count[1], false),
                       coverOf(iLon, grid.nLon(), layout.size, layout.count[2], true), missing);
}

struct Uint16PointDecoder::Tables : value_encoding_detail::Covers {
    using Covers::Covers;
};

Uint16PointDecoder::Uint16PointDecoder(const grid::SphericalGrid& grid, const grid::BrickLayout& layout)
    : m_layout(layout), m_tables(std::make_shared<const Tables>(grid, layout))
{
}

float Uint16PointDecoder::decode(const uint16_t* encoded, const float* bounds, size_t index, size_t iLat, size_t iR,
                                 size_t iLon, bool missing) const
{
    using namespace value_encoding_detail;
    return decodePoint(m_layout, bounds, encoded[index], m_tables->lat[iLat], m_tables->r[iR], m_tables->lon[iLon],
                       missing);
}

}  // namespace raypc::dataset
