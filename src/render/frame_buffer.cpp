#include "render/frame_buffer.h"

#include "core/error.h"
#include "render/render_kernel.h"

#include <algorithm>
#include <cmath>
#include <limits>

namespace raypc::render {

FrameBuffer::FrameBuffer(int width, int height) : m_width(width), m_height(height)
{
    if (width <= 0 || height <= 0 || width > 16384 || height > 16384)
        fail("image size {}x{}: expected 1..16384 pixels per side", width, height);
    clear();
}
FrameBuffer::~FrameBuffer() = default;
FrameBuffer::FrameBuffer(FrameBuffer&&) noexcept = default;
FrameBuffer& FrameBuffer::operator=(FrameBuffer&&) noexcept = default;

void FrameBuffer::clear()
{
    const size_t n = size_t(m_width) * size_t(m_height);
    m_passes = 0;
    m_rgbaSum.assign(4 * n, 0.0f);
    m_depthSum.assign(n, 0.0f);
    m_depthCount.assign(n, 0);
    m_pass.resize(n);
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

namespace {
constexpr size_t kPackedFloatsPerPixel = 6;
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
        const size_t need = kPackedFloatsPerPixel * size_t(r.x1 - r.x0) * size_t(r.y1 - r.y0);
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
    }
    return k;
}

std::vector<float> FrameBuffer::averagedRgba() const
{
    std::vector<float> out(m_rgbaSum.size());
    const float s = m_passes > 0 ? 1.0f / float(m_passes) : 0.0f;
    for (size_t i = 0; i < out.size(); ++i)
        out[i] = m_rgbaSum[i] * s;
    return out;
}

std::vector<float> FrameBuffer::averagedDepthKm() const
{
    std::vector<float> out(m_depthSum.size());
    for (size_t i = 0; i < out.size(); ++i)
        out[i] = m_depthCount[i] ? m_depthSum[i] / float(m_depthCount[i]) : INFINITY;
    return out;
}

std::vector<uint8_t> FrameBuffer::resolveRgba8(Rgb background, bool opaqueBackground) const
{
    return toRgba8(averagedRgba(), background, opaqueBackground);
}

std::vector<uint8_t> toRgba8(const std::vector<float>& rgba, Rgb background, bool opaqueBackground)
{
    std::vector<uint8_t> out(rgba.size());
    auto to8 = [](float v) { return uint8_t(std::lround(std::clamp(v, 0.0f, 1.0f) * 255.0f)); };
    for (size_t i = 0; i < rgba.size(); i += 4) {
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
    return out;
}

}  // namespace raypc::render
