#include "render/frame_buffer.h"

#include "core/error.h"
#include "render/render_kernel.h"

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <cmath>
#include <limits>

namespace raypc::render {

FrameBuffer::FrameBuffer(int width, int height) : m_width(width), m_height(height)
{
    if (width <= 0 || height <= 0 || width > 16384 || height > 16384)
        fail("image size {}x{}: expected 1..16384 pixels per side", width, height);
    m_blocksX = (width + kBlockSize - 1) / kBlockSize;
    m_blocksY = (height + kBlockSize - 1) / kBlockSize;
    clear();
}
FrameBuffer::~FrameBuffer() = default;
FrameBuffer::FrameBuffer(FrameBuffer&&) noexcept = default;
FrameBuffer& FrameBuffer::operator=(FrameBuffer&&) noexcept = default;

size_t FrameBuffer::bytesPerPixel()
{
    return 4 * sizeof(float) + sizeof(float) + sizeof(uint16_t) + sizeof(kernel::PixelOut);
}

void FrameBuffer::clear()
{
    const size_t n = size_t(m_width) * size_t(m_height);
    m_passes = 0;
    m_rgbaSum.assign(4 * n, 0.0f);
    m_depthSum.assign(n, 0.0f);
    m_depthCount.assign(n, 0);
    m_pass.resize(n);
    m_blockPasses.assign(size_t(blockCount()), 0);
    m_blockDone.assign(size_t(blockCount()), 0);
    m_blockError.assign(size_t(blockCount()), INFINITY);
    m_blockFirstError.assign(size_t(blockCount()), 0.0f);
}

void FrameBuffer::setRefinement(Refinement refinement)
{
    if (!(refinement.errorGreyLevels >= 0) || !std::isfinite(refinement.errorGreyLevels))
        fail("refinement error {}: expected a finite number of 8-bit levels >= 0 (0: off)", refinement.errorGreyLevels);
    if (refinement.minPasses < 1)
        fail("refinement: minimum passes {}: expected at least 1", refinement.minPasses);
    m_refinement = refinement;
}

bool FrameBuffer::converged() const
{
    return m_refinement.enabled() && std::all_of(m_blockDone.begin(), m_blockDone.end(), [](uint8_t d) { return d != 0; });
}

int FrameBuffer::tileCount() const
{
    return ((m_width + kTileSize - 1) / kTileSize) * ((m_height + kTileSize - 1) / kTileSize);
}

TileRect FrameBuffer::tile(int t) const
{
    const int tilesX = (m_width + kTileSize - 1) / kTileSize;
    const int tx = t % tilesX, ty = t / tilesX;
    return {tx * kTileSize, ty * kTileSize, std::min((tx + 1) * kTileSize, m_width),
            std::min((ty + 1) * kTileSize, m_height)};
}

TileRect FrameBuffer::block(int b) const
{
    const int bx = b % m_blocksX, by = b / m_blocksX;
    return {bx * kBlockSize, by * kBlockSize, std::min((bx + 1) * kBlockSize, m_width),
            std::min((by + 1) * kBlockSize, m_height)};
}

int FrameBuffer::blocksOfTile(int t, int (&out)[kMaxBlocksPerTile]) const
{
    static_assert(kTileSize % kBlockSize == 0, "a tile is a whole number of blocks");
    const TileRect r = tile(t);
    int n = 0;
    for (int by = r.y0 / kBlockSize; by * kBlockSize < r.y1; ++by)
        for (int bx = r.x0 / kBlockSize; bx * kBlockSize < r.x1; ++bx)
            out[n++] = by * m_blocksX + bx;
    return n;
}

float FrameBuffer::estimateErrorGreyLevels(int b, int passesAfter) const
{
    const TileRect r = block(b);
    float worst = 0;
    if (passesAfter == 1) {
        // One pass: the second differences along x and y centred on the block's pixels (the pixels
        // next to the block included, in whatever tile). The mean of later passes is a pixel's value
        // over its footprint (subpixel offsets) and over the along-ray offsets: where the image is
        // linear across a pixel's neighbours the footprint's mean is the centre's value, at an edge a
        // second difference d allows the centre to be off by up to d / 2, and the along-ray offset is
        // a hash of the pixel, so the sampling noise of a pass shows as second differences too.
        auto at = [&](int x, int y) -> const kernel::PixelOut& { return m_pass[size_t(y) * size_t(m_width) + size_t(x)]; };
        auto stencil = [&](int x, int y, int dx, int dy) {
            if (x - dx < 0 || y - dy < 0 || x + dx >= m_width || y + dy >= m_height)
                return;
            const kernel::PixelOut &u = at(x - dx, y - dy), &m = at(x, y), &v = at(x + dx, y + dy);
            worst = std::max({worst, std::abs(u.r - 2 * m.r + v.r), std::abs(u.g - 2 * m.g + v.g),
                              std::abs(u.b - 2 * m.b + v.b), std::abs(u.a - 2 * m.a + v.a)});
        };
        for (int y = r.y0; y < r.y1; ++y)
            for (int x = r.x0; x < r.x1; ++x) {
                stencil(x, y, 1, 0);
                stencil(x, y, 0, 1);
            }
        return 0.5f * 255.0f * worst;
    }
    // Later passes: how much this pass moves the block's mean, |x_n - mean_(n-1)| / n, at its worst
    // pixel; but at least the first pass's estimate / n. Where a sharp edge crosses the block a pixel's
    // few samples may all have fallen on one side so far (the mean then seems not to move); the
    // mean of n well-spread samples over the footprint is off by about 1 / n of one sample's error.
    const float previous = float(passesAfter - 1), inv = 1.0f / float(passesAfter);
    for (int y = r.y0; y < r.y1; ++y)
        for (int x = r.x0; x < r.x1; ++x) {
            const size_t i = size_t(y) * size_t(m_width) + size_t(x);
            const kernel::PixelOut& p = m_pass[i];
            const float* s = &m_rgbaSum[4 * i];
            worst = std::max({worst, std::abs(p.r - s[0] / previous), std::abs(p.g - s[1] / previous),
                              std::abs(p.b - s[2] / previous), std::abs(p.a - s[3] / previous)});
        }
    return std::max(255.0f * inv * worst, m_blockFirstError[size_t(b)] * inv);
}

void FrameBuffer::accumulateTile(int t, const std::vector<uint8_t>& rendered)
{
    int blocks[kMaxBlocksPerTile];
    const int nb = blocksOfTile(t, blocks);
    for (int k = 0; k < nb; ++k) {
        const int b = blocks[k];
        if (!rendered[size_t(b)])
            continue;
        const int passesAfter = int(m_blockPasses[size_t(b)]) + 1;
        // Before the sums change: the estimate of later passes reads the previous mean.
        if (m_refinement.enabled() && passesAfter >= m_refinement.minPasses) {
            m_blockError[size_t(b)] = estimateErrorGreyLevels(b, passesAfter);
            if (passesAfter == 1)
                m_blockFirstError[size_t(b)] = m_blockError[size_t(b)];
            m_blockDone[size_t(b)] = m_blockError[size_t(b)] < m_refinement.errorGreyLevels;
        }
        const TileRect r = block(b);
        for (int y = r.y0; y < r.y1; ++y)
            for (int x = r.x0; x < r.x1; ++x) {
                const size_t i = size_t(y) * size_t(m_width) + size_t(x);
                const kernel::PixelOut& p = m_pass[i];
                m_rgbaSum[4 * i] += p.r;
                m_rgbaSum[4 * i + 1] += p.g;
                m_rgbaSum[4 * i + 2] += p.b;
                m_rgbaSum[4 * i + 3] += p.a;
                if (std::isfinite(p.depthKm)) {
                    m_depthSum[i] += p.depthKm;
                    ++m_depthCount[i];
                }
            }
        m_blockPasses[size_t(b)] = uint32_t(passesAfter);
    }
}

namespace {
constexpr size_t kPackedFloatsPerPixel = 6;
constexpr size_t kPackedFloatsPerBlock = 2;
}  // namespace

std::vector<float> FrameBuffer::packTiles(TileShare share) const
{
    std::vector<float> out;
    for (int t = 0; t < tileCount(); ++t) {
        if (!share.owns(t))
            continue;
        const TileRect r = tile(t);
        for (int y = r.y0; y < r.y1; ++y)
            for (int x = r.x0; x < r.x1; ++x) {
                const size_t i = size_t(y) * size_t(m_width) + size_t(x);
                out.insert(out.end(), {m_rgbaSum[4 * i], m_rgbaSum[4 * i + 1], m_rgbaSum[4 * i + 2],
                                       m_rgbaSum[4 * i + 3], m_depthSum[i], float(m_depthCount[i])});
            }
        int blocks[kMaxBlocksPerTile];
        const int nb = blocksOfTile(t, blocks);
        for (int k = 0; k < nb; ++k)
            out.insert(out.end(), {float(m_blockPasses[size_t(blocks[k])]), float(m_blockDone[size_t(blocks[k])])});
    }
    return out;
}

size_t FrameBuffer::unpackTiles(std::span<const float> packed, TileShare share)
{
    size_t k = 0;
    for (int t = 0; t < tileCount(); ++t) {
        if (!share.owns(t))
            continue;
        const TileRect r = tile(t);
        int blocks[kMaxBlocksPerTile];
        const int nb = blocksOfTile(t, blocks);
        const size_t need = kPackedFloatsPerPixel * size_t(r.x1 - r.x0) * size_t(r.y1 - r.y0) +
                            kPackedFloatsPerBlock * size_t(nb);
        if (k + need > packed.size())
            fail("frame {}x{}: {} floats of gathered tiles, fewer than the tiles of worker {} of {} need",
                 m_width, m_height, packed.size(), share.index, share.count);
        for (int y = r.y0; y < r.y1; ++y)
            for (int x = r.x0; x < r.x1; ++x) {
                const size_t i = size_t(y) * size_t(m_width) + size_t(x);
                for (int c = 0; c < 4; ++c)
                    m_rgbaSum[4 * i + c] = packed[k++];
                m_depthSum[i] = packed[k++];
                m_depthCount[i] = uint16_t(packed[k++]);
            }
        for (int j = 0; j < nb; ++j) {
            const float passes = packed[k++], done = packed[k++];
            if (!(passes >= 0 && passes <= float(m_passes) && (done == 0 || done == 1)))
                fail("frame {}x{}: gathered tile {} of worker {} of {}: block with {} passes (frame: {}), stopped {}: "
                     "expected 0..{} passes and 0 or 1",
                     m_width, m_height, t, share.index, share.count, passes, m_passes, done, m_passes);
            m_blockPasses[size_t(blocks[j])] = uint32_t(passes);
            m_blockDone[size_t(blocks[j])] = uint8_t(done);
        }
    }
    return k;
}

std::vector<float> FrameBuffer::averagedRgba() const
{
    std::vector<float> out(m_rgbaSum.size());
    tbb::parallel_for(0, blockCount(), [&](int b) {
        const uint32_t n = m_blockPasses[size_t(b)];
        const float s = n > 0 ? 1.0f / float(n) : 0.0f;
        const TileRect r = block(b);
        for (int y = r.y0; y < r.y1; ++y)
            for (size_t i = 4 * (size_t(y) * size_t(m_width) + size_t(r.x0)), end = i + 4 * size_t(r.x1 - r.x0); i < end; ++i)
                out[i] = m_rgbaSum[i] * s;
    });
    return out;
}

std::vector<float> FrameBuffer::averagedDepthKm() const
{
    std::vector<float> out(m_depthSum.size());
    tbb::parallel_for(tbb::blocked_range<size_t>(0, out.size(), 1 << 16), [&](const tbb::blocked_range<size_t>& range) {
        for (size_t i = range.begin(); i < range.end(); ++i)
            out[i] = m_depthCount[i] ? m_depthSum[i] / float(m_depthCount[i]) : INFINITY;
    });
    return out;
}

std::vector<uint8_t> FrameBuffer::resolveRgba8(Rgb background, bool opaqueBackground) const
{
    return toRgba8(averagedRgba(), background, opaqueBackground);
}

std::vector<uint8_t> toRgba8(const std::vector<float>& rgba, Rgb background, bool opaqueBackground)
{
    std::vector<uint8_t> out(rgba.size());
    // Rounds as std::lround of the float product (half away from zero, here >= 0), without a call
    // per channel: a 1920x1080 frame has 8 M of them.
    auto to8 = [](float v) { return uint8_t(double(std::clamp(v, 0.0f, 1.0f) * 255.0f) + 0.5); };
    tbb::parallel_for(tbb::blocked_range<size_t>(0, rgba.size() / 4, 1 << 14), [&](const tbb::blocked_range<size_t>& pixels) {
        for (size_t i = 4 * pixels.begin(); i < 4 * pixels.end(); i += 4) {
            const float t = 1.0f - rgba[i + 3];
            if (opaqueBackground) {
                out[i] = to8(rgba[i] + t * background.r);
                out[i + 1] = to8(rgba[i + 1] + t * background.g);
                out[i + 2] = to8(rgba[i + 2] + t * background.b);
                out[i + 3] = 255;
            } else {
                out[i] = to8(rgba[i]);
                out[i + 1] = to8(rgba[i + 1]);
                out[i + 2] = to8(rgba[i + 2]);
                out[i + 3] = to8(rgba[i + 3]);
            }
        }
    });
    return out;
}

}  // namespace raypc::render
