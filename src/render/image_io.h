// Image files written by the renderer: PNG (libpng) and PFM depth maps, both written atomically.
#pragma once

#include <cstdint>
#include <filesystem>
#include <vector>

namespace raypc::render {

struct ImageRgba8 {
    int width = 0, height = 0;
    std::vector<uint8_t> pixels;  // RGBA, row-major from the top-left
};

// Writes an 8-bit RGBA PNG (RGB when `dropAlpha`). Throws raypc::Error naming the path on failure.
void writePng(const std::filesystem::path& path, const ImageRgba8& image, bool dropAlpha = true);
// Reads an 8-bit PNG of any colour type into RGBA. Throws raypc::Error naming the path.
ImageRgba8 readPng(const std::filesystem::path& path);
// Writes one float channel as a little-endian PFM ("Pf", rows stored bottom to top as the format says).
void writePfm(const std::filesystem::path& path, int width, int height, const std::vector<float>& values);

}  // namespace raypc::render
