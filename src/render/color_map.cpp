#include "render/color_map.h"

#include <algorithm>
#include <cmath>

namespace raypc::render {

Rgb sampleStops(std::span<const ColorStop> stops, float u)
{
    u = std::clamp(std::isfinite(u) ? u : 0.0f, 0.0f, 1.0f);
    if (stops.size() == 1)
        return stops[0].c;
    size_t i = 1;
    while (i + 1 < stops.size() && stops[i].u < u)
        ++i;
    const ColorStop& a = stops[i - 1];
    const ColorStop& b = stops[i];
    const float w = b.u > a.u ? std::clamp((u - a.u) / (b.u - a.u), 0.0f, 1.0f) : 1.0f;
    return {a.c.r + w * (b.c.r - a.c.r), a.c.g + w * (b.c.g - a.c.g), a.c.b + w * (b.c.b - a.c.b)};
}

Rgb sampleColorMap(ColorMapId map, float u) { return sampleStops(state::colorMapStops(map), u); }

}  // namespace raypc::render
