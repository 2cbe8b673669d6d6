// The scalar reference kernel: the same sample positions, chunking, skipping and compositing
// order as the SIMD kernel, one sample at a time, written for clarity.
#include "render/render_kernel.h"

namespace raypc::render::kernel {
namespace {

float coordinateValue(const KernelBrush& brush, Vec3 p, const Located& L)
{
    float v = 0;
    switch (brush.component) {
    case grid::PointComponent::X: v = p.x; break;
    case grid::PointComponent::Y: v = p.y; break;
    case grid::PointComponent::Z: v = p.z; break;
    case grid::PointComponent::LatDeg: v = L.latDeg; break;
    case grid::PointComponent::LonDeg: v = L.lonDeg; break;
    case grid::PointComponent::RKm: v = L.rKm; break;
    }
    return brush.scale * v + brush.offset;
}

bool insideBrushes(const KernelParams& k, Vec3 p, const Located& L)
{
    for (int b = 0; b < k.brushCount; ++b) {
        const KernelBrush& brush = k.brushes[b];
        const float v = brush.onCoordinate ? coordinateValue(brush, p, L) : sampleAt(k, brush.variable, L);
        if (!(v >= brush.min && v <= brush.max))
            return false;
        if (brush.rangeCount > 1) {
            bool inOne = false;
            for (int i = 0; i < brush.rangeCount && !inOne; ++i)
                inOne = v >= brush.ranges[i].min && v <= brush.ranges[i].max;
            if (!inOne)
                return false;
        }
    }
    return true;
}

void marchScalar(const KernelParams& k, Vec3 o, Vec3 d, float t0, float t1, float along, RayAccum& acc,
                 TileStats& stats)
{
    walkChunks(k, o, d, t0, t1, acc, stats, [&](float tc, float dt) {
        bool anyActive = false;
        for (int i = 0; i < kChunkSamples && acc.transmittance > k.stopTransmittance; ++i) {
            const float start = tc + float(i) * dt;
            if (!(start < t1))
                break;
            if (!(start + dt > t0))
                continue;
            const float len = std::min(start + dt, t1) - std::max(start, t0);
            const float t = std::min(std::max(start + along * dt, t0), t1);
            const Vec3 p = o + d * t;
            const Located L = locate(k, p.x, p.y, p.z);
            if (!brickActive(k, L)) {
                ++stats.samplesSkipped;
                continue;
            }
            anyActive = true;
            ++stats.samples;
            if (!insideBrushes(k, p, L))
                continue;
            const float value = sampleAt(k, k.color, L);
            if (std::isnan(value))
                continue;  // missing (also where a trilinear sample meets a missing value): empty space
            const int idx = k.table.indexOf(value);
            const float sigma = std::max(k.table.sigmaPerKm[idx], k.selectionSigmaPerKm);
            if (!(sigma > 0.0f))
                continue;
            const float alpha = std::max(0.0f, 1.0f - std::exp(-sigma * len));
            const Occlusion occ = occlusionAt(k, p);
            const float s = k.shade ? shadeFactor(k, nativeGradient(k, L, p), d, occ)
                                    : (k.shadowLight ? unlitFactor(k, occ) : 1.0f);
            const float w = acc.transmittance * alpha * s;
            acc.r += w * k.table.red[idx];
            acc.g += w * k.table.green[idx];
            acc.b += w * k.table.blue[idx];
            acc.transmittance *= 1.0f - alpha;
            if (!std::isfinite(acc.depthKm) && 1.0f - acc.transmittance >= k.depthOpacity)
                acc.depthKm = t;
        }
        return anyActive;
    });
}

}  // namespace

void renderTileScalar(const KernelParams& k, Tile tile, PixelOut* out, TileStats& stats)
{
    renderTileWith(k, tile, out, stats,
                   [&](Vec3 o, Vec3 d, float t0, float t1, float along, RayAccum& acc, TileStats& st) {
                       marchScalar(k, o, d, t0, t1, along, acc, st);
                   });
}

void sampleBatchScalar(const KernelParams& k, const KernelVariable& v, const float* x, const float* y,
                       const float* z, int n, float* out)
{
    for (int i = 0; i < n; ++i)
        out[i] = sampleAt(k, v, locate(k, x[i], y[i], z[i]));
}

void extinctionBatchScalar(const KernelParams& k, const float* x, const float* y, const float* z, int n, float* out)
{
    for (int i = 0; i < n; ++i) {
        const Vec3 p{x[i], y[i], z[i]};
        const Located L = locate(k, p.x, p.y, p.z);
        const bool inShell = L.rKm >= k.rInnerKm && L.rKm <= k.rOuterKm;
        const float value = inShell && brickActive(k, L) && insideBrushes(k, p, L) ? sampleAt(k, k.color, L) : NAN;
        out[i] = std::isnan(value) ? 0.0f : std::max(k.table.sigmaPerKm[k.table.indexOf(value)], k.selectionSigmaPerKm);
    }
}

}  // namespace raypc::render::kernel
