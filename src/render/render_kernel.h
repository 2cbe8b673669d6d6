// Internal to raypc_render: the plain-data view of one prepared frame that the kernels read, the
// per-pixel driver shared by the scalar and SIMD kernels, and the scalar reference sampler.
//
// Everything here is validated and baked by VolumeRenderer (volume_renderer.cpp) so that the kernels
// are noexcept, allocate nothing and make no virtual calls. Both kernels march runs of kChunkSamples
// consecutive samples along one ray ("chunks") that share one step length; the SIMD kernel
// (render_kernel_simd.cpp) processes a chunk as 16 / (SIMD width) vectors, the scalar kernel
// (render_kernel_scalar.cpp) one sample at a time, so the sample positions (and the images) do not
// depend on the machine's SIMD width and tests can compare the two kernels.
#pragma once

#include "dataset/dataset.h"
#include "render/camera.h"
#include "render/color_map.h"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <numbers>

namespace raypc::render::kernel {

inline constexpr float kRadToDeg = float(180.0 / std::numbers::pi);
// Samples per chunk, independent of the SIMD width (so images are identical on AVX2 and AVX-512).
inline constexpr int kChunkSamples = 16;

// atan for |a| <= 1: odd minimax polynomial, max error about 1e-5 rad (0.0006° — far below a cell).
inline float atanUnit(float a)
{
    const float s = a * a;
    float p = -0.01172120f;
    p = p * s + 0.05265332f;
    p = p * s - 0.11643287f;
    p = p * s + 0.19354346f;
    p = p * s - 0.33262347f;
    p = p * s + 0.99997726f;
    return p * a;
}

inline float fastAtan2(float y, float x)
{
    const float ax = std::abs(x), ay = std::abs(y);
    const float mx = std::max(ax, ay), mn = std::min(ax, ay);
    const float a = mx > 0.0f ? mn / mx : 0.0f;
    float r = atanUnit(a);
    if (ay > ax)
        r = float(std::numbers::pi / 2) - r;
    if (x < 0.0f)
        r = float(std::numbers::pi) - r;
    return y < 0.0f ? -r : r;
}

// Coordinate (degrees or km) -> fractional grid index along one axis. Uniform axes use the affine
// map, axes uniform but for their last interval (coarsened odd-sized axes) two affine pieces; other
// non-uniform ones a table of fractional indices at equally spaced coordinates, linearly
// interpolated (exact at the table nodes; the table is at least 64x finer than the grid).
struct AxisMap {
    bool affine = true;
    float scale = 1, offset = 0;  // affine: f = coord * scale + offset for coord <= breakCoord,
    float breakCoord = INFINITY, scale2 = 0, offset2 = 0;  // coord * scale2 + offset2 above it
    float coordMin = 0, invTableStep = 1;
    int tableLast = 0;  // table has tableLast + 1 entries
    const float* table = nullptr;

    float map(float coord) const
    {
        if (affine)
            return coord <= breakCoord ? coord * scale + offset : coord * scale2 + offset2;
        const float u = std::clamp((coord - coordMin) * invTableStep, 0.0f, float(tableLast) - 1e-3f);
        const int k = int(u);
        return table[k] + (u - float(k)) * (table[k + 1] - table[k]);
    }
};

struct KernelVariable {
    const float* values = nullptr;  // canonical grid order
    const float* capMean = nullptr;  // 2 * nR: ring means of the southmost row per r, then the northmost
};

// A brush on a variable or on a coordinate, whose value is scale * component + offset
// (coordinateDefinition in grid/coordinates.h).
struct KernelBrush {
    bool onCoordinate = false;
    grid::PointComponent component = grid::PointComponent::X;  // when onCoordinate
    float scale = 1, offset = 0;
    KernelVariable variable;                // otherwise
    // The only range, or with several (an axis' ranges OR-ed, RangeFilter) the hull of them all:
    // the single-range test is all the common case pays, and it rejects what lies outside the hull.
    float min = 0, max = 0;
    const dataset::ValueRange* ranges = nullptr;  // rangeCount > 1: the value must also lie in one of these
    int rangeCount = 1;
};

struct ColorTable {
    const float *red = nullptr, *green = nullptr, *blue = nullptr, *sigmaPerKm = nullptr;
    float valueMin = 0, indexScale = 0;
    int size = 0;
    int indexOf(float v) const { return int(std::clamp((v - valueMin) * indexScale + 0.5f, 0.0f, float(size - 1))); }
};

struct KernelParams;

// The closest opaque tube (pathline) along a ray, shaded: found before the march, which then stops
// at tKm; the tube is composited behind the accumulated volume. tKm = +inf: no tube.
struct TubeHit {
    float tKm = INFINITY;
    Rgb color;
};
// Traces one primary ray (o + t d, |d| = 1, t in [0, tMaxKm)) against the tubes; `ctx` is the tube
// scene (pathline_scene.cpp). noexcept and allocation-free, called once per ray from renderTileWith.
using TraceTubesFn = TubeHit (*)(const void* ctx, const KernelParams& k, Vec3 o, Vec3 d, float tMaxKm, int px,
                                 int py) noexcept;

struct KernelParams {
    // Grid (sizes >= 2 along each axis) and its coordinate maps.
    int nLat = 0, nR = 0, nLon = 0;
    AxisMap lat, r, lon;  // lat: degrees north -> [0, nLat-1]; r: km -> [0, nR-1]; lon: degrees in [0,360) -> [0, nLon)
    // Beyond the outermost lat rows the field blends linearly towards the row's ring mean, reached at the pole.
    float latSouthDeg = -90, latNorthDeg = 90, capScaleSouth = 0, capScaleNorth = 0;
    float rInnerKm = 3485, rOuterKm = 6371;

