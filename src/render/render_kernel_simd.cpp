// The SIMD kernel: each vector holds consecutive samples along one ray; a chunk of kChunkSamples (16)
// samples is one AVX-512 vector, two AVX2 vectors or four SSE4 vectors, and shares one step length,
// so the sample positions do not depend on the SIMD width. Coordinates, cell location, the
// trilinear gathers, brushing and the transfer function run across lanes; front-to-back compositing
// is the short sequential tail over the lanes that have any opacity.
// Highway with dynamic dispatch: compiled for the x86 targets Highway knows (SSE4, AVX2, AVX-512)
// and the best one is chosen at run time — no -march flag is needed for the project.
#undef HWY_TARGET_INCLUDE
#define HWY_TARGET_INCLUDE "render/render_kernel_simd.cpp"
#include <hwy/foreach_target.h>  // IWYU pragma: keep

#include <hwy/contrib/math/math-inl.h>
#include <hwy/highway.h>

#include "render/render_kernel.h"

HWY_BEFORE_NAMESPACE();
namespace raypc::render::kernel::HWY_NAMESPACE {
namespace hn = hwy::HWY_NAMESPACE;

// At most 16 lanes so that a vector never spans two chunks.
using DF = hn::CappedTag<float, kChunkSamples>;
using DI = hn::RebindToSigned<DF>;
using VF = hn::Vec<DF>;
using VI = hn::Vec<DI>;
using MF = hn::Mask<DF>;
using MI = hn::Mask<DI>;
#if HWY_TARGET != HWY_SCALAR
// Lon neighbour pairs: half as many 64-bit lanes, each holding the values at iLon0 and iLon0 + 1.
using DH = hn::Half<DI>;
using D64 = hn::Rebind<int64_t, DH>;
#endif

constexpr size_t kMaxLanes = HWY_MAX_BYTES / sizeof(float);

HWY_INLINE VF AtanUnit(DF d, VF a)
{
    const VF s = hn::Mul(a, a);
    VF p = hn::Set(d, -0.01172120f);
    p = hn::MulAdd(p, s, hn::Set(d, 0.05265332f));
    p = hn::MulAdd(p, s, hn::Set(d, -0.11643287f));
    p = hn::MulAdd(p, s, hn::Set(d, 0.19354346f));
    p = hn::MulAdd(p, s, hn::Set(d, -0.33262347f));
    p = hn::MulAdd(p, s, hn::Set(d, 0.99997726f));
    return hn::Mul(p, a);
}

HWY_INLINE VF FastAtan2(DF d, VF y, VF x)
{
    const VF ax = hn::Abs(x), ay = hn::Abs(y);
    const VF mx = hn::Max(ax, ay), mn = hn::Min(ax, ay);
    const MF nonzero = hn::Gt(mx, hn::Zero(d));
    const VF a = hn::IfThenElseZero(nonzero, hn::Div(mn, hn::IfThenElse(nonzero, mx, hn::Set(d, 1.0f))));
    VF r = AtanUnit(d, a);
    r = hn::IfThenElse(hn::Gt(ay, ax), hn::Sub(hn::Set(d, float(std::numbers::pi / 2)), r), r);
    r = hn::IfThenElse(hn::Lt(x, hn::Zero(d)), hn::Sub(hn::Set(d, float(std::numbers::pi)), r), r);
    return hn::IfThenElse(hn::Lt(y, hn::Zero(d)), hn::Neg(r), r);
}

HWY_INLINE VF Clamp(VF v, VF lo, VF hi) { return hn::Min(hn::Max(v, lo), hi); }

HWY_INLINE VF MapAxis(DF d, const AxisMap& m, VF c)
{
    if (m.affine) {
        const VF f = hn::MulAdd(c, hn::Set(d, m.scale), hn::Set(d, m.offset));
        if (!(m.breakCoord < INFINITY))
            return f;
        return hn::IfThenElse(hn::Le(c, hn::Set(d, m.breakCoord)), f,
                              hn::MulAdd(c, hn::Set(d, m.scale2), hn::Set(d, m.offset2)));
    }
    const DI di;
    const VF u = Clamp(hn::Mul(hn::Sub(c, hn::Set(d, m.coordMin)), hn::Set(d, m.invTableStep)), hn::Zero(d),
                       hn::Set(d, float(m.tableLast) - 1e-3f));
    const VI ki = hn::ConvertTo(di, u);
    const VF t0 = hn::GatherIndex(d, m.table, ki);
    const VF t1 = hn::GatherIndex(d, m.table + 1, ki);
    return hn::MulAdd(hn::Sub(u, hn::ConvertTo(d, ki)), hn::Sub(t1, t0), t0);
}

struct LocatedV {
    VI o00, o01, o10, o11, iLon0, iLon1, capIndex, brick;
    VF wLat, wR, wLon, cap;
    VF latDeg, lonDeg, rKm;
    bool anyCap;
    bool anySeam;  // some lane has iLon0 = nLon - 1 (its lon neighbour wraps to 0)
};

HWY_INLINE LocatedV Locate(DF d, const KernelParams& k, VF x, VF y, VF z)
{
    const DI di;
    LocatedV L;
    const VF rho = hn::Sqrt(hn::MulAdd(x, x, hn::Mul(y, y)));
    L.rKm = hn::Sqrt(hn::MulAdd(rho, rho, hn::Mul(z, z)));
    const VF toDeg = hn::Set(d, kRadToDeg);
    L.latDeg = hn::Mul(FastAtan2(d, z, rho), toDeg);
    const VF lon = hn::Mul(FastAtan2(d, y, x), toDeg);
    L.lonDeg = hn::IfThenElse(hn::Lt(lon, hn::Zero(d)), hn::Add(lon, hn::Set(d, 360.0f)), lon);

    const VF fLat = Clamp(MapAxis(d, k.lat, L.latDeg), hn::Zero(d), hn::Set(d, float(k.nLat - 1)));
    const VI iLat0 = hn::Min(hn::ConvertTo(di, fLat), hn::Set(di, k.nLat - 2));
    L.wLat = hn::Sub(fLat, hn::ConvertTo(d, iLat0));
    const VF fR = Clamp(MapAxis(d, k.r, L.rKm), hn::Zero(d), hn::Set(d, float(k.nR - 1)));
    const VI iR0 = hn::Min(hn::ConvertTo(di, fR), hn::Set(di, k.nR - 2));
    L.wR = hn::Sub(fR, hn::ConvertTo(d, iR0));
    const VF nLonF = hn::Set(d, float(k.nLon));
    VF fLon = MapAxis(d, k.lon, L.lonDeg);
    fLon = hn::IfThenElse(hn::Lt(fLon, hn::Zero(d)), hn::Add(fLon, nLonF), fLon);
    fLon = hn::IfThenElse(hn::Ge(fLon, nLonF), hn::Sub(fLon, nLonF), fLon);
    L.iLon0 = hn::Min(hn::ConvertTo(di, fLon), hn::Set(di, k.nLon - 1));
    L.wLon = hn::Sub(fLon, hn::ConvertTo(d, L.iLon0));
    const VI next = hn::Add(L.iLon0, hn::Set(di, 1));
    const MI seam = hn::Eq(next, hn::Set(di, k.nLon));
    L.iLon1 = hn::IfThenZeroElse(seam, next);
    L.anySeam = !hn::AllFalse(di, seam);

    L.o00 = hn::Mul(hn::Add(hn::Mul(iLat0, hn::Set(di, k.nR)), iR0), hn::Set(di, k.nLon));
    L.o01 = hn::Add(L.o00, hn::Set(di, k.nLon));
    L.o10 = hn::Add(L.o00, hn::Set(di, k.nR * k.nLon));
    L.o11 = hn::Add(L.o10, hn::Set(di, k.nLon));

    L.cap = hn::Add(hn::Max(hn::Zero(d), hn::Mul(hn::Sub(hn::Set(d, k.latSouthDeg), L.latDeg), hn::Set(d, k.capScaleSouth))),
                    hn::Max(hn::Zero(d), hn::Mul(hn::Sub(L.latDeg, hn::Set(d, k.latNorthDeg)), hn::Set(d, k.capScaleNorth))));
    L.anyCap = !hn::AllFalse(d, hn::Gt(L.cap, hn::Zero(d)));
    L.capIndex = hn::Add(hn::IfThenElseZero(hn::RebindMask(di, hn::Gt(L.latDeg, hn::Zero(d))), hn::Set(di, k.nR)), iR0);
    if (k.brickActive) {
        const int s = k.brickShift;
        L.brick = hn::Add(hn::Mul(hn::Add(hn::Mul(hn::ShiftRightSame(iLat0, s), hn::Set(di, k.bricksR)),
                                          hn::ShiftRightSame(iR0, s)),
                                  hn::Set(di, k.bricksLon)),
                          hn::ShiftRightSame(L.iLon0, s));
    }
    return L;
}

HWY_INLINE VF LerpV(VF a, VF b, VF w) { return hn::MulAdd(w, hn::Sub(b, a), a); }

// Lon-interpolated value of one (lat, r) corner row at byte offsets 4 (row + iLon0): the two lon
// neighbours are adjacent in memory, so one 64-bit gather per pair fetches both (half as many
// element loads as two 32-bit gathers); used when no lane wraps at the lon seam.
#if HWY_TARGET != HWY_SCALAR
#define RAYPC_LON_PAIRS 1
HWY_INLINE VF LonPair(DF d, const float* p, VI idx, VF wLon)
{
    const DH dh;
    const D64 d64;
    const VI off = hn::ShiftLeft<2>(idx);
    const int64_t* base = reinterpret_cast<const int64_t*>(p);
    const VF lo = hn::BitCast(d, hn::GatherOffset(d64, base, hn::PromoteTo(d64, hn::LowerHalf(dh, off))));
    const VF hi = hn::BitCast(d, hn::GatherOffset(d64, base, hn::PromoteTo(d64, hn::UpperHalf(dh, off))));
    return LerpV(hn::ConcatEven(d, hi, lo), hn::ConcatOdd(d, hi, lo), wLon);
}
#else
#define RAYPC_LON_PAIRS 0
#endif

HWY_INLINE VF Sample(DF d, const KernelParams& k, const KernelVariable& v, const LocatedV& L)
{
    const float* p = v.values;
    VF c00, c01, c10, c11;
    if (RAYPC_LON_PAIRS && !L.anySeam) {
#if RAYPC_LON_PAIRS
        c00 = LonPair(d, p, hn::Add(L.o00, L.iLon0), L.wLon);
        c01 = LonPair(d, p, hn::Add(L.o01, L.iLon0), L.wLon);
        c10 = LonPair(d, p, hn::Add(L.o10, L.iLon0), L.wLon);
        c11 = LonPair(d, p, hn::Add(L.o11, L.iLon0), L.wLon);
#endif
    } else {
        c00 = LerpV(hn::GatherIndex(d, p, hn::Add(L.o00, L.iLon0)), hn::GatherIndex(d, p, hn::Add(L.o00, L.iLon1)), L.wLon);
        c01 = LerpV(hn::GatherIndex(d, p, hn::Add(L.o01, L.iLon0)), hn::GatherIndex(d, p, hn::Add(L.o01, L.iLon1)), L.wLon);
        c10 = LerpV(hn::GatherIndex(d, p, hn::Add(L.o10, L.iLon0)), hn::GatherIndex(d, p, hn::Add(L.o10, L.iLon1)), L.wLon);
        c11 = LerpV(hn::GatherIndex(d, p, hn::Add(L.o11, L.iLon0)), hn::GatherIndex(d, p, hn::Add(L.o11, L.iLon1)), L.wLon);
    }
    const VF value = LerpV(LerpV(c00, c01, L.wR), LerpV(c10, c11, L.wR), L.wLat);
    if (!L.anyCap)
        return value;
    // Pole caps: blend towards the ring mean of the outermost row at this radius.
    const VF mean = LerpV(hn::GatherIndex(d, v.capMean, L.capIndex), hn::GatherIndex(d, v.capMean + 1, L.capIndex), L.wR);
    return LerpV(value, mean, L.cap);
}
#undef RAYPC_LON_PAIRS

// scale * component + offset (KernelBrush; the table is coordinateDefinition in data/coordinates.h).
HWY_INLINE VF CoordinateValue(DF d, const KernelBrush& brush, VF x, VF y, VF z, const LocatedV& L)
{
    VF v = x;
    switch (brush.component) {
    case PointComponent::X: v = x; break;
    case PointComponent::Y: v = y; break;
    case PointComponent::Z: v = z; break;
    case PointComponent::LatDeg: v = L.latDeg; break;
    case PointComponent::LonDeg: v = L.lonDeg; break;
    case PointComponent::RKm: v = L.rKm; break;
    }
    return hn::MulAdd(hn::Set(d, brush.scale), v, hn::Set(d, brush.offset));
}

HWY_INLINE VF ColourValueAt(DF d, const KernelParams& k, VF x, VF y, VF z)
{
    return Sample(d, k, k.colour, Locate(d, k, x, y, z));
}

struct Ray {
    Vec3 o, d;
};

// Lane permutations for the prefix products of compositing: shiftUp[s] moves lane i - 2^s to lane i
// (the first 2^s lanes are replaced by the caller). Built once per tile.
using IndicesF = decltype(hn::SetTableIndices(DF(), static_cast<const int32_t*>(nullptr)));
struct LaneShifts {
    IndicesF shiftUp[4];
    LaneShifts()
    {
        const DF d;
        HWY_ALIGN int32_t index[kMaxLanes];
        for (int s = 0; s < 4; ++s) {
            for (int i = 0; i < int(hn::Lanes(d)); ++i)
                index[i] = std::max(i - (1 << s), 0);
            shiftUp[s] = hn::SetTableIndices(d, index);
        }
    }
};

// kMultiRange: some brushed axis has several ranges (decided once per tile, so that the common
// single-range case runs the loop without the test of further ranges).
template <bool kMultiRange>
void MarchSimd(const KernelParams& k, const LaneShifts& shifts, const Ray& ray, float t0, float t1, float along,
               RayAccum& acc, TileStats& stats)
{
    const DF d;
    const DI di;
    const int lanes = int(hn::Lanes(d));
    HWY_ALIGN float tBuf[kMaxLanes];
    const VF iota = hn::Iota(d, 0.0f);
    const VF one = hn::Set(d, 1.0f);
    const VF vStop = hn::Set(d, k.stopTransmittance);
    const VF vDepth = hn::Set(d, k.depthOpacity);
    const VF vT1 = hn::Set(d, t1);
    const VF zero = hn::Zero(d);
    const VF vAlong = hn::Set(d, along);

    const RaySampling rs = raySampling(k, ray.o, ray.d);
    const VF vT0 = hn::Set(d, t0);
    SkipState skip(k, ray.o, ray.d);
    int j = rs.chunkOf(t0);
    float tc = rs.chunkStart(j);
    while (tc < t1 && acc.transmittance > k.stopTransmittance) {
        const float tn = rs.chunkStart(j + 1);
        const float dt = (tn - tc) * (1.0f / float(kChunkSamples));
        ++stats.chunks;
        // Interval skipping: known-empty space is passed over in one jump to the chunk where it ends.
        if (chunkIsEmpty(k, tc, tn, skip)) {
            const int next = chunkAfterEmpty(rs, j, t1, skip);
            countJumped(stats, j, next, tc, dt, t0, t1);
            j = next;
            tc = rs.chunkStart(j);
            continue;
        }
        const VF vdt = hn::Set(d, dt);
        bool anyActive = false;
        for (int base = 0; base < kChunkSamples && acc.transmittance > k.stopTransmittance; base += lanes) {
            // Sample intervals [start, start + dt) clipped to [t0, t1); the sample sits `along` into its
            // interval (clamped to the segment).
            const VF start = hn::MulAdd(hn::Add(iota, hn::Set(d, float(base))), vdt, hn::Set(d, tc));
            const VF end = hn::Add(start, vdt);
            const MF valid = hn::And(hn::Lt(start, vT1), hn::Gt(end, vT0));
            if (hn::AllFalse(d, valid))
                continue;
            const VF len = hn::Sub(hn::Min(end, vT1), hn::Max(start, vT0));
            const VF t = hn::Min(hn::Max(hn::MulAdd(vAlong, vdt, start), vT0), vT1);
            const VF x = hn::MulAdd(t, hn::Set(d, ray.d.x), hn::Set(d, ray.o.x));
            const VF y = hn::MulAdd(t, hn::Set(d, ray.d.y), hn::Set(d, ray.o.y));
            const VF z = hn::MulAdd(t, hn::Set(d, ray.d.z), hn::Set(d, ray.o.z));

            const LocatedV L = Locate(d, k, x, y, z);
            MF active = valid;
            if (k.brickActive) {
                const VI flag = hn::GatherIndex(di, k.brickActive, hn::IfThenElseZero(hn::RebindMask(di, valid), L.brick));
                const MF capOrFlag = hn::Or(hn::Gt(L.cap, zero), hn::RebindMask(d, hn::Ne(flag, hn::Zero(di))));
                active = hn::And(valid, capOrFlag);
            }
            const size_t nValid = hn::CountTrue(d, valid);
            const size_t nActive = hn::CountTrue(d, active);
            stats.samples += nActive;
            stats.samplesSkipped += nValid - nActive;
            if (nActive == 0)
                continue;
            anyActive = true;
            // Brushing: any brush that rejects a lane zeroes it; stop as soon as no lane is left.
            MF keep = active;
            for (int b = 0; b < k.brushCount && !hn::AllFalse(d, keep); ++b) {
                const KernelBrush& brush = k.brushes[b];
                const VF v = brush.onCoordinate ? CoordinateValue(d, brush, x, y, z, L) : Sample(d, k, brush.variable, L);
                keep = hn::And(keep, hn::And(hn::Ge(v, hn::Set(d, brush.min)), hn::Le(v, hn::Set(d, brush.max))));
                // Several ranges on the axis (min, max is their hull): a lane must lie in one of them.
                if (kMultiRange && brush.rangeCount > 1) {
                    MF inOne = hn::FirstN(d, 0);
                    for (int i = 0; i < brush.rangeCount; ++i)
                        inOne = hn::Or(inOne, hn::And(hn::Ge(v, hn::Set(d, brush.ranges[i].min)),
                                                      hn::Le(v, hn::Set(d, brush.ranges[i].max))));
                    keep = hn::And(keep, inOne);
                }
            }
            if (hn::AllFalse(d, keep))
                continue;
            const VF value = Sample(d, k, k.colour, L);
            const VF u = Clamp(hn::MulAdd(hn::Sub(value, hn::Set(d, k.table.valueMin)), hn::Set(d, k.table.indexScale),
                                          hn::Set(d, 0.5f)),
                               zero, hn::Set(d, float(k.table.size - 1)));
            const VI idx = hn::IfThenElseZero(hn::RebindMask(di, keep), hn::ConvertTo(di, u));
            const VF sigma = hn::IfThenElseZero(keep, hn::GatherIndex(d, k.table.sigmaPerKm, idx));
            const MF opaque = hn::Gt(sigma, zero);
            if (hn::AllFalse(d, opaque))
                continue;
            // Opacity correction: alpha = 1 - exp(-sigma * length) for this sample's own interval.
            const VF alpha = hn::IfThenElseZero(
                opaque, hn::Max(zero, hn::Sub(hn::Set(d, 1.0f), hn::Exp(d, hn::Neg(hn::Mul(sigma, len))))));
            VF shade = hn::Set(d, 1.0f);
            if (k.shade) {
                const VF h = hn::Set(d, k.gradientDeltaKm);
                const VF gx = hn::Sub(ColourValueAt(d, k, hn::Add(x, h), y, z), ColourValueAt(d, k, hn::Sub(x, h), y, z));
                const VF gy = hn::Sub(ColourValueAt(d, k, x, hn::Add(y, h), z), ColourValueAt(d, k, x, hn::Sub(y, h), z));
                const VF gz = hn::Sub(ColourValueAt(d, k, x, y, hn::Add(z, h)), ColourValueAt(d, k, x, y, hn::Sub(z, h)));
                const VF g2 = hn::MulAdd(gx, gx, hn::MulAdd(gy, gy, hn::Mul(gz, gz)));
                const VF gl = hn::MulAdd(gx, hn::Set(d, k.lightDir.x),
                                         hn::MulAdd(gy, hn::Set(d, k.lightDir.y), hn::Mul(gz, hn::Set(d, k.lightDir.z))));
                const MF hasGradient = hn::Gt(g2, hn::Set(d, 1e-30f));
                const VF safeG2 = hn::IfThenElse(hasGradient, g2, hn::Set(d, 1.0f));
                const VF lit = hn::MulAdd(hn::Set(d, k.diffuse), hn::Div(hn::Abs(gl), hn::Sqrt(safeG2)), hn::Set(d, k.ambient));
                shade = hn::IfThenElse(hasGradient, lit, shade);
            }
            const VF red = hn::Mul(shade, hn::GatherIndex(d, k.table.red, idx));
            const VF green = hn::Mul(shade, hn::GatherIndex(d, k.table.green, idx));
            const VF blue = hn::Mul(shade, hn::GatherIndex(d, k.table.blue, idx));
            // Front-to-back compositing across the lanes at once: the transmittance after lane i is
            // T (1 - a_0) ... (1 - a_i), an inclusive prefix product (log2(lanes) permute steps).
            // Lanes are composited while the transmittance before them is above the stop threshold
            // (a prefix of the lanes), as the scalar kernel stops mid-chunk; the products are
            // rounded in a different order, so the two kernels agree to rounding.
            VF after = hn::Sub(one, alpha);
            for (int s = 0; (1 << s) < lanes; ++s)
                after = hn::Mul(after, hn::IfThenElse(hn::FirstN(d, size_t(1) << s), one,
                                                      hn::TableLookupLanes(after, shifts.shiftUp[s])));
            const VF vT = hn::Set(d, acc.transmittance);
            const VF tBefore = hn::Mul(vT, hn::IfThenElse(hn::FirstN(d, 1), one, hn::TableLookupLanes(after, shifts.shiftUp[0])));
            const VF tAfter = hn::Mul(vT, after);
            const MF live = hn::Gt(tBefore, vStop);
            const VF w = hn::IfThenElseZero(live, hn::Mul(tBefore, alpha));
            acc.r += hn::GetLane(hn::SumOfLanes(d, hn::Mul(w, red)));
            acc.g += hn::GetLane(hn::SumOfLanes(d, hn::Mul(w, green)));
            acc.b += hn::GetLane(hn::SumOfLanes(d, hn::Mul(w, blue)));
            if (!std::isfinite(acc.depthKm)) {
                const MF deep = hn::And(live, hn::Ge(hn::Sub(one, tAfter), vDepth));
                if (!hn::AllFalse(d, deep)) {
                    hn::Store(t, d, tBuf);
                    acc.depthKm = tBuf[hn::FindKnownFirstTrue(d, deep)];
                }
            }
            acc.transmittance = hn::GetLane(hn::MinOfLanes(d, hn::IfThenElse(live, tAfter, one)));
        }
        skip.probe = !anyActive;
        if (!anyActive)
            ++stats.chunksSkipped;
        ++j;
        tc = tn;
    }
}

void RenderTile(const KernelParams& k, Tile tile, PixelOut* out, TileStats& stats)
{
    const LaneShifts shifts;
    if (k.multiRangeBrushes)
        renderTileWith(k, tile, out, stats,
                       [&](Vec3 o, Vec3 dir, float t0, float t1, float along, RayAccum& acc, TileStats& st) {
                           MarchSimd<true>(k, shifts, Ray{o, dir}, t0, t1, along, acc, st);
                       });
    else
        renderTileWith(k, tile, out, stats,
                       [&](Vec3 o, Vec3 dir, float t0, float t1, float along, RayAccum& acc, TileStats& st) {
                           MarchSimd<false>(k, shifts, Ray{o, dir}, t0, t1, along, acc, st);
                       });
}

int Lanes() { return int(hn::Lanes(DF())); }

void SampleBatch(const KernelParams& k, const KernelVariable& v, const float* x, const float* y, const float* z,
                 int n, float* out)
{
    const DF d;
    const int lanes = int(hn::Lanes(d));
    HWY_ALIGN float bx[kMaxLanes], by[kMaxLanes], bz[kMaxLanes], bo[kMaxLanes];
    for (int i = 0; i < n; i += lanes) {
        const int m = std::min(lanes, n - i);
        for (int j = 0; j < lanes; ++j) {
            bx[j] = x[i + std::min(j, m - 1)];
            by[j] = y[i + std::min(j, m - 1)];
            bz[j] = z[i + std::min(j, m - 1)];
        }
        const LocatedV L = Locate(d, k, hn::Load(d, bx), hn::Load(d, by), hn::Load(d, bz));
        hn::Store(Sample(d, k, v, L), d, bo);
        std::copy(bo, bo + m, out + i);
    }
}

}  // namespace raypc::render::kernel::HWY_NAMESPACE
HWY_AFTER_NAMESPACE();

#if HWY_ONCE
namespace raypc::render::kernel {

HWY_EXPORT(RenderTile);
HWY_EXPORT(Lanes);
HWY_EXPORT(SampleBatch);

void renderTileSimd(const KernelParams& k, Tile tile, PixelOut* out, TileStats& stats)
{
    HWY_DYNAMIC_DISPATCH(RenderTile)(k, tile, out, stats);
}

int simdLanes() { return HWY_DYNAMIC_DISPATCH(Lanes)(); }

void sampleBatchSimd(const KernelParams& k, const KernelVariable& v, const float* x, const float* y, const float* z,
                     int n, float* out)
{
    HWY_DYNAMIC_DISPATCH(SampleBatch)(k, v, x, y, z, n, out);
}

}  // namespace raypc::render::kernel
#endif
