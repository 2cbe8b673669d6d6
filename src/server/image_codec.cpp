#include "server/image_codec.h"

#include "core/error.h"

#include <png.h>
#include <turbojpeg.h>

#include <memory>
#include <vector>

namespace raypc::server {

std::string encodeJpeg(std::span<const uint8_t> rgba, int width, int height, int quality)
{
    RAYPC_CHECK_EQ(rgba.size(), size_t(width) * size_t(height) * 4);
    std::unique_ptr<void, int (*)(tjhandle)> handle(tjInitCompress(), tjDestroy);
    if (!handle)
        fail("JPEG encoder: {}", tjGetErrorStr2(nullptr));
    unsigned char* buffer = nullptr;
    unsigned long size = 0;
    if (tjCompress2(handle.get(), rgba.data(), width, 0, height, TJPF_RGBX, &buffer, &size, TJSAMP_420, quality,
                    TJFLAG_FASTDCT) != 0) {
        const std::string message = tjGetErrorStr2(handle.get());
        tjFree(buffer);
        fail("JPEG encoder: {}", message);
    }
    std::string out(reinterpret_cast<const char*>(buffer), size);
    tjFree(buffer);
    return out;
}

std::string encodePng(std::span<const uint8_t> rgba, int width, int height, int compressionLevel)
{
    RAYPC_CHECK_EQ(rgba.size(), size_t(width) * size_t(height) * 4);
    png_structp png = png_create_write_struct(PNG_LIBPNG_VER_STRING, nullptr, nullptr, nullptr);
    if (!png)
        fail("PNG encoder: out of memory");
    png_infop info = png_create_info_struct(png);
    std::string out;
    // Rows as RGB (the frame is opaque over its background).
    std::vector<uint8_t> row(size_t(width) * 3);
    if (!info || setjmp(png_jmpbuf(png))) {
        png_destroy_write_struct(&png, &info);
        fail("PNG encoder failed for a {}x{} image", width, height);
    }
    png_set_write_fn(
        png, &out,
        [](png_structp p, png_bytep data, png_size_t n) {
            static_cast<std::string*>(png_get_io_ptr(p))->append(reinterpret_cast<const char*>(data), n);
        },
        nullptr);
    png_set_IHDR(png, info, png_uint_32(width), png_uint_32(height), 8, PNG_COLOR_TYPE_RGB, PNG_INTERLACE_NONE,
                 PNG_COMPRESSION_TYPE_DEFAULT, PNG_FILTER_TYPE_DEFAULT);
    png_set_compression_level(png, compressionLevel);
    // The quickest levels filter each row by its left neighbour only (the adaptive choice of
    // filters costs more than it saves there).
    if (compressionLevel <= 2)
        png_set_filter(png, PNG_FILTER_TYPE_BASE, PNG_FILTER_SUB);
    png_write_info(png, info);
    for (int y = 0; y < height; ++y) {
        const uint8_t* src = rgba.data() + size_t(y) * size_t(width) * 4;
        for (int x = 0; x < width; ++x)
            for (int c = 0; c < 3; ++c)
                row[size_t(x) * 3 + size_t(c)] = src[size_t(x) * 4 + size_t(c)];
        png_write_row(png, row.data());
    }
    png_write_end(png, nullptr);
    png_destroy_write_struct(&png, &info);
    return out;
}

}  // namespace raypc::server
