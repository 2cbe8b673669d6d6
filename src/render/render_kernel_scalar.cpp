// The scalar reference kernel: the same sample positions, chunking, skipping and compositing
// order as the SIMD kernel, one sample at a time, written for clarity.
#include "render/render_kernel.h"

namespace raypc::render::kernel {
namespace {

float coordinateValue(const KernelBrush& brush, Vec3 p, const Located& L)
{
    float v = 0;
    switch (brush.component) {
    case PointComponent::X: v = p.x; break;
    case PointComponent::Y: v = p.y; break;
    case PointComponent::Z: v = p.z; break;
    case PointComponent::LatDeg: v = L.latDeg; break;
    case PointComponent::LonDeg: v = L.lonDeg; break;
    case PointComponent::RKm: v = L.rKm; break;
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

float colourValueAt(const KernelParams& k, Vec3 p)
{
    return sampleAt(k, k.colour, locate(k, p.x, p.y, p.z));
}

// Two-sided diffuse shading from the central-difference gradient of the colouring variable.
float shadeFactor(const KernelParams& k, Vec3 p)
{
    const float h = k.gradientDeltaKm;
    const Vec3 g{colourValueAt(k, p + Vec3{h, 0, 0}) - colourValueAt(k, p - Vec3{h, 0, 0}),
                 colourValueAt(k, p + Vec3{0, h, 0}) - colourValueAt(k, p - Vec3{0, h, 0}),
                 colourValueAt(k, p + Vec3{0, 0, h}) - colourValueAt(k, p - Vec3{0, 0, h})};
    const float g2 = dot(g, g);
    if (!(g2 > 1e-30f))
        return 1.0f;
    return k.ambient + k.diffuse * std::abs(dot(g, k.lightDir)) / std::sqrt(g2);
}

void marchScalar(const KernelParams& k, Vec3 o, Vec3 d, float t0, float t1, float along, RayAccum& acc,
                 TileStats& stats)
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
            const int idx = k.table.indexOf(sampleAt(k, k.colour, L));
            const float sigma = k.table.sigmaPerKm[idx];
            if (!(sigma > 0.0f))
                continue;
            const float alpha = std::max(0.0f, 1.0f - std::exp(-sigma * len));
            float s = k.shade ? shadeFactor(k, p) : 1.0f;
            const float w = acc.transmittance * alpha * s;
            acc.r += w * k.table.red[idx];
            acc.g += w * k.table.green[idx];
            acc.b += w * k.table.blue[idx];
            acc.transmittance *= 1.0f - alpha;
            if (!std::isfinite(acc.depthKm) && 1.0f - acc.transmittance >= k.depthOpacity)
                acc.depthKm = t;
        }
        skip.probe = !anyActive;
        if (!anyActive)
            ++stats.chunksSkipped;
        ++j;
        tc = tn;
    }
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

}  // namespace raypc::render::kernel
