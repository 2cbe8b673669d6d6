// How units are written (src/render/display_units.json, shared with the UI's units.ts); the colour
// bars' ticks.
#include "render/legend.h"
#include "render/slice_drawing.h"

#include <gtest/gtest.h>

#include <cmath>
#include <string>

namespace raypc::render {
namespace {

TEST(DisplayUnits, SymbolsForWholeNamesAndSuperscriptsForExponents)
{
    EXPECT_EQ(displayUnits("degrees_north"), "°N");
    EXPECT_EQ(displayUnits("degrees_east"), "°E");
    EXPECT_EQ(displayUnits("kg/m^3"), "kg/m³");
    EXPECT_EQ(displayUnits("m^2/s"), "m²/s");
    // A name only as the whole string; exponents without a superscript in the table stay as written.
    EXPECT_EQ(displayUnits("degrees_north per km"), "degrees_north per km");
    EXPECT_EQ(displayUnits("x^4"), "x^4");
    EXPECT_EQ(displayUnits("^^3"), "^³");
    EXPECT_EQ(displayUnits("W/m/K"), "W/m/K");
    EXPECT_EQ(displayUnits(""), "");
    EXPECT_EQ(displayUnits("m^"), "m^");
}

// The ticks of a colour bar of [lo, hi] in a picture of width x height, drawn as drawLegends draws
// them (its bar, its font), checked: at least two, in order, each label inside the bar and at
// least half a font's height from the next (measured in the font drawn), each value inside the range
// at its own position along the bar, the values a round step apart (1, 2 or 5 × 10^k) and
// multiples of it (or every other one of them: 4 × 10^k).
void expectTicksApart(float lo, float hi, int width, int height)
{
    TransferFunction tf;
    tf.range = {lo, hi};
    const int fontPx = legendFontPx(width, height), barPx = legendBarPx(width, height);
    const auto measure = [&](const std::string& t) { return legendTextWidthPx(t, fontPx); };
    const std::vector<LegendSpec::Tick> ticks = colorBarTicks(tf, barPx, fontPx / 2, measure);
    SCOPED_TRACE(testing::Message() << "[" << lo << ", " << hi << "] in " << width << "x" << height << ": bar " << barPx << " px, font " << fontPx << " px");
    ASSERT_GE(ticks.size(), 2u);
    int right = -1000000;
    std::vector<double> values;
    for (const LegendSpec::Tick& t : ticks) {
        const int w = measure(t.text), left = tickLabelLeftPx(t.at, w, barPx);
        EXPECT_GE(left, 0) << t.text;
        EXPECT_LE(left + w, barPx) << t.text;
        EXPECT_GE(left - right, fontPx / 2) << "'" << t.text << "' runs into the label before it";
        right = left + w;
        const double v = std::stod(t.text);
        EXPECT_GE(v, lo - 1e-6 * (hi - lo)) << t.text;
        EXPECT_LE(v, hi + 1e-6 * (hi - lo)) << t.text;
        EXPECT_NEAR(t.at, (v - lo) / (hi - lo), 1e-4) << t.text;
        values.push_back(v);
    }
    const double step = values[1] - values[0];
    const double mant = step / std::pow(10.0, std::floor(std::log10(step)));
    EXPECT_TRUE(std::abs(mant - 1) < 1e-6 || std::abs(mant - 2) < 1e-6 || std::abs(mant - 4) < 1e-6 || std::abs(mant - 5) < 1e-6)
        << "step " << step;
    for (size_t i = 0; i < values.size(); ++i) {
        EXPECT_NEAR(values[i] / step, std::round(values[i] / step), 1e-6) << values[i];
        if (i > 0) {
            EXPECT_NEAR(values[i] - values[i - 1], step, 1e-6 * step) << values[i];
        }
    }
}

// The colour bars ("-269.8 -205.6 -141.4", "0 8.545 17.09" ran together) at the sizes the
// UI asks (time–depth pictures in the side panel, maps and sections in the bottom panel) and at
// screenshot sizes.
TEST(ColorBarTicks, RoundValuesThatDoNotCollide)
{
    for (const auto& [w, h] : {std::pair{240, 160}, {320, 200}, {360, 240}, {480, 270}, {640, 360}, {958, 240}, {1280, 720}, {1920, 1080}, {3840, 2160}}) {
        expectTicksApart(-269.8f, 372.1f, w, h);
        expectTicksApart(0.0f, 17.09f, w, h);
        expectTicksApart(-451.8f, 451.8f, w, h);
        expectTicksApart(0.99f, 1.0037f, w, h);
    }
}

TEST(ColorBarTicks, PowersOfTenOnALogScaleAndOneLabelForOneValue)
{
    TransferFunction tf;
    tf.range = {1e-3f, 10.0f};
    tf.logScale = true;
    const auto measure = [](const std::string& t) { return legendTextWidthPx(t, 12); };
    const std::vector<LegendSpec::Tick> ticks = colorBarTicks(tf, 200, 12, measure);
    ASSERT_GE(ticks.size(), 2u);
    for (const LegendSpec::Tick& t : ticks) {
        const double e = std::log10(std::stod(t.text));
        EXPECT_NEAR(e, std::round(e), 1e-9) << t.text;
        EXPECT_NEAR(t.at, (e + 3) / 4, 1e-4) << t.text;
    }
    tf.logScale = false;
    tf.range = {5.0f, 5.0f};
    const std::vector<LegendSpec::Tick> one = colorBarTicks(tf, 200, 12, measure);
    ASSERT_EQ(one.size(), 1u);
    EXPECT_EQ(one[0].text, "5");
}

// A picture's title (maps, sections, time–depth pictures) fits its width as drawn, in the labels'
// font: the parts that fit, the first one shortened with "…" when it alone does not.
TEST(FitTitle, MeasuredInTheLabelsFontAndNeverWiderThanThePicture)
{
    const std::string first = "selected share of each shell [%] · temperature anomaly ≥ 100 K and depth 500–800 km";
    for (const int w : {200, 320, 480, 958, 1920}) {
        const int h = w * 3 / 5, fontPx = labelFontPx(w, h);
        const std::string t = slice::fitTitle({first, "0.0–120.5 Myr", "Mollweide centred on 0.0°E"}, w, h);
        SCOPED_TRACE(testing::Message() << w << "x" << h << ": '" << t << "'");
        EXPECT_LE(legendTextWidthPx(t, fontPx) + 2 * fontPx, w);
        EXPECT_FALSE(t.empty());
        if (t.size() < first.size())
            EXPECT_EQ(t.substr(t.size() - 3), "…");
        else
            EXPECT_EQ(t.substr(0, first.size()), first);
    }
}

}  // namespace
}  // namespace raypc::render