    // Bricks: active flags per brick (nullptr: no skipping); brick size is 1 << brickShift points.
    const int32_t* brickActive = nullptr;
    int brickShift = 3, bricksR = 1, bricksLon = 1;
    // The Cartesian skip grid (skip_grid.h): cellN^3 cells of 1 / cellInvKm km from cellOriginKm on
    // every axis, per cell the Chebyshev distance in cells to the nearest cell that may hold an
    // active sample (nullptr: not used).
    const uint8_t* cellDistance = nullptr;
    int cellN = 0;
    float cellOriginKm = 0, cellInvKm = 1, cellStepPastKm = 0;

    KernelVariable color;
    ColorTable table;
    const KernelBrush* brushes = nullptr;
    int brushCount = 0;
    bool multiRangeBrushes = false;  // some brush has rangeCount > 1 (the SIMD kernel's variant)
    // "Show the selection" (the state's `selection`): a selected sample's extinction is at least this,
    // whatever the table says, so that a selection in values the transfer function hides is seen.
    // 0: the table alone. Non-zero only while brushes are set (VolumeRenderer::fillKernelParams).
    float selectionSigmaPerKm = 0;

    // Samples: about stepFactor cells apart (mean radial spacing drKm, smaller mean angular spacing
    // dAngleRad), see RaySampling.
    float stepFactor = 0.5f, drKm = 1, dAngleRad = 0.01f;
    float stopTransmittance = 0.005f;  // early ray termination below this transmittance
    float depthOpacity = 0.5f;          // depth = first sample where accumulated opacity >= this

    // Shading: the gradient of the colouring variable on its native grid (nativeGradient) lights a
    // sample with ambient + diffuse |n.l| + specular |n.h|^shininess (two-sided Blinn-Phong).
    bool shade = false;
    Vec3 lightDir{0, 0, 1};  // unit, towards the light, world frame
    float ambient = 0.35f, diffuse = 0.65f, specular = 0, shininess = 32;
    // The colouring variable's gradient at the grid points (nodeGradient, grid/grid.h: per degree of
    // lat, per km of r, per degree of lon), interpolated like the field (bound when shade is set). In
    // the pole caps the lat and lon components fade to 0 and the radial one blends towards the
    // radial derivative of the ring mean, as differences of the blended field would.
    KernelVariable gradLat, gradR, gradLon;

    // Occlusion (shadow_volume.h; null: none): on shadowN^3 Cartesian nodes from shadowOriginKm,
    // 1 / shadowInvKm apart on every axis, the visibility of the light (`shadowLight`, lookups
    // moved shadowLightBiasKm towards the light so that a sample's own cell does not shadow it) and
    // of the ambient light (`shadowAmbient`), both in [0, 1] with the strength already applied.
    const float* shadowLight = nullptr;
    const float* shadowAmbient = nullptr;
    int shadowN = 0;
    float shadowOriginKm = 0, shadowInvKm = 1, shadowLightBiasKm = 0;

