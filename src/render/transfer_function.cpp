#include "render/transfer_function.h"

#include "core/error.h"

#include <algorithm>
#include <cmath>
#include <numeric>

namespace raypc::render {

float absQuantile(dataset::ValueRange values, std::span<const double> histogram, double q)
{
    const float largest = std::max(std::abs(values.min), std::abs(values.max));
    const double total = std::accumulate(histogram.begin(), histogram.end(), 0.0);
    if (histogram.empty() || !(total > 0) || !(values.max > values.min))
        return largest;
    // Each bin's fraction spread evenly over its values, folded onto |value|: the fraction above a
    // magnitude m is the sum over bins of the part of each bin beyond ±m.
    const double width = (double(values.max) - values.min) / double(histogram.size());
    auto beyond = [&](double m) {
        double f = 0;
        for (size_t i = 0; i < histogram.size(); ++i) {
            const double lo = values.min + width * double(i), hi = lo + width;
            const double above = std::max(0.0, hi - std::max(lo, m)), below = std::max(0.0, std::min(hi, -m) - lo);
            f += histogram[i] * (above + below) / width;
        }
        return f / total;
    };
    // Bisection on the magnitude: `beyond` falls from 1 (at 0) to 0 (at the larger magnitude).
    double a = 0, b = largest;
    for (int k = 0; k < 60; ++k) {
        const double m = 0.5 * (a + b);
        (beyond(m) > 1.0 - q ? a : b) = m;
    }
    return float(b);
}

float niceCeil(float x)
{
    if (!(x > 0) || !std::isfinite(x))
        return x;
    const double decade = std::pow(10.0, std::floor(std::log10(double(x))));
    for (double n : {1.0, 1.5, 2.0, 2.5, 3.0, 4.0, 5.0, 6.0, 8.0, 10.0})
        if (n * decade >= double(x) * (1 - 1e-6))
            return float(n * decade);
    return float(10 * decade);
}

dataset::ValueRange defaultColorRange(dataset::ValueRange r, bool centredOnZero, std::span<const double> histogram)
{
    if (centredOnZero) {
        const float largest = std::max(std::abs(r.min), std::abs(r.max));
        const float m = histogram.empty() ? largest : std::min(largest, niceCeil(absQuantile(r, histogram, 0.995)));
        r = {-m, m};
    }
    if (!(r.min < r.max))
        r = {r.min - 0.5f, r.max + 0.5f};
    return r;
}

dataset::ValueRange defaultColorRange(const dataset::VariableStats& stats, bool centredOnZero)
{
    return defaultColorRange(stats.range, centredOnZero, stats.histogram);
}

void TransferFunction::validate() const
{
    if (!std::isfinite(range.min) || !std::isfinite(range.max) || !(range.min < range.max))
        fail("transfer function range [{}, {}]: expected finite min < max", range.min, range.max);
    if (opacity.empty())
        fail("transfer function opacity: no points, expected at least one");
    for (size_t i = 0; i < opacity.size(); ++i) {
        const auto& p = opacity[i];
        if (!(p.position >= 0 && p.position <= 1))
            fail("opacity point {}: position {} outside [0, 1]", i, p.position);
        if (!(p.opacity >= 0 && p.opacity <= 1))
            fail("opacity point {}: opacity {} outside [0, 1]", i, p.opacity);
        if (i > 0 && p.position < opacity[i - 1].position)
            fail("opacity point {}: position {} is below the previous one; expected ascending positions", i,
                 p.position);
    }
    if (!(opacityUnitKm > 0) || !std::isfinite(opacityUnitKm))
        fail("opacity unit distance {} km: expected a positive distance", opacityUnitKm);
    for (size_t i = 0; i < colorPoints.size(); ++i) {
        const auto& p = colorPoints[i];
        if (!(p.u >= 0 && p.u <= 1))
            fail("colour point {}: position {} outside [0, 1]", i, p.u);
        if (i > 0 && p.u < colorPoints[i - 1].u)
            fail("colour point {}: position {} is below the previous one; expected ascending positions", i, p.u);
        for (float c : {p.c.r, p.c.g, p.c.b})
            if (!(c >= 0 && c <= 1))
                fail("colour point {}: colour component {} outside [0, 1]", i, c);
    }
    if (logScale && !(range.min > 0))
        fail("log scale over the range [{}, {}]: expected a positive minimum", range.min, range.max);
}

float TransferFunction::positionOf(float value) const
{
    float u;
    if (logScale)
        u = (std::log10(std::max(value, range.min)) - std::log10(range.min)) /
            (std::log10(range.max) - std::log10(range.min));
    else
        u = (value - range.min) / (range.max - range.min);
    return std::clamp(std::isfinite(u) ? u : 0.0f, 0.0f, 1.0f);
}

float TransferFunction::colorPositionOf(float value) const
{
    float u;
    if (colorPoints.empty() && !logScale && state::isCentredOnZero(colorMap)) {
        // Centred maps put value 0 at the middle colour, scaled by the larger magnitude.
        const float magnitude = std::max(std::abs(range.min), std::abs(range.max));
        u = std::clamp(0.5f + 0.5f * value / magnitude, 0.0f, 1.0f);
    } else {
        u = positionOf(value);
    }
    return reversed ? 1.0f - u : u;
}

Rgb TransferFunction::colorAt(float u) const
{
    return colorPoints.empty() ? sampleColorMap(colorMap, u) : sampleStops(colorPoints, u);
}

Rgb TransferFunction::colorOf(float value) const { return colorAt(colorPositionOf(value)); }

float TransferFunction::opacityAt(float u) const
{
    if (u <= opacity.front().position)
        return opacity.front().opacity;
    for (size_t i = 1; i < opacity.size(); ++i) {
        if (u <= opacity[i].position) {
            const auto& a = opacity[i - 1];
            const auto& b = opacity[i];
            const float span = b.position - a.position;
            return span > 0 ? a.opacity + (u - a.position) / span * (b.opacity - a.opacity) : b.opacity;
        }
    }
    return opacity.back().opacity;
}

TransferTable TransferTable::bake(const TransferFunction& tf)
{
    tf.validate();
    TransferTable t;
    t.valueMin = tf.range.min;
    t.indexScale = float(kSize - 1) / (tf.range.max - tf.range.min);
    t.red.resize(kSize);
    t.green.resize(kSize);
    t.blue.resize(kSize);
    t.sigmaPerKm.resize(kSize);
    t.nonzeroPrefix.assign(kSize + 1, 0);
    // The table is indexed linearly in value; with a log scale its entries hold the colour and
    // opacity at the value's logarithmic position (the lowest decades get few entries).
    for (int i = 0; i < kSize; ++i) {
        const float value = tf.range.min + float(i) / float(kSize - 1) * (tf.range.max - tf.range.min);
        const float u = tf.positionOf(value);
        const Rgb c = tf.colorOf(value);
        t.red[i] = c.r;
        t.green[i] = c.g;
        t.blue[i] = c.b;
        // Full opacity is capped so that sigma stays finite; 1 - 1e-6 is opaque for every purpose.
        const float a = std::min(tf.opacityAt(u), 1.0f - 1e-6f);
        t.sigmaPerKm[i] = float(-std::log1p(-double(a)) / tf.opacityUnitKm);
        t.nonzeroPrefix[i + 1] = t.nonzeroPrefix[i] + (t.sigmaPerKm[i] > 0.0f ? 1 : 0);
    }
    return t;
}

int TransferTable::indexOf(float value) const
{
    const float k = (value - valueMin) * indexScale + 0.5f;
    return int(std::clamp(k, 0.0f, float(kSize - 1)));
}

bool TransferTable::transparentOver(float lo, float hi) const
{
    if (!(lo <= hi))
        return true;  // a brick of nothing but missing values: (+inf, -inf)
    const int a = indexOf(lo), b = indexOf(hi);
    return nonzeroPrefix[b + 1] - nonzeroPrefix[a] == 0;
}

}  // namespace raypc::render
