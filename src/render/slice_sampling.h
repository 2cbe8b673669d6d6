// Internal to raypc_render: how maps and sections sample the native grid (slice_view.h): the depths
// a grid covers, the values at a point (the colour variable, whether the brushes select it, the
// velocity) and the samples of every pixel. Inline, as the pictures call them for every pixel.
//
// Units: km, degrees; velocities in cm/yr. Thread safety: a PointProbe is read by many threads at
// once after fixRadius; samplePixels runs rows in parallel (oneTBB).
#pragma once

#include "core/error.h"
#include "core/spherical.h"
#include "core/vec3.h"
#include "dataset/dataset.h"
#include "grid/coordinates.h"
#include "grid/sampler.h"
#include "analysis/selection.h"
#include "render/volume_renderer.h"

#include <tbb/parallel_for.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <optional>
#include <string>
#include <utility>
#include <vector>

namespace raypc::render::slice {

// The depths a grid covers: from its outermost to its innermost radius.
inline std::pair<double, double> depthRangeKm(const grid::SphericalGrid& grid)
{
    return {kSurfaceRadiusKm - grid.rKm.back(), kSurfaceRadiusKm - grid.rKm.front()};
}

// The radius of `depthKm`, clamped to the grid's; throws raypc::Error naming `what` for a depth
// outside the grid's depths.
inline double radiusAtDepth(const grid::SphericalGrid& grid, double depthKm, const std::string& what)
{
    const auto [top, bottom] = depthRangeKm(grid);
    constexpr double kTolerance = 1e-6;
    if (!(depthKm >= top - kTolerance && depthKm <= bottom + kTolerance))
        fail("{}: {} km is outside the grid's depths, {:g} to {:g} km", what, depthKm, top, bottom);
    return std::clamp(kSurfaceRadiusKm - depthKm, grid.rKm.front(), grid.rKm.back());
}

// The values at a point: the colour variable, whether the brushes select it, and the velocity.
class PointProbe {
public:
    PointProbe(const dataset::StepVolume& volume, const RenderParams& params, const std::vector<std::string>& names, bool flow,
               const std::string& flowKey)
        : m_sampler(volume.grid()), m_params(params), m_color(volume.values(size_t(params.colorVariable)))
    {
        for (const analysis::RangeFilter& f : params.brushes)
            m_brushValues.push_back(f.variable >= 0 ? volume.values(size_t(f.variable)) : nullptr);
        if (flow) {
            const char* component[3] = {"vx", "vy", "vz"};
            for (int k = 0; k < 3; ++k) {
                const auto it = std::find(names.begin(), names.end(), component[k]);
                if (it == names.end())
                    fail("{}: the flow needs the velocity's components vx, vy and vz; the dataset has no {}", flowKey,
                         component[k]);
                m_velocity[size_t(k)] = volume.values(size_t(it - names.begin()));
            }
        }
    }

    struct Sample {
        float value;
        bool selected;
    };
    // At a point whose location on the grid is known (a section locates its columns and its rows
    // once).
    Sample at(const grid::GridSampler::Location& where, double latDeg, double lonDeg, double rKm) const
    {
        auto value = [&](size_t slot) { return m_sampler.sample(slot == 0 ? m_color : m_brushValues[slot - 1], where); };
        return evaluate(value, latDeg, lonDeg, rKm);
    }

