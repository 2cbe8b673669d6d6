// The features of a step painted in the 3D view (state.features.colorById and .highlight, state
// version 11; docs/features.md): the connected regions of the state's selection (analysis/features.h,
// found at features.level with features.minVolumeKm3) each in its own colour, or the highlighted
// ones in amber, and the rest of the selection dark grey and faint. What the renderer draws is an extra
// variable of the step's volume (StepVolume::withVariable) holding each grid point's palette slot,
// coloured by a transfer function of fixed colours: the one path from a state to pixels is kept.
//
// Thread safety: pure functions of their arguments.
#pragma once

#include "dataset/dataset.h"
#include "analysis/selection.h"
#include "render/legend.h"
#include "state/render_state.h"
#include "render/volume_renderer.h"

#include <span>
#include <string>
#include <vector>

namespace raypc::render {

// The palette's slots: 0 the selected material of no painted feature, 1..10 a feature by its id
// (slot (id - 1) mod 10 + 1; Tableau 10, sent to the UI in GET /api/info), 11 a highlighted feature
// without colorById.
inline constexpr int kFeaturePaintSlots = 12;
Rgb featurePaintColor(int slot);

// Whether the state paints features.
bool paintsFeatures(const state::RenderState& state);

// The slot of every grid point of `target` (canonical order): the feature labels of `labels` (a
// StepFeatures::labels on `labelGrid`, any level of the same dataset: each target point takes the
// label of the nearest label-grid point along each axis, longitude wrapping) turned into slots as
// the state's settings say. A point with no feature takes a neighbouring point's slot (6
// neighbours, the longitude seam joined), so that interpolation at a feature's edge stays in its
// colour; where there is none, 0.
std::vector<float> featurePaintField(const grid::SphericalGrid& target, const grid::SphericalGrid& labelGrid,
                                     std::span<const int32_t> labels, const state::FeatureSettings& settings);

// The opacity (per opacityUnitKm) of slot 0, the selected material of no painted feature.
inline constexpr float kFeatureRestOpacity = 0.08f;
// Colours the volume by the slots of variable `variable`: the fixed palette, slot 0 dark grey and
// faint (kFeatureRestOpacity), painted slots 0.8.
void applyFeaturePaint(RenderParams& params, int variable);

// The legend of painted features: with colorById the ten colours of ids 1..10 (each labelled with its
// id), else grey ("rest") then amber ("highlighted"); the title says which.
LegendSpec featurePaintLegend(const state::FeatureSettings& settings);

}  // namespace raypc::render
