#include "render/line_raster.h"

#include <algorithm>

namespace raypc::render {

namespace {

// Calls `mark(pixel index, coverage, u)` for every pixel the segment covers (u: where along it).
template <class Mark>
void rasterSegment(const LineLayer& layer, float x0, float y0, float x1, float y1, float widthPx, const Mark& mark)
{
    const float half = 0.5f * widthPx;
    const float pad = half + 1.0f;
    const int ix0 = std::max(0, int(std::floor(std::min(x0, x1) - pad)));
    const int ix1 = std::min(layer.width - 1, int(std::ceil(std::max(x0, x1) + pad)));
    const int iy0 = std::max(0, int(std::floor(std::min(y0, y1) - pad)));
    const int iy1 = std::min(layer.height - 1, int(std::ceil(std::max(y0, y1) + pad)));
    const float dx = x1 - x0, dy = y1 - y0;
    const float len2 = dx * dx + dy * dy;
    for (int y = iy0; y <= iy1; ++y)
        for (int x = ix0; x <= ix1; ++x) {
            const float cx = float(x) + 0.5f, cy = float(y) + 0.5f;
            const float u = len2 > 0 ? std::clamp(((cx - x0) * dx + (cy - y0) * dy) / len2, 0.0f, 1.0f) : 0.0f;
            const float ex = x0 + u * dx - cx, ey = y0 + u * dy - cy;
            const float dist = std::sqrt(ex * ex + ey * ey);
            const float c = std::clamp(half + 0.5f - dist, 0.0f, 1.0f);
            if (c <= 0)
                continue;
            mark(size_t(y) * size_t(layer.width) + size_t(x), c, u);
        }
}

}  // namespace

void drawSegment(LineLayer& layer, float x0, float y0, float t0, float x1, float y1, float t1, float widthPx)
{
    rasterSegment(layer, x0, y0, x1, y1, widthPx, [&](size_t i, float c, float u) {
        if (c > layer.coverage[i]) {
            layer.coverage[i] = c;
            if (!layer.t.empty())
                layer.t[i] = t0 + u * (t1 - t0);
        }
    });
}

void drawSegment(LineLayer& layer, float x0, float y0, float x1, float y1, float widthPx, Rgb color, float weight)
{
    rasterSegment(layer, x0, y0, x1, y1, widthPx, [&](size_t i, float c, float) {
        c *= std::clamp(weight, 0.0f, 1.0f);
        if (c > layer.coverage[i]) {
            layer.coverage[i] = c;
            if (!layer.color.empty())
                layer.color[i] = color;
        }
    });
}

void compositeLines(std::vector<uint8_t>& rgba, const LineLayer& layer, Rgb color, float opacity)
{
    for (size_t i = 0; i < layer.coverage.size(); ++i) {
        const float a = layer.coverage[i] * opacity;
        if (a <= 0)
            continue;
        const Rgb own = layer.color.empty() ? color : layer.color[i];
        const float c[3] = {own.r * 255.0f, own.g * 255.0f, own.b * 255.0f};
        uint8_t* p = &rgba[i * 4];
        for (int k = 0; k < 3; ++k)
            p[k] = uint8_t(std::clamp(p[k] + (c[k] - p[k]) * a + 0.5f, 0.0f, 255.0f));
        p[3] = uint8_t(std::clamp(p[3] + (255.0f - p[3]) * a + 0.5f, 0.0f, 255.0f));
    }
}

void compositeLines(std::vector<uint8_t>& rgba, const LineLayer& layer, float opacity)
{
    compositeLines(rgba, layer, Rgb{1, 1, 1}, opacity);
}

}  // namespace raypc::render
