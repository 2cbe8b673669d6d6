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
    VI iLat0, iR0;
    VI o00, o01, o10, o11, iLon0, iLon1, capIndex, brick;
    VF wLat, wR, wLon, cap;
    VF latDeg, lonDeg, rKm;
    bool anyCap;
    bool anySeam;  // some lane has iLon0 = nLon - 1 (its lon neighbour wraps to 0)
};

// Offsets of the four (lat, r) corner rows of L's cell.
HWY_INLINE void SetRowOffsets(const KernelParams& k, LocatedV& L)
{
    const DI di;
    L.o00 = hn::Mul(hn::Add(hn::Mul(L.iLat0, hn::Set(di, k.nR)), L.iR0), hn::Set(di, k.nLon));
    L.o01 = hn::Add(L.o00, hn::Set(di, k.nLon));
    L.o10 = hn::Add(L.o00, hn::Set(di, k.nR * k.nLon));
    L.o11 = hn::Add(L.o10, hn::Set(di, k.nLon));
}

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
    L.iLat0 = iLat0;
    L.wLat = hn::Sub(fLat, hn::ConvertTo(d, iLat0));
    const VF fR = Clamp(MapAxis(d, k.r, L.rKm), hn::Zero(d), hn::Set(d, float(k.nR - 1)));
    const VI iR0 = hn::Min(hn::ConvertTo(di, fR), hn::Set(di, k.nR - 2));
    L.iR0 = iR0;
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

    SetRowOffsets(k, L);

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
// shadowGridAt (render_kernel.h) across lanes: the x neighbours of a node are adjacent in memory,
// so each of the four (y, z) corner rows is one pair gather where pairs are available.
HWY_INLINE VF ShadowGridAt(DF d, const KernelParams& k, const float* grid, VF fx, VF fy, VF fz)
{
    const DI di;
    const VF zero = hn::Zero(d), top = hn::Set(d, float(k.shadowN - 1) - 1e-3f);
    fx = Clamp(fx, zero, top);
    fy = Clamp(fy, zero, top);
    fz = Clamp(fz, zero, top);
    const VI ix = hn::ConvertTo(di, fx), iy = hn::ConvertTo(di, fy), iz = hn::ConvertTo(di, fz);
    const VF wx = hn::Sub(fx, hn::ConvertTo(d, ix)), wy = hn::Sub(fy, hn::ConvertTo(d, iy)),
             wz = hn::Sub(fz, hn::ConvertTo(d, iz));
    const int n = k.shadowN;
    const VI o00 = hn::Add(hn::Mul(hn::Add(hn::Mul(iz, hn::Set(di, n)), iy), hn::Set(di, n)), ix);
    const VI o01 = hn::Add(o00, hn::Set(di, n)), o10 = hn::Add(o00, hn::Set(di, n * n)),
             o11 = hn::Add(o10, hn::Set(di, n));
    VF c00, c01, c10, c11;
#if RAYPC_LON_PAIRS
    c00 = LonPair(d, grid, o00, wx);
    c01 = LonPair(d, grid, o01, wx);
    c10 = LonPair(d, grid, o10, wx);
    c11 = LonPair(d, grid, o11, wx);
#else
    const VI one = hn::Set(di, 1);
    c00 = LerpV(hn::GatherIndex(d, grid, o00), hn::GatherIndex(d, grid, hn::Add(o00, one)), wx);
    c01 = LerpV(hn::GatherIndex(d, grid, o01), hn::GatherIndex(d, grid, hn::Add(o01, one)), wx);
    c10 = LerpV(hn::GatherIndex(d, grid, o10), hn::GatherIndex(d, grid, hn::Add(o10, one)), wx);
    c11 = LerpV(hn::GatherIndex(d, grid, o11), hn::GatherIndex(d, grid, hn::Add(o11, one)), wx);
#endif
    return LerpV(LerpV(c00, c01, wy), LerpV(c10, c11, wy), wz);
}
#undef RAYPC_LON_PAIRS

