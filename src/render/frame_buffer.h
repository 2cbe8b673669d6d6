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

// Adaptive refinement of still frames (docs/rendering.md, "Adaptive refinement"): a block of
// FrameBuffer::kBlockSize² pixels stops taking passes once its estimated error is below
// `errorGreyLevels` (8-bit units of premultiplied RGBA); the other blocks go on. The estimate
// reads only the block's pixels and, after the first pass, the first pass's pixels around it (a
// pixel's value depends only on the pixel and the pass), so a frame shared out by tiles
// (TileShare) decides as one rendered whole does. Off (errorGreyLevels 0): every pass renders
// every pixel.
struct Refinement {
    float errorGreyLevels = 0;
    // Passes every block takes before its error is estimated: 1 estimates from the first pass's
    // differences between neighbouring pixels, later passes from how much a pass changed the mean.
    int minPasses = 1;
    bool enabled() const { return errorGreyLevels > 0; }
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
    // Passes rendered into the frame (the pass number of the next one); with refinement a block
    // that stopped holds fewer (blockPasses).
    int passes() const { return m_passes; }
    // The memory the buffer holds per pixel (bytes): its sums, depth counts and a pass's scratch.
    static size_t bytesPerPixel();
    void clear();  // restart accumulation (after a restart-class change); keeps the refinement

    // Refinement for the passes to come (Refinement{}: off). Set it on an empty frame.
    void setRefinement(Refinement refinement);
    const Refinement& refinement() const { return m_refinement; }

    // Tiles of a pass: the unit of work of the ray caster's threads and of TileShare.
    static constexpr int kTileSize = 32;
    int tileCount() const;
    TileRect tile(int t) const;

    // Blocks: the unit of adaptive refinement, kTileSize / kBlockSize per side of a tile, row-major
    // over the frame.
    static constexpr int kBlockSize = 8;
    static constexpr int kMaxBlocksPerTile = (kTileSize / kBlockSize) * (kTileSize / kBlockSize);
    int blockCount() const { return m_blocksX * m_blocksY; }
    TileRect block(int b) const;
    // The blocks of tile t, row-major; returns their number.
    int blocksOfTile(int t, int (&out)[kMaxBlocksPerTile]) const;
    // Passes accumulated in block b, and whether it takes the next pass (not yet converged).
    int blockPasses(int b) const { return m_blockPasses[size_t(b)]; }
    bool blockRefining(int b) const { return !m_blockDone[size_t(b)]; }
    // The last estimate of block b's error (8-bit units; +inf before one was made).
    float blockErrorGreyLevels(int b) const { return m_blockError[size_t(b)]; }
    // Refinement is on and every block has stopped (a further pass renders nothing).
    bool converged() const;

    // The accumulated sums of the tiles `share` owns, in tile order (per tile 6 floats a pixel:
    // RGBA, depth sum, depth count, then 2 floats per block of the tile: its passes, 1 if it has
    // stopped refining); unpackTiles puts such a block back. Used to gather a shared-out frame:
    // the sums, not averages, move, so the gathered frame equals one rendered whole, bit for bit.
    std::vector<float> packTiles(TileShare share) const;
    // Reads the tiles of `share` from the front of `packed` and returns the floats it used.
    size_t unpackTiles(std::span<const float> packed, TileShare share);

    // Mean of the passes so far (of each block's own passes): premultiplied RGBA, row-major from the top-left, 4 floats a pixel.
    std::vector<float> averagedRgba() const;
    // Mean of the finite per-pass depths (km), +inf where no pass had one.
    std::vector<float> averagedDepthKm() const;
    // 8-bit RGBA, composited over `background` when `opaqueBackground`, else premultiplied with alpha.
    std::vector<uint8_t> resolveRgba8(Rgb background, bool opaqueBackground = true) const;

private:
    friend class VolumeRenderer;
    // Estimates the error of the blocks of tile t with rendered[b] set, stops those below the
    // threshold, then adds the pass in m_pass to them. Distinct tiles may be accumulated
    // concurrently. A block's first-pass estimate also reads the pixels of m_pass next to it, which
    // the caller must have rendered in this pass (VolumeRenderer renders those of tiles it does
    // not render itself: firstPassNeighbours).
    void accumulateTile(int t, const std::vector<uint8_t>& rendered);
    float estimateErrorGreyLevels(int b, int blockPassesAfter) const;
    // Whether this pass estimates some block from its first pass (and reads its neighbours' pixels).
    bool firstPassEstimates() const { return m_refinement.enabled() && m_refinement.minPasses == 1 && m_passes == 0; }

    int m_width, m_height, m_passes = 0;
    int m_blocksX, m_blocksY;
    Refinement m_refinement;
    std::vector<float> m_rgbaSum, m_depthSum;
    std::vector<uint16_t> m_depthCount;
    std::vector<uint32_t> m_blockPasses;
    std::vector<uint8_t> m_blockDone;
    std::vector<float> m_blockError;
    std::vector<float> m_blockFirstError;  // the first pass's estimate (0 when not made)
    std::vector<kernel::PixelOut> m_pass;  // scratch of the pass being rendered
};

}  // namespace raypc::render
