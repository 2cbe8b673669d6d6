// Transfer function: a colour map plus piecewise-linear opacity over one variable's value range,
// and its baked lookup table for the kernels.
//
// Opacity is defined per `opacityUnitKm` of path length: a slab of that thickness with constant
// opacity a lets 1 - a through. The table stores the extinction sigma = -ln(1 - a) / opacityUnitKm
// (1/km), and a sample of step dt gets alpha = 1 - exp(-sigma dt) ("opacity correction"), so the
// look does not depend on the sampling rate.
#pragma once

#include "dataset/dataset.h"
#include "render/color_map.h"
#include "state/view_types.h"

#include <span>
#include <vector>

namespace raypc::render {

using state::OpacityPoint;  // state/view_types.h

// The colour range a variable gets when none is chosen: the one rule for the default view, the
// presets (which name no range), the volume, the pathlines and the UI (which takes it from
// /api/info). For maps centred on zero (isCentredOnZero: anomalies, signed velocities) it is
// symmetric, ±the 99.5th percentile of |value| over the series (volume-weighted, from `histogram`:
// kHistogramBins fractions over `values`, VariableStats::histogram) rounded up to a nice number (1,
// 1.5, 2, 2.5, 3, 4, 5, 6, 8 × 10^k) but never beyond the larger magnitude: the few extreme points
// do not wash out the plumes and slabs. Without a histogram, ±the larger magnitude. Other maps take
// the exact range. A constant (or empty) range is widened by 0.5 each way so that it stays usable.
dataset::ValueRange defaultColorRange(dataset::ValueRange values, bool centredOnZero,
                                      std::span<const double> histogram = {});
// The same for a variable's statistics over the series (VariableInfo::global).
dataset::ValueRange defaultColorRange(const dataset::VariableStats& stats, bool centredOnZero);
// The quantile `q` (0..1) of |value| for a histogram of kHistogramBins fractions over `values`
// (linear within a bin); the larger magnitude for an empty histogram.
float absQuantile(dataset::ValueRange values, std::span<const double> histogram, double q);
// The smallest nice number (1, 1.5, 2, 2.5, 3, 4, 5, 6, 8 × 10^k) ≥ x > 0.
float niceCeil(float x);

struct TransferFunction {
    ColorMapId colorMap = ColorMapId::Viridis;
    dataset::ValueRange range{0, 1};  // values outside are clamped to the ends
    std::vector<OpacityPoint> opacity = {{0, 0}, {1, 0.5f}};
    float opacityUnitKm = 100.0f;
    // Colour control points (the UI's editor, a ParaView colour map): when not empty they replace
    // colorMap, positions normalised as the opacity's (not centred on zero).
    std::vector<ColorStop> colorPoints;
    bool reversed = false;  // the colours run from the map's end to its start
    // Positions (colour and opacity) over log10 of the value: for positive quantities; range.min > 0.
    bool logScale = false;

    // Normalised position of a value: linear, or logarithmic with logScale (clamped to [0, 1]).
    float positionOf(float value) const;
    // The colour of a value (the map or the colour points, reversed if asked; centred maps put 0 in
    // the middle).
    Rgb colorOf(float value) const;
    // colorOf in two parts: where a value falls on the colours (in [0, 1], centring and reversal
    // applied), and the colour there (the map or the colour points); a table of colorAt serves
    // pictures of millions of values.
    float colorPositionOf(float value) const;
    Rgb colorAt(float u) const;

    // Throws raypc::Error on an empty or inverted range, positions not ascending in [0, 1],
    // opacities outside [0, 1], a non-positive unit distance, colour points not ascending in
    // [0, 1] or with components outside [0, 1], or a log scale over a range that is not positive.
    void validate() const;
    // Opacity at normalised position u (piecewise linear, constant beyond the end points).
    float opacityAt(float u) const;
};

// The baked table: kSize entries over [range.min, range.max], nearest-entry lookup.
struct TransferTable {
    static constexpr int kSize = 1024;
    float valueMin = 0;
    float indexScale = 0;  // (kSize - 1) / (max - min)
    std::vector<float> red, green, blue, sigmaPerKm;
    std::vector<int> nonzeroPrefix;  // kSize + 1 prefix counts of sigma > 0, for range queries

    static TransferTable bake(const TransferFunction& tf);
    int indexOf(float value) const;
    // True when sigma is 0 for every value in [lo, hi].
    bool transparentOver(float lo, float hi) const;
};

}  // namespace raypc::render