    bool drawCore = true;
    bool coreByVariable = false;
    Rgb coreColor{0.55f, 0.55f, 0.58f};
    KernelVariable coreVariable;
    ColorTable coreTable;

    // Tubes along pathlines (nullptr: none), bound per pass by VolumeRenderer::renderPass.
    TraceTubesFn traceTubes = nullptr;
    const void* tubeContext = nullptr;

    CameraFrame camera;
    int pass = 0;
    uint32_t seed = 0x9e3779b9u;
};

struct TileStats {
    uint64_t samples = 0;         // samples whose data were read
    uint64_t samplesSkipped = 0;  // samples in inactive bricks (no data read)
    uint64_t chunks = 0, chunksSkipped = 0;
    uint64_t chunksJumped = 0;  // skipped by interval skipping, without locating their samples
    uint64_t rays = 0;
};

// Output of one pixel: premultiplied colour, alpha = 1 - transmittance, depth (km along the ray, +inf if none).
struct PixelOut {
    float r = 0, g = 0, b = 0, a = 0, depthKm = INFINITY;
};

struct RayAccum {
    float r = 0, g = 0, b = 0, transmittance = 1;
    float depthKm = INFINITY;
};

// Tile rectangle [x0, x1) x [y0, y1); out has stride `width` pixels.
struct Tile {
    int x0, y0, x1, y1;
};

inline uint32_t hash32(uint32_t x)
{
    x ^= x >> 16;
    x *= 0x7feb352du;
    x ^= x >> 15;
    x *= 0x846ca68bu;
    x ^= x >> 16;
    return x;
}

// Per-pass subpixel offset (R2 low-discrepancy sequence; pass 0 is the pixel centre) and
// per-pixel sample offset along the ray (a pixel hash rotated by the golden ratio each pass).
inline void jitter(const KernelParams& k, int px, int py, float& sx, float& sy, float& along)
{
    // x - floor(x) is exact for x >= 0, like fmod(x, 1), and much cheaper.
    auto fraction = [](float x) { return x - std::floor(x); };
    if (k.pass == 0) {
        sx = sy = 0.5f;
    } else {
        sx = fraction(0.5f + float(k.pass) * 0.7548776662f);
        sy = fraction(0.5f + float(k.pass) * 0.5698402910f);
    }
    const uint32_t h = hash32(uint32_t(px) * 73856093u ^ uint32_t(py) * 19349663u ^ k.seed);
    along = fraction(float(h >> 8) * (1.0f / 16777216.0f) + float(k.pass) * 0.6180339887f);
}

// Where the samples of a ray lie: a closed-form sample count U(t) along the ray, so that the chunk
// holding any t is found directly (skipping jumps over empty space in O(1) and never moves a
// sample). With s = t + o.d the signed distance from the ray's closest approach to the centre,
// h that distance and r = sqrt(h^2 + s^2), the sampling rate (samples per km) is
//   dU/ds = max(|s| / (r dr), 1 / (H dθ)) / stepFactor,   H = max(h, dr / dθ),
// i.e. about stepFactor cells of the dominant direction of index change per sample: dr where the
// ray runs radially (|s| / r = |cos α|), H dθ — the angular cell at the closest approach — where it
// runs tangentially (there r is within 3 % of h as long as the closest approach is outside the
// core). Both pieces integrate in closed form: U = s / (stepFactor H dθ) up to the crossover s*,
// then U* + (r - r*) / (stepFactor dr); U is odd in s and continuous with a continuous rate.
// Chunk j holds the samples with U in [16 j, 16 j + 16), evenly spaced in t.
struct RaySampling {
    float b = 0, h2 = 0;         // s = t + b; squared distance of the ray from the centre
    float sStar = INFINITY, uStar = INFINITY, rStar = 0;
    float kmPerSampleMid = 1, kmPerSampleRadial = 1;

