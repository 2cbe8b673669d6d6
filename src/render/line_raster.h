// Anti-aliased lines in pictures: the graticule and coastlines on the globe (reference_geometry.h)
// and on maps, contours and axes of maps and sections (slice_view.h). A line is rasterised into a
// coverage layer first (per pixel the strongest coverage drawn, so crossing segments of one kind do
// not add up), then composited in one colour.
//
// Pixel centres are at (x + 0.5, y + 0.5), y down, as in the images.
#pragma once

#include "render/color_map.h"

#include <cmath>
#include <cstdint>
#include <vector>

namespace raypc::render {

// Per pixel the strongest coverage drawn and, for lines in 3D, its distance along the pixel's ray;
// for lines of many colours (pathlines on maps and sections), the colour of that strongest line.
struct LineLayer {
    int width, height;
    std::vector<float> coverage, t;  // t: empty for lines in the picture's plane (maps, sections)
    std::vector<Rgb> color;          // empty for lines of one colour
    LineLayer(int w, int h, bool withDistance = true, bool withColor = false)
        : width(w), height(h), coverage(size_t(w) * size_t(h), 0.0f), t(withDistance ? size_t(w) * size_t(h) : 0, INFINITY),
          color(withColor ? size_t(w) * size_t(h) : 0)
    {
    }
};

// A segment `widthPx` wide; coverage falls off over one pixel beyond half the width. t0 and t1
// (the ends' distances along their rays) are interpolated into the layer's t where it is drawn
// (when it has one).
void drawSegment(LineLayer& layer, float x0, float y0, float t0, float x1, float y1, float t1, float widthPx);
// In the picture's plane.
inline void drawSegment(LineLayer& layer, float x0, float y0, float x1, float y1, float widthPx)
{
    drawSegment(layer, x0, y0, 0, x1, y1, 0, widthPx);
}

// In the picture's plane, in `color` (the layer has colours), its coverage scaled by `weight` in
// [0, 1] (a fainter line).
void drawSegment(LineLayer& layer, float x0, float y0, float x1, float y1, float widthPx, Rgb color, float weight);

// Blends the layer into 8-bit RGBA (straight alpha, opaque or not), `color` at coverage x opacity.
void compositeLines(std::vector<uint8_t>& rgba, const LineLayer& layer, Rgb color, float opacity);
// The same in each pixel's own colour (a layer with colours).
void compositeLines(std::vector<uint8_t>& rgba, const LineLayer& layer, float opacity);

}  // namespace raypc::render