    // From now on `onShell` samples the shell of radius rKm (a map's): the colour's and the brushes'
    // variables interpolated in radius once, then in lat and lon per point (the same trilinear
    // value; GridSampler::sampleLateral).
    void fixRadius(double rKm)
    {
        const auto radial = m_sampler.locateRadius(rKm);
        if (!radial)
            fail("a shell of radius {} km is outside the grid", rKm);
        m_shellRKm = rKm;
        const grid::SphericalGrid& g = m_sampler.grid();
        auto layerOf = [&](const float* values) {
            std::vector<double> layer(g.nLat() * g.nLon());
            tbb::parallel_for(size_t(0), g.nLat(), [&](size_t iLat) {
                const float* a = values + g.index(iLat, radial->r0, 0);
                const float* b = values + g.index(iLat, radial->r1, 0);
                for (size_t iLon = 0; iLon < g.nLon(); ++iLon)
                    layer[iLat * g.nLon() + iLon] = a[iLon] + (double(b[iLon]) - a[iLon]) * radial->tR;
            });
            return layer;
        };
        m_layers.clear();
        m_layers.push_back(layerOf(m_color));
        for (const float* values : m_brushValues)
            m_layers.push_back(values ? layerOf(values) : std::vector<double>{});
    }
    std::optional<Sample> onShell(double latDeg, double lonDeg) const
    {
        const auto where = m_sampler.locateLatLon(latDeg, lonDeg);
        if (!where)
            return std::nullopt;
        const size_t nLon = m_sampler.grid().nLon();
        auto value = [&](size_t slot) {
            const std::vector<double>& layer = m_layers[slot];
            return m_sampler.sampleLateral([&](size_t iLat, size_t iLon) { return layer[iLat * nLon + iLon]; }, *where);
        };
        return evaluate(value, latDeg, lonDeg, m_shellRKm);
    }

    // The velocity (cm/yr, Cartesian components in the contest frame) at a point.
    std::optional<Vec3d> velocityCmPerYr(double latDeg, double lonDeg, double rKm) const
    {
        const auto where = m_sampler.locate(latDeg, lonDeg, rKm);
        if (!where || !m_velocity[0])
            return std::nullopt;
        return Vec3d{m_sampler.sample(m_velocity[0], *where), m_sampler.sample(m_velocity[1], *where),
                     m_sampler.sample(m_velocity[2], *where)} *
               kMpsToCmPerYr;
    }

    const grid::GridSampler& sampler() const { return m_sampler; }

private:
    // The colour and whether the brushes select the point, with `value(slot)` the interpolated value
    // there of the colour variable (slot 0) or of brush i's variable (slot 1 + i).
    template <class Value>
    Sample evaluate(const Value& value, double latDeg, double lonDeg, double rKm) const
    {
        bool selected = true;
        for (size_t i = 0; i < m_params.brushes.size() && selected; ++i) {
            const analysis::RangeFilter& f = m_params.brushes[i];
            const double v = f.variable >= 0 ? value(1 + i) : grid::coordinateValue(*f.coordinate, latDeg, lonDeg, rKm);
            selected = f.contains(v);
        }
        return Sample{float(value(size_t(0))), selected};
    }

    grid::GridSampler m_sampler;
    const RenderParams& m_params;
    const float* m_color;
    std::vector<const float*> m_brushValues;  // per brush: its variable's values, or null for a coordinate
    std::array<const float*, 3> m_velocity{};
    double m_shellRKm = NAN;                   // fixRadius's
    std::vector<std::vector<double>> m_layers;  // fixRadius's: the colour's, then per brush (empty: a coordinate)
};

// Per pixel: the colour variable (NaN where nothing is drawn) and whether it is selected.
struct PixelSamples {
    int width = 0, height = 0;
    std::vector<float> value;
    std::vector<uint8_t> selected;
    PixelSamples(int w, int h) : width(w), height(h), value(size_t(w) * size_t(h), NAN), selected(value.size(), 1) {}
};

// Samples every pixel: `sampleAt(x, y)` gives the sample at the centre of pixel (x, y), or nullopt
// where nothing is drawn.
template <class SampleAt>
PixelSamples samplePixels(int width, int height, const SampleAt& sampleAt)
{
    PixelSamples out(width, height);
    tbb::parallel_for(0, height, [&](int y) {
        for (int x = 0; x < width; ++x)
            if (const std::optional<PointProbe::Sample> s = sampleAt(x, y)) {
                const size_t i = size_t(y) * size_t(width) + size_t(x);
                out.value[i] = s->value;
                out.selected[i] = s->selected ? 1 : 0;
            }
    });
    return out;
}

}  // namespace raypc::render::slice
