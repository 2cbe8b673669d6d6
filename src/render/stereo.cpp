#include "render/stereo.h"

#include "core/error.h"

#include <algorithm>
#include <cmath>
#include <string>

namespace raypc::render {

StereoLayout stereoLayout(StereoMode mode, int width, int height)
{
    StereoLayout l{width, height, width, height, 1.0, mode == StereoMode::Off ? 1 : 2};
    if (mode == StereoMode::SideBySide) {
        l.width = 2 * width;
    } else if (mode == StereoMode::SideBySideHalf) {
        l.eyeWidth = std::max(1, width / 2);
        l.width = 2 * l.eyeWidth;
        l.pixelAspect = double(width) / double(l.eyeWidth);
    }
    return l;
}

namespace {

void checkEyes(const StereoLayout& layout, size_t left, size_t right, size_t channels)
{
    const size_t n = size_t(layout.eyeWidth) * size_t(layout.eyeHeight) * channels;
    RAYPC_CHECK_EQ(left, n);
    RAYPC_CHECK_EQ(right, n);
}

// Rows of two eye images of `channels` values a pixel, left | right.
template <class T>
std::vector<T> besideEachOther(const StereoLayout& l, const std::vector<T>& left, const std::vector<T>& right,
                               size_t channels)
{
    checkEyes(l, left.size(), right.size(), channels);
    const size_t row = size_t(l.eyeWidth) * channels;
    std::vector<T> out(2 * row * size_t(l.eyeHeight));
    for (size_t y = 0; y < size_t(l.eyeHeight); ++y) {
        std::copy_n(left.begin() + std::ptrdiff_t(y * row), row, out.begin() + std::ptrdiff_t(2 * y * row));
        std::copy_n(right.begin() + std::ptrdiff_t(y * row), row, out.begin() + std::ptrdiff_t(2 * y * row + row));
    }
    return out;
}

}  // namespace

std::vector<uint8_t> composeStereo(StereoMode mode, const StereoLayout& layout, const std::vector<uint8_t>& left,
                                   const std::vector<uint8_t>& right)
{
    if (mode != StereoMode::Anaglyph)
        return besideEachOther(layout, left, right, 4);
    checkEyes(layout, left.size(), right.size(), 4);
    std::vector<uint8_t> out(left.size());
    for (size_t i = 0; i < left.size(); i += 4) {
        const double luma = 0.299 * left[i] + 0.587 * left[i + 1] + 0.114 * left[i + 2];
        out[i] = uint8_t(std::clamp(std::lround(luma), 0L, 255L));
        out[i + 1] = right[i + 1];
        out[i + 2] = right[i + 2];
        out[i + 3] = std::max(left[i + 3], right[i + 3]);
    }
    return out;
}

std::vector<float> sideBySide(const StereoLayout& layout, const std::vector<float>& left, const std::vector<float>& right)
{
    return besideEachOther(layout, left, right, 1);
}

}  // namespace raypc::render