    float samplesAt(float t) const
    {
        const float s = t + b, a = std::abs(s);
        const float u = a <= sStar ? a / kmPerSampleMid
                                   : uStar + (std::sqrt(h2 + a * a) - rStar) / kmPerSampleRadial;
        return s < 0.0f ? -u : u;
    }
    float tAt(float u) const
    {
        const float a = std::abs(u);
        float s;
        if (a <= uStar) {
            s = a * kmPerSampleMid;
        } else {
            const float r = rStar + (a - uStar) * kmPerSampleRadial;
            s = std::sqrt(std::max(r * r - h2, 0.0f));
        }
        return (u < 0.0f ? -s : s) - b;
    }
    float chunkStart(int j) const { return tAt(float(j * kChunkSamples)); }
    // The chunk holding t.
    int chunkOf(float t) const { return int(std::floor(samplesAt(t) / float(kChunkSamples))); }
};

inline RaySampling raySampling(const KernelParams& k, Vec3 o, Vec3 d)
{
    RaySampling rs;
    rs.b = dot(o, d);
    rs.h2 = std::max(0.0f, dot(o, o) - rs.b * rs.b);
    const float h = std::sqrt(rs.h2);
    const float cellRatioKm = k.drKm / k.dAngleRad;  // dr / dθ: where the two pieces meet at h
    rs.kmPerSampleMid = k.stepFactor * std::max(h, cellRatioKm) * k.dAngleRad;
    rs.kmPerSampleRadial = k.stepFactor * k.drKm;
    if (h > cellRatioKm) {
        const float q = cellRatioKm / h, c = std::sqrt(1.0f - q * q);
        rs.sStar = cellRatioKm / c;
        rs.rStar = h / c;
        rs.uStar = rs.sStar / rs.kmPerSampleMid;
    }
    return rs;
}

// Where a point is in the grid: corner indices, weights and the pole-cap blend.
struct Located {
    int iLat0, iR0, iLon0, iLon1;
    float wLat, wR, wLon;
    float cap;     // 0 inside the rows, -> 1 at the pole
    int capRow;    // 0 (south) or nR (north): offset into capMean
    float latDeg, lonDeg, rKm;
};

inline Located locate(const KernelParams& k, float x, float y, float z)
{
    Located L;
    const float rho = std::sqrt(x * x + y * y);
    L.rKm = std::sqrt(rho * rho + z * z);
    L.latDeg = fastAtan2(z, rho) * kRadToDeg;
    float lon = fastAtan2(y, x) * kRadToDeg;
    L.lonDeg = lon < 0.0f ? lon + 360.0f : lon;

    const float fLat = std::clamp(k.lat.map(L.latDeg), 0.0f, float(k.nLat - 1));
    L.iLat0 = std::min(int(fLat), k.nLat - 2);
    L.wLat = fLat - float(L.iLat0);
    const float fR = std::clamp(k.r.map(L.rKm), 0.0f, float(k.nR - 1));
    L.iR0 = std::min(int(fR), k.nR - 2);
    L.wR = fR - float(L.iR0);
    float fLon = k.lon.map(L.lonDeg);
    fLon = fLon < 0.0f ? fLon + float(k.nLon) : fLon;
    fLon = fLon >= float(k.nLon) ? fLon - float(k.nLon) : fLon;
    L.iLon0 = std::min(int(fLon), k.nLon - 1);
    L.wLon = fLon - float(L.iLon0);
    L.iLon1 = L.iLon0 + 1 == k.nLon ? 0 : L.iLon0 + 1;
    L.cap = std::max(0.0f, (k.latSouthDeg - L.latDeg) * k.capScaleSouth) +
            std::max(0.0f, (L.latDeg - k.latNorthDeg) * k.capScaleNorth);
    L.capRow = L.latDeg > 0.0f ? k.nR : 0;
    return L;
}

inline float sampleAt(const KernelParams& k, const KernelVariable& v, const Located& L)
{
    const int o00 = (L.iLat0 * k.nR + L.iR0) * k.nLon;
    const int o01 = o00 + k.nLon;
    const int o10 = o00 + k.nR * k.nLon;
    const int o11 = o10 + k.nLon;
    const float* d = v.values;
    const float c00 = d[o00 + L.iLon0] + L.wLon * (d[o00 + L.iLon1] - d[o00 + L.iLon0]);
    const float c01 = d[o01 + L.iLon0] + L.wLon * (d[o01 + L.iLon1] - d[o01 + L.iLon0]);
    const float c10 = d[o10 + L.iLon0] + L.wLon * (d[o10 + L.iLon1] - d[o10 + L.iLon0]);
    const float c11 = d[o11 + L.iLon0] + L.wLon * (d[o11 + L.iLon1] - d[o11 + L.iLon0]);
    const float c0 = c00 + L.wR * (c01 - c00);
    const float c1 = c10 + L.wR * (c11 - c10);
    float value = c0 + L.wLat * (c1 - c0);
    const float* m = v.capMean + L.capRow + L.iR0;
    const float mean = m[0] + L.wR * (m[1] - m[0]);
    return value + L.cap * (mean - value);
}

// The gradient of the colouring variable at a located point p (km, world frame): its gradient at
// the grid points in (lat, r, lon) (KernelParams::gradLat, gradR, gradLon), interpolated with the
// point's weights and mapped to Cartesian with the local unit vectors (e_r, e_north, e_east).
// Units: value per km.
inline Vec3 nativeGradient(const KernelParams& k, const Located& L, Vec3 p)
{
    const float perDegLat = sampleAt(k, k.gradLat, L), perKmR = sampleAt(k, k.gradR, L);
    const float perDegLon = sampleAt(k, k.gradLon, L);
    const float r = std::max(L.rKm, 1.0f), rho = std::max(std::sqrt(p.x * p.x + p.y * p.y), 1e-3f * r);
    const float gNorth = perDegLat * kRadToDeg / r, gEast = perDegLon * kRadToDeg / rho;
    const Vec3 eR = p * (1.0f / r);
    const Vec3 eNorth{-p.z * p.x / (r * rho), -p.z * p.y / (r * rho), rho / r};
    const Vec3 eEast{-p.y / rho, p.x / rho, 0.0f};
    return eR * perKmR + eNorth * gNorth + eEast * gEast;
}

// How much of the light and of the ambient light reach a point (1: all; KernelParams::shadowLight).
struct Occlusion {
    float light = 1, ambient = 1;
};

// Trilinear value of a shadow grid at node coordinates f (clamped to the grid).
inline float shadowGridAt(const KernelParams& k, const float* grid, float fx, float fy, float fz)
{
    const float top = float(k.shadowN - 1) - 1e-3f;
    fx = std::clamp(fx, 0.0f, top);
    fy = std::clamp(fy, 0.0f, top);
    fz = std::clamp(fz, 0.0f, top);
    const int ix = int(fx), iy = int(fy), iz = int(fz);
    const float wx = fx - float(ix), wy = fy - float(iy), wz = fz - float(iz);
    const size_t n = size_t(k.shadowN), o = (size_t(iz) * n + size_t(iy)) * n + size_t(ix);
    const float* g = grid + o;
    auto lerp = [](float a, float b, float w) { return a + w * (b - a); };
    const float c00 = lerp(g[0], g[1], wx), c01 = lerp(g[n], g[n + 1], wx);
    const float c10 = lerp(g[n * n], g[n * n + 1], wx), c11 = lerp(g[n * n + n], g[n * n + n + 1], wx);
    return lerp(lerp(c00, c01, wy), lerp(c10, c11, wy), wz);
}

inline Occlusion occlusionAt(const KernelParams& k, Vec3 p)
{
    if (!k.shadowLight)
        return {};
    const float inv = k.shadowInvKm, o = k.shadowOriginKm;
    const Vec3 q = p + k.lightDir * k.shadowLightBiasKm;
    return {shadowGridAt(k, k.shadowLight, (q.x - o) * inv, (q.y - o) * inv, (q.z - o) * inv),
            shadowGridAt(k, k.shadowAmbient, (p.x - o) * inv, (p.y - o) * inv, (p.z - o) * inv)};
}

// The factor of a sample without a lighting normal (shading off, or a flat field): 1 when nothing
// is occluded, else the lit weights' mix of the two visibilities.
inline float unlitFactor(const KernelParams& k, Occlusion occ)
{
    const float sum = k.ambient + k.diffuse;
    return sum > 0.0f ? (k.ambient * occ.ambient + k.diffuse * occ.light) / sum : 1.0f;
}

// Two-sided Blinn-Phong of a sample with gradient g seen along the unit ray direction d, the
// ambient term scaled by the ambient visibility and the direct terms by the light's; unlitFactor
// where the field is flat.
inline float shadeFactor(const KernelParams& k, Vec3 g, Vec3 d, Occlusion occ = {})
{
    const float g2 = dot(g, g);
    if (!(g2 > 1e-30f))
        return unlitFactor(k, occ);
    const float inv = 1.0f / std::sqrt(g2);
    float direct = k.diffuse * std::abs(dot(g, k.lightDir)) * inv;
    const Vec3 lv = k.lightDir - d;  // light plus view direction
    if (k.specular > 0.0f && dot(lv, lv) > 1e-12f)
        direct += k.specular * std::pow(std::abs(dot(g, normalize(lv))) * inv, k.shininess);
    return k.ambient * occ.ambient + direct * occ.light;
}

inline bool brickActive(const KernelParams& k, const Located& L)
{
    if (!k.brickActive || L.cap > 0.0f)
        return true;
    const int b = ((L.iLat0 >> k.brickShift) * k.bricksR + (L.iR0 >> k.brickShift)) * k.bricksLon +
                  (L.iLon0 >> k.brickShift);
    return k.brickActive[b] != 0;
}

// The ray in the skip grid's cell units, f(t) = f0 + t g, prepared once per ray segment.
struct CellRay {
    float f0[3]{}, g[3]{}, invG[3]{}, absInvG[3]{};
    float up[3]{};  // 1 where g >= 0 (cells are left through their upper face), else 0
};

inline CellRay cellRay(const KernelParams& k, Vec3 o, Vec3 d)
{
    CellRay c;
    const float oc[3] = {o.x, o.y, o.z}, dc[3] = {d.x, d.y, d.z};
    for (int a = 0; a < 3; ++a) {
        c.f0[a] = (oc[a] - k.cellOriginKm) * k.cellInvKm;
        c.g[a] = dc[a] * k.cellInvKm;
        c.up[a] = c.g[a] >= 0.0f ? 1.0f : 0.0f;
        c.invG[a] = c.g[a] != 0.0f ? 1.0f / c.g[a] : 1e30f;
        c.absInvG[a] = std::abs(c.invG[a]);
    }
    return c;
}

// How far along the ray from t the skip grid shows only cells without active samples: probes the
// cell at the point; at distance D >= 1 the (2D - 1)^3 block of cells around it is empty, so the ray
// moves to the block's exit (a little past it: the cells' bricks were found for cells grown by
// kSkipCellPadKm, which also covers the rounding of the cell coordinates) and probes again, at most
// `probes` times. Returns the first t (>= the given one) where the ray may meet an active sample;
// `occupiedUntil` (if given) receives where the ray leaves the occupied cell found there.
// The probes form a serial chain, so the work after the table load is kept short: the exit of the
// current cell is computed while the load is in flight, the block adds (D - 1) cells per axis.
inline float cellSkipTo(const KernelParams& k, const CellRay& c, float t, int probes, float* occupiedUntil = nullptr)
{
    const float span = float(k.cellN);
    const size_t n = size_t(k.cellN);
    for (int i = 0; i < probes; ++i) {
        const float f[3] = {c.f0[0] + t * c.g[0], c.f0[1] + t * c.g[1], c.f0[2] + t * c.g[2]};
        if (!(f[0] >= 0.0f && f[1] >= 0.0f && f[2] >= 0.0f && f[0] < span && f[1] < span && f[2] < span))
            return t;
        const int ix = int(f[0]), iy = int(f[1]), iz = int(f[2]);
        const int D = k.cellDistance[(size_t(iz) * n + size_t(iy)) * n + size_t(ix)];
        // Exit of the cell itself along each axis, then of the block [i - (D - 1), i + D).
        const float cellExit[3] = {(float(ix) + c.up[0] - f[0]) * c.invG[0], (float(iy) + c.up[1] - f[1]) * c.invG[1],
                                   (float(iz) + c.up[2] - f[2]) * c.invG[2]};
        const float m = float(std::max(D - 1, 0));
        const float exit = std::min({cellExit[0] + m * c.absInvG[0], cellExit[1] + m * c.absInvG[1],
                                     cellExit[2] + m * c.absInvG[2]});
        if (D == 0) {
            if (occupiedUntil)
                *occupiedUntil = t + exit;
            return t;
        }
        t += std::max(exit, 0.0f) + k.cellStepPastKm;
    }
    return t;
}

// Interval skipping state of one ray segment: [.., tSafe] is known to hold only inactive samples;
// the skip grid is probed at the start of a chunk only after a chunk without active samples, so
// dense regions pay nothing for it.
struct SkipState {
    CellRay ray;
    float tSafe = -INFINITY;
    float tOccupied = -INFINITY;  // the last probe found an occupied cell that the ray leaves here
    bool probe = true;
    SkipState(const KernelParams& k, Vec3 o, Vec3 d)
    {
        if (k.cellDistance)
            ray = cellRay(k, o, d);
    }
};

// True when every sample of the chunk [tc, tEnd) lies in inactive space, so it can be passed over
// without locating its samples; then s.tSafe says how far the empty space is known to reach.
inline bool chunkIsEmpty(const KernelParams& k, float tc, float tEnd, SkipState& s)
{
    if (!k.cellDistance)
        return false;
    if (tEnd <= s.tSafe)
        return true;
    if (!s.probe || tc < s.tOccupied)  // probing again inside the same occupied cell finds nothing
        return false;
    s.tSafe = std::max(s.tSafe, cellSkipTo(k, s.ray, std::max(tc, s.tSafe), 8, &s.tOccupied));
    return tEnd <= s.tSafe;
}

// After chunkIsEmpty: the chunk where the known-empty space (up to s.tSafe, within the segment's end
// t1) ends, at least j + 1. That chunk is located sample by sample before the next probe.
inline int chunkAfterEmpty(const RaySampling& rs, int j, float t1, SkipState& s)
{
    s.probe = false;
    return std::max(j + 1, rs.chunkOf(std::min(s.tSafe, t1)));
}

// Sample i of a chunk starting at tc with spacing dt owns [tc + i dt, tc + (i + 1) dt) clipped to the
// segment [t0, t1) and sits `along` into it (clamped to the segment). How many of the chunk's
// samples have a non-empty interval (for statistics; closed form, exact up to rounding at the ends).
inline int chunkSampleCount(float tc, float dt, float t0, float t1)
{
    const float first = std::floor((t0 - tc) / dt);       // the sample whose interval holds t0
    const float last = std::ceil((t1 - tc) / dt) - 1.0f;  // the last sample starting before t1
    return std::max(0, int(std::clamp(last, -1.0f, float(kChunkSamples - 1)) - std::clamp(first, 0.0f, float(kChunkSamples)) + 1.0f));
}

// Statistics of the chunks j .. next - 1 passed over by a jump; chunk j starts at tc with spacing dt
// (it may be cut by the segment [t0, t1)), the others are whole.
inline void countJumped(TileStats& stats, int j, int next, float tc, float dt, float t0, float t1)
{
    const uint64_t chunks = uint64_t(next - j);
    stats.samplesSkipped += uint64_t(chunkSampleCount(tc, dt, t0, t1)) + uint64_t(kChunkSamples) * (chunks - 1);
    stats.chunks += chunks - 1;  // the first was counted when it was reached
    stats.chunksSkipped += chunks;
    stats.chunksJumped += chunks;
}

// The chunk walk both kernels share: chunk by chunk along the segment [t0, t1) while the ray is not
// opaque, known-empty space passed over in one jump (interval skipping), and the skip grid probed
// again after a chunk without active samples. `marchChunk(tc, dt)` composites the samples of the
// chunk starting at tc with spacing dt into acc and returns whether any of them was active.
template <class MarchChunk>
void walkChunks(const KernelParams& k, Vec3 o, Vec3 d, float t0, float t1, const RayAccum& acc, TileStats& stats,
                MarchChunk&& marchChunk)
{
    const RaySampling rs = raySampling(k, o, d);
    SkipState skip(k, o, d);
    int j = rs.chunkOf(t0);
    float tc = rs.chunkStart(j);
    while (tc < t1 && acc.transmittance > k.stopTransmittance) {
        const float tn = rs.chunkStart(j + 1);
        const float dt = (tn - tc) * (1.0f / float(kChunkSamples));
        ++stats.chunks;
        if (chunkIsEmpty(k, tc, tn, skip)) {
            const int next = chunkAfterEmpty(rs, j, t1, skip);
            countJumped(stats, j, next, tc, dt, t0, t1);
            j = next;
            tc = rs.chunkStart(j);
            continue;
        }
        const bool anyActive = marchChunk(tc, dt);
        skip.probe = !anyActive;
        if (!anyActive)
            ++stats.chunksSkipped;
        ++j;
        tc = tn;
    }
}

// The opaque core sphere: plain or coloured by a variable at the core radius, Lambert-shaded.
inline Rgb coreColorAt(const KernelParams& k, Vec3 hit)
{
    Rgb c = k.coreColor;
    if (k.coreByVariable) {
        const Located L = locate(k, hit.x, hit.y, hit.z);
        // Where the variable is missing, the plain core colour.
        if (const float v = sampleAt(k, k.coreVariable, L); !std::isnan(v)) {
            const int i = k.coreTable.indexOf(v);
            c = {k.coreTable.red[i], k.coreTable.green[i], k.coreTable.blue[i]};
        }
    }
    const float lambert = std::max(0.0f, dot(normalize(hit), k.lightDir));
    const Occlusion occ = occlusionAt(k, hit);
    const float s = k.ambient * occ.ambient + k.diffuse * lambert * occ.light;
    return {c.r * s, c.g * s, c.b * s};
}

// The per-pixel driver: rays through the tile, shell segments, the marcher, then the core.
// `march(o, d, t0, t1, along, acc, stats)` composites one segment front to back into acc.
template <class March>
void renderTileWith(const KernelParams& k, Tile tile, PixelOut* out, TileStats& stats, March&& march)
{
    for (int py = tile.y0; py < tile.y1; ++py) {
        for (int px = tile.x0; px < tile.x1; ++px) {
            float sx, sy, along;
            jitter(k, px, py, sx, sy, along);
            const Vec3 o = k.camera.eye;
            const Vec3 d = k.camera.direction(float(px) + sx, float(py) + sy);
            const ShellSegments seg = intersectShell(o, d, k.rInnerKm, k.rOuterKm, !k.drawCore);
            RayAccum acc;
            ++stats.rays;
            // The closest tube first (in front of the core, if any): the volume is marched only up to it.
            const bool coreHit = k.drawCore && seg.coreT >= 0.0f;
            const TubeHit tube = k.traceTubes ? k.traceTubes(k.tubeContext, k, o, d, coreHit ? seg.coreT : INFINITY, px, py)
                                              : TubeHit{};
            for (int s = 0; s < seg.count && acc.transmittance > k.stopTransmittance; ++s) {
                const float t1 = std::min(seg.t1[s], tube.tKm);
                if (!(seg.t0[s] < t1))
                    break;
                march(o, d, seg.t0[s], t1, along, acc, stats);
            }
            if (std::isfinite(tube.tKm)) {
                // C += T C_tube, alpha likewise: the tube is opaque and hides the core behind it.
                if (acc.transmittance > k.stopTransmittance) {
                    acc.r += acc.transmittance * tube.color.r;
                    acc.g += acc.transmittance * tube.color.g;
                    acc.b += acc.transmittance * tube.color.b;
                    acc.transmittance = 0.0f;
                    if (!std::isfinite(acc.depthKm))
                        acc.depthKm = tube.tKm;
                }
            } else if (coreHit && acc.transmittance > k.stopTransmittance) {
                const Rgb c = coreColorAt(k, o + d * seg.coreT);
                acc.r += acc.transmittance * c.r;
                acc.g += acc.transmittance * c.g;
                acc.b += acc.transmittance * c.b;
                acc.transmittance = 0.0f;
                if (!std::isfinite(acc.depthKm))
                    acc.depthKm = seg.coreT;
            }
            PixelOut& p = out[size_t(py) * size_t(k.camera.width) + size_t(px)];
            p = {acc.r, acc.g, acc.b, 1.0f - acc.transmittance, acc.depthKm};
        }
    }
}

// Scalar reference kernel (render_kernel_scalar.cpp).
void renderTileScalar(const KernelParams& k, Tile tile, PixelOut* out, TileStats& stats);
// SIMD kernel with dynamic dispatch (render_kernel_simd.cpp).
void renderTileSimd(const KernelParams& k, Tile tile, PixelOut* out, TileStats& stats);
// Float lanes of the SIMD target chosen at run time.
int simdLanes();
// Batch samplers for tests: value of `v` at n points (x, y, z arrays, km).
void sampleBatchScalar(const KernelParams& k, const KernelVariable& v, const float* x, const float* y,
                       const float* z, int n, float* out);
void sampleBatchSimd(const KernelParams& k, const KernelVariable& v, const float* x, const float* y,
                     const float* z, int n, float* out);
// The extinction (per km) the kernels give a sample at each of n points: the transfer table's
// sigma of the colouring variable (at least selectionSigmaPerKm) where the point lies in the shell,
// in an active brick and inside every brush; 0 elsewhere. For the shadow volume (shadow_volume.h).
void extinctionBatchScalar(const KernelParams& k, const float* x, const float* y, const float* z, int n, float* out);
void extinctionBatchSimd(const KernelParams& k, const float* x, const float* y, const float* z, int n, float* out);

}  // namespace raypc::render::kernel
