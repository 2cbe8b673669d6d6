// Internal to raypc_render: volumetric occlusion of the volume, the core and the tubes
// (docs/rendering.md, "Shadows and ambient occlusion").
//
// A coarse Cartesian grid of nodes over the planet's bounding cube holds, per node:
//   - the extinction (per km) of the cell around it: the mean of the kernels' own sigma (transfer
//     table, brushes, brick flags; extinctionBatchSimd) at 2^3 points of the cell, plus the visible
//     pathline tubes splatted as opaque cylinders (mean optical depth kept);
//   - the light's visibility: exp(-optical depth towards the light), marched slice by slice along
//     the light's dominant axis (each node continues the optical depth of the point one slice
//     towards the light, interpolated bilinearly: O(nodes), and the interpolation blurs the shadow
//     a little — soft shadows), times the core's shadow (opaque when the core is drawn, a soft-edged
//     cylinder behind it; the core's own lit half never shadows itself);
//   - the ambient light's visibility: the mean over the six axis directions of exp(-optical depth
//     over kAmbientReachKm), from prefix sums of the extinction along each axis.
// Both visibilities V are stored as 1 - strength (1 - V), read by the kernels with trilinear
// interpolation (occlusionAt in render_kernel.h).
//
// Cost classes: the extinction is rebuilt when the transfer table, brushes, brick flags, colouring
// variable or the visible tubes change (restart class); the light's visibility also when the light
// direction in the world changes (it follows the camera) or the core is shown or hidden. update()
// rebuilds only what changed. Units: km. Not thread safe: one per VolumeRenderer, updated before a
// pass, read by the pass.
#pragma once

#include "render/render_kernel.h"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <vector>

namespace raypc::render {

class PathlineScene;

// Nodes per axis of the shadow grid over [-(rOuter + cell), rOuter + cell]^3: at most 128 (cells of
// 102 km at the Earth's radius; docs/rendering.md, "Shadows and ambient occlusion").
inline constexpr int kShadowNodes = 128;

// The nodes for a volume whose finer angular spacing is dAngleRad: cells of half its lateral
// spacing at the surface but at least 102 km, from 32 to kShadowNodes nodes — the full-resolution
// contest grid (1°) gets 128, its level 2 (4°) 61, so the coarse levels shown while interacting
// rebuild a grid 9x smaller when the camera (and with it the light) moves; the demo (2.8°) 85.
inline int shadowNodesFor(float dAngleRad, float rOuterKm)
{
    const float cellKm = std::max(0.5f * dAngleRad * rOuterKm, 2.0f * rOuterKm / float(kShadowNodes - 3));
    const int n = int(std::ceil(2.0f * rOuterKm / cellKm)) + 3;
    return std::clamp(n, 32, kShadowNodes);
}
// How far the ambient occlusion looks (km; rounded to whole cells of the grid).
inline constexpr float kAmbientReachKm = 400.0f;

struct ShadowBuildStats {
    double extinctionMs = 0, tubesMs = 0, lightMs = 0, ambientMs = 0;
    bool extinctionBuilt = false, tubesBuilt = false, lightBuilt = false, ambientBuilt = false;
};

class ShadowVolume {
public:
    explicit ShadowVolume(int nodes = kShadowNodes);

    // Brings the grids up to date with the kernel view `k` (its transfer table, brushes, brick
    // flags, skip grid, colouring variable, light direction, core) and the visible tubes of
    // `tubes` (null: none), with `strength` in [0, 1]. Rebuilds only what changed.
    ShadowBuildStats update(const kernel::KernelParams& k, float strength, const PathlineScene* tubes);
    // Points k's shadow fields at the grids (after update).
    void bind(kernel::KernelParams& k) const;

    int nodes() const { return m_n; }
    float cellKm() const { return m_cellKm; }
    float originKm() const { return m_originKm; }
    // Per node, x fastest: extinction (per km, volume and tubes) and the two visibilities.
    const std::vector<float>& extinction() const { return m_sigma; }
    const std::vector<float>& lightVisibility() const { return m_light; }
    const std::vector<float>& ambientVisibility() const { return m_ambient; }

private:
    void buildExtinction(const kernel::KernelParams& k);
    void splatTubes(const PathlineScene* tubes);
    void buildLight(const kernel::KernelParams& k, float strength);
    void buildAmbient(float strength);

    int m_n;
    float m_originKm = 0, m_cellKm = 1;
    std::vector<float> m_volumeSigma, m_tubeSigma, m_sigma, m_light, m_ambient;
    uint64_t m_volumeKey = 0, m_tubeKey = 0, m_lightKey = 0, m_ambientKey = 0;
    bool m_valid = false;
};

}  // namespace raypc::render
