// How units are written (src/render/display_units.json, shared with the UI's units.ts).
#include "render/legend.h"

#include <gtest/gtest.h>

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

}  // namespace
}  // namespace raypc::render
