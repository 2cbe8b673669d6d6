#include "render/feature_paint.h"

#include "core/error.h"

#include <tbb/parallel_for.h>

#include <algorithm>
#include <array>
#include <cmath>

namespace raypc::render {
namespace {

// The nearest index of `to` for each value of `from` (both ascending); `periodic`: values in
// degrees of a closed circle (longitude), compared across the seam.
std::vector<size_t> nearestIndices(const std::vector<double>& from, const std::vector<double>& to, bool periodic)
{
    std::vector<size_t> out(from.size());
    for (size_t i = 0; i < from.size(); ++i) {
        size_t best = 0;
        double bestDistance = INFINITY;
        for (size_t j = 0; j < to.size(); ++j) {
            double d = std::abs(from[i] - to[j]);
            if (periodic)
                d = std::min(d, 360.0 - std::fmod(d, 360.0));
            if (d < bestDistance)
                bestDistance = d, best = j;
        }
        out[i] = best;
    }
    return out;
}

}  // namespace

Rgb featurePaintColor(int slot)
{
    // Tableau 10 (as d3.schemeTableau10); the UI takes these from GET /api/info (featurePalette).
    static constexpr std::array<Rgb, kFeaturePaintSlots> kPalette{{
        // 0: no painted feature, a dark neutral grey (a quarter of a diverging map's light neutral,
        // lit or not) and faint, so the rest is never mistaken for a near-zero value.
        {0.20f, 0.20f, 0.20f},
        {0x4e / 255.f, 0x79 / 255.f, 0xa7 / 255.f}, {0xf2 / 255.f, 0x8e / 255.f, 0x2c / 255.f},
        {0xe1 / 255.f, 0x57 / 255.f, 0x59 / 255.f}, {0x76 / 255.f, 0xb7 / 255.f, 0xb2 / 255.f},
        {0x59 / 255.f, 0xa1 / 255.f, 0x4f / 255.f}, {0xed / 255.f, 0xc9 / 255.f, 0x49 / 255.f},
        {0xaf / 255.f, 0x7a / 255.f, 0xa1 / 255.f}, {0xff / 255.f, 0x9d / 255.f, 0xa7 / 255.f},
        {0x9c / 255.f, 0x75 / 255.f, 0x5f / 255.f}, {0xba / 255.f, 0xb0 / 255.f, 0xac / 255.f},
        {1.0f, 0.75f, 0.1f},                                                  // 11: highlighted
    }};
    RAYPC_CHECK(slot >= 0 && slot < kFeaturePaintSlots);
    return kPalette[size_t(slot)];
}

bool paintsFeatures(const state::RenderState& state)
{
    return !state.brushes.empty() && (state.features.colorById || !state.features.highlight.empty());
}

std::vector<float> featurePaintField(const grid::SphericalGrid& target, const grid::SphericalGrid& labelGrid,
                                     std::span<const int32_t> labels, const state::FeatureSettings& settings)
{
    if (labels.size() != labelGrid.cellCount())
        fail("feature paint: {} labels for a grid of {} points", labels.size(), labelGrid.cellCount());
    const std::vector<size_t> lat = nearestIndices(target.latDeg, labelGrid.latDeg, false);
    const std::vector<size_t> r = nearestIndices(target.rKm, labelGrid.rKm, false);
    const std::vector<size_t> lon = nearestIndices(target.lonDeg, labelGrid.lonDeg, true);
    const auto slotOf = [&](int32_t label) -> float {
        if (label <= 0)
            return -1;  // no feature
        const bool highlighted = std::find(settings.highlight.begin(), settings.highlight.end(), label) !=
                                 settings.highlight.end();
        if (!settings.highlight.empty() && !highlighted)
            return 0;
        return settings.colorById ? float((label - 1) % 10 + 1) : 11.0f;
    };
    const size_t nLat = target.nLat(), nR = target.nR(), nLon = target.nLon();
    std::vector<float> slots(target.cellCount());
    tbb::parallel_for(size_t(0), nLat, [&](size_t i) {
        for (size_t k = 0; k < nR; ++k)
            for (size_t j = 0; j < nLon; ++j)
                slots[target.index(i, k, j)] = slotOf(labels[labelGrid.index(lat[i], r[k], lon[j])]);
    });
    // Points of no feature take a neighbour's slot (the first found of lon, r, lat neighbours).
    std::vector<float> out(slots.size());
    tbb::parallel_for(size_t(0), nLat, [&](size_t i) {
        for (size_t k = 0; k < nR; ++k)
            for (size_t j = 0; j < nLon; ++j) {
                const size_t at = target.index(i, k, j);
                float v = slots[at];
                if (v < 0) {
                    const std::array<std::array<size_t, 3>, 6> around{{{i, k, (j + 1) % nLon},
                                                                        {i, k, (j + nLon - 1) % nLon},
                                                                        {i, k + 1, j},
                                                                        {i, k - 1, j},
                                                                        {i + 1, k, j},
                                                                        {i - 1, k, j}}};
                    for (const auto& [a, b, c] : around)
                        if (a < nLat && b < nR && slots[target.index(a, b, c)] >= 0) {
                            v = slots[target.index(a, b, c)];
                            break;
                        }
                }
                out[at] = std::max(v, 0.0f);
            }
    });
    return out;
}

void applyFeaturePaint(RenderParams& params, int variable)
{
    TransferFunction& tf = params.transfer;
    tf.range = {-0.5f, float(kFeaturePaintSlots) - 0.5f};
    tf.logScale = false;
    tf.reversed = false;
    tf.colorPoints.clear();
    const float n = float(kFeaturePaintSlots);
    // Each slot's colour over its own unit of the range, sharp between slots.
    for (int s = 0; s < kFeaturePaintSlots; ++s) {
        tf.colorPoints.push_back({(float(s) + 0.02f) / n, featurePaintColor(s)});
        tf.colorPoints.push_back({(float(s) + 0.98f) / n, featurePaintColor(s)});
    }
    tf.opacity = {{0.0f, kFeatureRestOpacity}, {0.98f / n, kFeatureRestOpacity}, {1.02f / n, 0.8f}, {1.0f, 0.8f}};
    params.colorVariable = variable;
    params.selectionMinOpacity = 0;
}

LegendSpec featurePaintLegend(const state::FeatureSettings& settings)
{
    LegendSpec legend;
    TransferFunction& tf = legend.colors;
    if (settings.colorById) {
        tf.range = {0.5f, 10.5f};
        for (int s = 1; s <= 10; ++s) {
            tf.colorPoints.push_back({(float(s) - 0.98f) / 10, featurePaintColor(s)});
            tf.colorPoints.push_back({(float(s) - 0.02f) / 10, featurePaintColor(s)});
            legend.ticks.push_back({(float(s) - 0.5f) / 10, std::to_string(s)});
        }
        legend.title = settings.highlight.empty() ? "feature id (colours repeat every 10); dark grey: the rest of the selection"
                                                  : "highlighted features by id; the rest of the selection dark grey";
    } else {
        tf.range = {0, 1};
        tf.colorPoints = {{0, featurePaintColor(0)}, {0.49f, featurePaintColor(0)}, {0.51f, featurePaintColor(11)},
                          {1, featurePaintColor(11)}};
        legend.ticks = {{0.25f, "rest"}, {0.75f, "highlighted"}};
        legend.title = "highlighted features (amber); the rest of the selection dark grey";
    }
    return legend;
}

}  // namespace raypc::render
