// The accumulation buffer of progressive passes (VolumeRenderer::renderPass writes it).
//
// Thread safety: not thread-safe; one pass at a time.
#pragma once

#include "render/color_map.h"

#include <cstdint>
#include <span>
#include <vector>

namespace raypc::render {

namespace kernel {
struct PixelOut;
}  // namespace kernel

// 8-bit RGBA of premultiplied float RGBA (4 floats a pixel): composited over `background` when
// `opaqueBackground`, else premultiplied with alpha.
std::vector<uint8_t> toRgba8(const std::vector<float>& premultipliedRgba, Rgb background, bool opaqueBackground = true);

// Which tiles of every pass one worker renders when a frame is shared out (image-parallel under
// mpirun, docs/scaling.md): tile t (row-major, FrameBuffer::kTileSize pixels a side) when
// t % count == index, so that every worker gets tiles from all over the image. {0, 1}: all tiles.
struct TileShare {
    int index = 0, count = 1;
    bool owns(int tile) const { return tile % count == index; }
    bool all() const { return count == 1; }
};

// A tile's pixels [x0, x1) x [y0, y1).
struct TileRect {
    int x0, y0, x1, y1;
};

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

    // Tiles of a pass: the unit of work of the ray caster's threads and of TileShare.
    static constexpr int kTileSize = 32;
    int tileCount() const;
    TileRect tile(int t) const;

    // The accumulated sums of the tiles `share` owns, in tile order (6 floats a pixel: RGBA, depth
    // sum, depth count); unpackTiles puts such a block back. Used to gather a shared-out frame:
    // the sums, not averages, move, so the gathered frame equals one rendered whole, bit for bit.
    std::vector<float> packTiles(TileShare share) const;
    // Reads the tiles of `share` from the front of `packed` and returns the floats it used.
    size_t unpackTiles(std::span<const float> packed, TileShare share);

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
