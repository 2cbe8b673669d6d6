// The accumulation buffer of progressive passes (VolumeRenderer::renderPass writes it).
//
// Thread safety: not thread-safe; one pass at a time.
#pragma once

#include "render/color_map.h"

#include <cstdint>
#include <vector>

namespace raypc::render {

namespace kernel {
struct PixelOut;
}  // namespace kernel

// 8-bit RGBA of premultiplied float RGBA (4 floats a pixel): composited over `background` when
// `opaqueBackground`, else premultiplied with alpha.
std::vector<uint8_t> toRgba8(const std::vector<float>& premultipliedRgba, Rgb background, bool opaqueBackground = true);

// Accumulates progressive passes. Colours are premultiplied by alpha (alpha = 1 - transmittance).
class FrameBuffer {
public:
    FrameBuffer(int width, int height);
    ~FrameBuffer();
    FrameBuffer(FrameBuffer&&) noexcept;
    FrameBuffer& operator=(FrameBuffer&&) noexcept;

    int width() const { return m_width; }
    int height() const { return m_height; }
    int passes() const { return m_passes; }
    void clear();  // restart accumulation (after a restart-class change)

    // Mean of the passes so far: premultiplied RGBA, row-major from the top-left, 4 floats a pixel.
    std::vector<float> averagedRgba() const;
    // Mean of the finite per-pass depths (km), +inf where no pass had one.
    std::vector<float> averagedDepthKm() const;
    // 8-bit RGBA, composited over `background` when `opaqueBackground`, else premultiplied with alpha.
    std::vector<uint8_t> resolveRgba8(Rgb background, bool opaqueBackground = true) const;

private:
    friend class VolumeRenderer;
    int m_width, m_height, m_passes = 0;
    std::vector<float> m_rgbaSum, m_depthSum;
    std::vector<uint16_t> m_depthCount;
    std::vector<kernel::PixelOut> m_pass;  // scratch of the pass being rendered
};

}  // namespace raypc::render