// occlusionAt (render_kernel.h) across lanes.
struct OcclusionV {
    VF light, ambient;
};
HWY_INLINE OcclusionV OcclusionAt(DF d, const KernelParams& k, VF x, VF y, VF z)
{
    const VF inv = hn::Set(d, k.shadowInvKm), o = hn::Set(d, k.shadowOriginKm);
    auto node = [&](VF c) { return hn::Mul(hn::Sub(c, o), inv); };
    const VF b = hn::Set(d, k.shadowLightBiasKm);
    OcclusionV occ;
    occ.light = ShadowGridAt(d, k, k.shadowLight, node(hn::MulAdd(b, hn::Set(d, k.lightDir.x), x)),
                             node(hn::MulAdd(b, hn::Set(d, k.lightDir.y), y)),
                             node(hn::MulAdd(b, hn::Set(d, k.lightDir.z), z)));
    occ.ambient = ShadowGridAt(d, k, k.shadowAmbient, node(x), node(y), node(z));
    return occ;
}

// unlitFactor (render_kernel.h) across lanes.
HWY_INLINE VF UnlitFactor(DF d, const KernelParams& k, const OcclusionV& occ)
{
    const float sum = k.ambient + k.diffuse;
    if (!(sum > 0.0f))
        return hn::Set(d, 1.0f);
    return hn::MulAdd(hn::Set(d, k.ambient / sum), occ.ambient, hn::Mul(hn::Set(d, k.diffuse / sum), occ.light));
}

// scale * component + offset (KernelBrush; the table is coordinateDefinition in grid/coordinates.h).
HWY_INLINE VF CoordinateValue(DF d, const KernelBrush& brush, VF x, VF y, VF z, const LocatedV& L)
{
    VF v = x;
    switch (brush.component) {
    case grid::PointComponent::X: v = x; break;
    case grid::PointComponent::Y: v = y; break;
    case grid::PointComponent::Z: v = z; break;
    case grid::PointComponent::LatDeg: v = L.latDeg; break;
    case grid::PointComponent::LonDeg: v = L.lonDeg; break;
    case grid::PointComponent::RKm: v = L.rKm; break;
    }
    return hn::MulAdd(hn::Set(d, brush.scale), v, hn::Set(d, brush.offset));
}

// nativeGradient (render_kernel.h) across lanes: the gradient at the grid points interpolated with
// the samples' weights, mapped to Cartesian with the local unit vectors.
struct GradientV {
    VF x, y, z;
};
HWY_INLINE GradientV NativeGradient(DF d, const KernelParams& k, const LocatedV& L, VF x, VF y, VF z)
{
    const VF perDegLat = Sample(d, k, k.gradLat, L);
    const VF perKmR = Sample(d, k, k.gradR, L);
    const VF perDegLon = Sample(d, k, k.gradLon, L);

    const VF r = hn::Max(L.rKm, hn::Set(d, 1.0f));
    const VF rho = hn::Max(hn::Sqrt(hn::MulAdd(x, x, hn::Mul(y, y))), hn::Mul(r, hn::Set(d, 1e-3f)));
    const VF invR = hn::Div(hn::Set(d, 1.0f), r), invRho = hn::Div(hn::Set(d, 1.0f), rho);
    const VF gNorth = hn::Mul(hn::Mul(perDegLat, hn::Set(d, kRadToDeg)), invR);
    const VF gEast = hn::Mul(hn::Mul(perDegLon, hn::Set(d, kRadToDeg)), invRho);
    // e_r = p / r, e_north = (-z x, -z y, rho^2) / (r rho), e_east = (-y, x, 0) / rho.
    const VF radial = hn::Mul(perKmR, invR);
    const VF north = hn::Mul(gNorth, hn::Mul(invR, invRho));
    const VF east = hn::Mul(gEast, invRho);
    const VF zNorth = hn::Mul(hn::Neg(z), north);
    GradientV g;
    g.x = hn::MulAdd(x, radial, hn::MulSub(x, zNorth, hn::Mul(y, east)));
    g.y = hn::MulAdd(y, radial, hn::MulAdd(y, zNorth, hn::Mul(x, east)));
    g.z = hn::MulAdd(z, radial, hn::Mul(hn::Mul(rho, rho), north));
    return g;
}

// shadeFactor (render_kernel.h) across lanes; `half` is normalize(light - ray direction); `occ`
// null: nothing occluded.
HWY_INLINE VF ShadeFactor(DF d, const KernelParams& k, const GradientV& g, Vec3 half, const OcclusionV* occ)
{
    const VF g2 = hn::MulAdd(g.x, g.x, hn::MulAdd(g.y, g.y, hn::Mul(g.z, g.z)));
    const MF hasGradient = hn::Gt(g2, hn::Set(d, 1e-30f));
    const VF inv = hn::Div(hn::Set(d, 1.0f), hn::Sqrt(hn::IfThenElse(hasGradient, g2, hn::Set(d, 1.0f))));
    auto absDot = [&](Vec3 a) {
        return hn::Mul(hn::Abs(hn::MulAdd(g.x, hn::Set(d, a.x), hn::MulAdd(g.y, hn::Set(d, a.y), hn::Mul(g.z, hn::Set(d, a.z))))),
                       inv);
    };
    VF direct = hn::Mul(hn::Set(d, k.diffuse), absDot(k.lightDir));
    if (k.specular > 0.0f) {
        // |n.h|^shininess = exp(shininess ln |n.h|), with |n.h| kept above 0 for the logarithm.
        const VF nh = hn::Max(absDot(half), hn::Set(d, 1e-20f));
        direct = hn::MulAdd(hn::Set(d, k.specular), hn::Exp(d, hn::Mul(hn::Set(d, k.shininess), hn::Log(d, nh))), direct);
    }
    if (!occ)
        return hn::IfThenElse(hasGradient, hn::Add(direct, hn::Set(d, k.ambient)), hn::Set(d, 1.0f));
    const VF lit = hn::MulAdd(direct, occ->light, hn::Mul(hn::Set(d, k.ambient), occ->ambient));
    return hn::IfThenElse(hasGradient, lit, UnlitFactor(d, k, *occ));
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

// The stages of one vector of samples in MarchSimd, in order: where the samples are, which lie in
// active bricks, which pass the brushes, their colour and opacity, their shading, and front-to-back
// compositing into the ray.

// Sample positions of lanes [base, base + lanes) of the chunk starting at tc with spacing dt: each
// sample owns [start, start + dt) clipped to [t0, t1) and sits `along` into it (clamped).
struct SamplesV {
    MF valid;     // the lane's interval is not empty
    VF len, t;    // clipped interval length (km) and position along the ray
    VF x, y, z;   // world position (km)
};
HWY_INLINE SamplesV ChunkSamples(DF d, const Ray& ray, float tc, float dt, int base, float t0, float t1, float along)
{
    const VF vdt = hn::Set(d, dt), vT0 = hn::Set(d, t0), vT1 = hn::Set(d, t1);
    const VF start = hn::MulAdd(hn::Add(hn::Iota(d, 0.0f), hn::Set(d, float(base))), vdt, hn::Set(d, tc));
    const VF end = hn::Add(start, vdt);
    SamplesV s;
    s.valid = hn::And(hn::Lt(start, vT1), hn::Gt(end, vT0));
    s.len = hn::Sub(hn::Min(end, vT1), hn::Max(start, vT0));
    s.t = hn::Min(hn::Max(hn::MulAdd(hn::Set(d, along), vdt, start), vT0), vT1);
    s.x = hn::MulAdd(s.t, hn::Set(d, ray.d.x), hn::Set(d, ray.o.x));
    s.y = hn::MulAdd(s.t, hn::Set(d, ray.d.y), hn::Set(d, ray.o.y));
    s.z = hn::MulAdd(s.t, hn::Set(d, ray.d.z), hn::Set(d, ray.o.z));
    return s;
}

// Lanes in active bricks (or in a pole cap, which has no bricks).
HWY_INLINE MF ActiveLanes(DF d, const KernelParams& k, const LocatedV& L, MF valid)
{
    if (!k.brickActive)
        return valid;
    const DI di;
    const VI flag = hn::GatherIndex(di, k.brickActive, hn::IfThenElseZero(hn::RebindMask(di, valid), L.brick));
    const MF capOrFlag = hn::Or(hn::Gt(L.cap, hn::Zero(d)), hn::RebindMask(d, hn::Ne(flag, hn::Zero(di))));
    return hn::And(valid, capOrFlag);
}

// Brushing: any brush that rejects a lane zeroes it; stops as soon as no lane is left. kMultiRange:
// some brushed axis has several ranges (decided once per tile, so that the common single-range case
// runs without the test of further ranges).
template <bool kMultiRange>
HWY_INLINE MF BrushedLanes(DF d, const KernelParams& k, const SamplesV& s, const LocatedV& L, MF keep)
{
    for (int b = 0; b < k.brushCount && !hn::AllFalse(d, keep); ++b) {
        const KernelBrush& brush = k.brushes[b];
        const VF v = brush.onCoordinate ? CoordinateValue(d, brush, s.x, s.y, s.z, L) : Sample(d, k, brush.variable, L);
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
    return keep;
}

// The transfer function: the table index of each kept lane and its opacity over its own interval,
// alpha = 1 - exp(-sigma len) (0 for lanes not kept or transparent).
struct ClassifiedV {
    VI index;
    VF alpha;
    MF opaque;
};
HWY_INLINE ClassifiedV Classify(DF d, const KernelParams& k, const LocatedV& L, MF keep, VF len)
{
    const DI di;
    const VF zero = hn::Zero(d);
    const VF value = Sample(d, k, k.color, L);
    // A missing value (NaN, also where a trilinear sample meets one) is empty space.
    keep = hn::And(keep, hn::Eq(value, value));
    const VF u = Clamp(hn::MulAdd(hn::Sub(value, hn::Set(d, k.table.valueMin)), hn::Set(d, k.table.indexScale), hn::Set(d, 0.5f)),
                       zero, hn::Set(d, float(k.table.size - 1)));
    ClassifiedV c;
    c.index = hn::IfThenElseZero(hn::RebindMask(di, keep), hn::ConvertTo(di, u));
    // At least the selection's floor (0 unless the selection is shown), as the scalar kernel.
    const VF sigma = hn::IfThenElseZero(
        keep, hn::Max(hn::GatherIndex(d, k.table.sigmaPerKm, c.index), hn::Set(d, k.selectionSigmaPerKm)));
    c.opaque = hn::Gt(sigma, zero);
    c.alpha = hn::IfThenElseZero(c.opaque, hn::Max(zero, hn::Sub(hn::Set(d, 1.0f), hn::Exp(d, hn::Neg(hn::Mul(sigma, len))))));
    return c;
}

// Front-to-back compositing across the lanes at once: the transmittance after lane i is
// T (1 - a_0) ... (1 - a_i), an inclusive prefix product (log2(lanes) permute steps). Lanes are
// composited while the transmittance before them is above the stop threshold (a prefix of the
// lanes), as the scalar kernel stops mid-chunk; the products are rounded in a different order, so
// the two kernels agree to rounding. The depth is the first sample where the accumulated opacity
// reaches depthOpacity.
HWY_INLINE void Composite(DF d, const KernelParams& k, const LaneShifts& shifts, VF alpha, VF red, VF green, VF blue,
                          VF t, RayAccum& acc)
{
    const int lanes = int(hn::Lanes(d));
    const VF one = hn::Set(d, 1.0f);
    VF after = hn::Sub(one, alpha);
    for (int s = 0; (1 << s) < lanes; ++s)
        after = hn::Mul(after, hn::IfThenElse(hn::FirstN(d, size_t(1) << s), one, hn::TableLookupLanes(after, shifts.shiftUp[s])));
    const VF vT = hn::Set(d, acc.transmittance);
    const VF tBefore = hn::Mul(vT, hn::IfThenElse(hn::FirstN(d, 1), one, hn::TableLookupLanes(after, shifts.shiftUp[0])));
    const VF tAfter = hn::Mul(vT, after);
    const MF live = hn::Gt(tBefore, hn::Set(d, k.stopTransmittance));
    const VF w = hn::IfThenElseZero(live, hn::Mul(tBefore, alpha));
    acc.r += hn::GetLane(hn::SumOfLanes(d, hn::Mul(w, red)));
    acc.g += hn::GetLane(hn::SumOfLanes(d, hn::Mul(w, green)));
    acc.b += hn::GetLane(hn::SumOfLanes(d, hn::Mul(w, blue)));
    if (!std::isfinite(acc.depthKm)) {
        const MF deep = hn::And(live, hn::Ge(hn::Sub(one, tAfter), hn::Set(d, k.depthOpacity)));
        if (!hn::AllFalse(d, deep)) {
            HWY_ALIGN float tBuf[kMaxLanes];
            hn::Store(t, d, tBuf);
            acc.depthKm = tBuf[hn::FindKnownFirstTrue(d, deep)];
        }
    }
    acc.transmittance = hn::GetLane(hn::MinOfLanes(d, hn::IfThenElse(live, tAfter, one)));
}

// One ray segment [t0, t1): the chunks of walkChunks, each as vectors of samples through the stages
// above.
// Flattened: walkChunks is compiled for the generic target and GCC does not inline this file's
// AVX-512 chunk body into it, so without this every 16-sample chunk was a call (4-13 % of a level-0
// pass; bench/ab_render.sh).
template <bool kMultiRange>
__attribute__((flatten)) void MarchSimd(const KernelParams& k, const LaneShifts& shifts, const Ray& ray, float t0, float t1, float along,
               RayAccum& acc, TileStats& stats)
{
    const DF d;
    const int lanes = int(hn::Lanes(d));
    const Vec3 lv = k.lightDir - ray.d;
    const Vec3 half = dot(lv, lv) > 1e-12f ? normalize(lv) : k.lightDir;
    walkChunks(k, ray.o, ray.d, t0, t1, acc, stats, [&](float tc, float dt) {
        bool anyActive = false;
        for (int base = 0; base < kChunkSamples && acc.transmittance > k.stopTransmittance; base += lanes) {
            const SamplesV s = ChunkSamples(d, ray, tc, dt, base, t0, t1, along);
            if (hn::AllFalse(d, s.valid))
                continue;
            const LocatedV L = Locate(d, k, s.x, s.y, s.z);
            const MF active = ActiveLanes(d, k, L, s.valid);
            const size_t nActive = hn::CountTrue(d, active);
            stats.samples += nActive;
            stats.samplesSkipped += hn::CountTrue(d, s.valid) - nActive;
            if (nActive == 0)
                continue;
            anyActive = true;
            const MF keep = BrushedLanes<kMultiRange>(d, k, s, L, active);
            if (hn::AllFalse(d, keep))
                continue;
            const ClassifiedV c = Classify(d, k, L, keep, s.len);
            if (hn::AllFalse(d, c.opaque))
                continue;
            VF shade = hn::Set(d, 1.0f);
            if (k.shadowLight) {
                const OcclusionV occ = OcclusionAt(d, k, s.x, s.y, s.z);
                shade = k.shade ? ShadeFactor(d, k, NativeGradient(d, k, L, s.x, s.y, s.z), half, &occ)
                                : UnlitFactor(d, k, occ);
            } else if (k.shade) {
                shade = ShadeFactor(d, k, NativeGradient(d, k, L, s.x, s.y, s.z), half, nullptr);
            }
            Composite(d, k, shifts, c.alpha, hn::Mul(shade, hn::GatherIndex(d, k.table.red, c.index)),
                      hn::Mul(shade, hn::GatherIndex(d, k.table.green, c.index)),
                      hn::Mul(shade, hn::GatherIndex(d, k.table.blue, c.index)), s.t, acc);
        }
        return anyActive;
    });
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

// Runs `f(x, y, z)` -> values on the points i..i+lanes-1 of each batch (the last batch padded with
// its last point) and stores the first n results to `out`.
template <class F>
void ForEachBatch(const float* x, const float* y, const float* z, int n, float* out, F&& f)
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
        hn::Store(f(hn::Load(d, bx), hn::Load(d, by), hn::Load(d, bz)), d, bo);
        std::copy(bo, bo + m, out + i);
    }
}

void SampleBatch(const KernelParams& k, const KernelVariable& v, const float* x, const float* y, const float* z,
                 int n, float* out)
{
    const DF d;
    ForEachBatch(x, y, z, n, out, [&](VF px, VF py, VF pz) { return Sample(d, k, v, Locate(d, k, px, py, pz)); });
}

void ExtinctionBatch(const KernelParams& k, const float* x, const float* y, const float* z, int n, float* out)
{
    const DF d;
    const DI di;
    ForEachBatch(x, y, z, n, out, [&](VF px, VF py, VF pz) {
        SamplesV s;
        s.x = px;
        s.y = py;
        s.z = pz;
        const LocatedV L = Locate(d, k, s.x, s.y, s.z);
        const MF inShell = hn::And(hn::Ge(L.rKm, hn::Set(d, k.rInnerKm)), hn::Le(L.rKm, hn::Set(d, k.rOuterKm)));
        const MF active = ActiveLanes(d, k, L, inShell);
        const MF keep = k.multiRangeBrushes ? BrushedLanes<true>(d, k, s, L, active) : BrushedLanes<false>(d, k, s, L, active);
        VF sigma = hn::Zero(d);
        if (!hn::AllFalse(d, keep)) {
            const VF value = Sample(d, k, k.color, L);
            // A missing value (NaN, also where a trilinear sample meets one) is empty space.
            const MF valued = hn::And(keep, hn::Eq(value, value));
            const VF u = Clamp(hn::MulAdd(hn::Sub(value, hn::Set(d, k.table.valueMin)), hn::Set(d, k.table.indexScale),
                                          hn::Set(d, 0.5f)),
                               hn::Zero(d), hn::Set(d, float(k.table.size - 1)));
            const VI index = hn::IfThenElseZero(hn::RebindMask(di, valued), hn::ConvertTo(di, u));
            sigma = hn::IfThenElseZero(
                valued, hn::Max(hn::GatherIndex(d, k.table.sigmaPerKm, index), hn::Set(d, k.selectionSigmaPerKm)));
        }
        return sigma;
    });
}

}  // namespace raypc::render::kernel::HWY_NAMESPACE
HWY_AFTER_NAMESPACE();

#if HWY_ONCE
namespace raypc::render::kernel {

HWY_EXPORT(RenderTile);
HWY_EXPORT(Lanes);
HWY_EXPORT(SampleBatch);
HWY_EXPORT(ExtinctionBatch);

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

void extinctionBatchSimd(const KernelParams& k, const float* x, const float* y, const float* z, int n, float* out)
{
    HWY_DYNAMIC_DISPATCH(ExtinctionBatch)(k, x, y, z, n, out);
}

}  // namespace raypc::render::kernel
#endif
