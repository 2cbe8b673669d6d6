#include "render/image_io.h"

#include "core/atomic_file.h"
#include "core/error.h"

#include <png.h>

#include <cstring>
#include <string>

namespace raypc::render {
namespace {

void appendBytes(png_structp png, png_bytep data, png_size_t length)
{
    auto* out = static_cast<std::string*>(png_get_io_ptr(png));
    out->append(reinterpret_cast<const char*>(data), length);
}

}  // namespace

void writePng(const std::filesystem::path& path, const ImageRgba8& image, bool dropAlpha)
{
    if (image.width <= 0 || image.height <= 0 || image.pixels.size() != size_t(image.width) * image.height * 4)
        fail("{}: image {}x{} with {} bytes is inconsistent", path.string(), image.width, image.height,
             image.pixels.size());
    png_structp png = png_create_write_struct(PNG_LIBPNG_VER_STRING, nullptr, nullptr, nullptr);
    png_infop info = png ? png_create_info_struct(png) : nullptr;
    if (!png || !info) {
        png_destroy_write_struct(&png, &info);
        fail("{}: cannot create a PNG writer", path.string());
    }
    std::string bytes;
    std::vector<uint8_t> row(size_t(image.width) * 4);
    if (setjmp(png_jmpbuf(png))) {
        png_destroy_write_struct(&png, &info);
        fail("{}: PNG encoding failed", path.string());
    }
    png_set_write_fn(png, &bytes, appendBytes, nullptr);
    png_set_IHDR(png, info, png_uint_32(image.width), png_uint_32(image.height), 8,
                 dropAlpha ? PNG_COLOR_TYPE_RGB : PNG_COLOR_TYPE_RGBA, PNG_INTERLACE_NONE,
                 PNG_COMPRESSION_TYPE_DEFAULT, PNG_FILTER_TYPE_DEFAULT);
    png_write_info(png, info);
    for (int y = 0; y < image.height; ++y) {
        const uint8_t* src = image.pixels.data() + size_t(y) * image.width * 4;
        if (dropAlpha) {
            for (int x = 0; x < image.width; ++x)
                std::memcpy(row.data() + 3 * size_t(x), src + 4 * size_t(x), 3);
        } else {
            std::memcpy(row.data(), src, row.size());
        }
        png_write_row(png, row.data());
    }
    png_write_end(png, nullptr);
    png_destroy_write_struct(&png, &info);
    writeFileAtomic(path, bytes);
}

ImageRgba8 readPng(const std::filesystem::path& path)
{
    const std::string bytes = readFile(path);
    png_image img;
    std::memset(&img, 0, sizeof img);
    img.version = PNG_IMAGE_VERSION;
    if (!png_image_begin_read_from_memory(&img, bytes.data(), bytes.size()))
        fail("{}: not a readable PNG ({})", path.string(), img.message);
    img.format = PNG_FORMAT_RGBA;
    ImageRgba8 out;
    out.width = int(img.width);
    out.height = int(img.height);
    out.pixels.resize(PNG_IMAGE_SIZE(img));
    if (!png_image_finish_read(&img, nullptr, out.pixels.data(), 0, nullptr)) {
        png_image_free(&img);
        fail("{}: PNG decoding failed ({})", path.string(), img.message);
    }
    return out;
}

void writePfm(const std::filesystem::path& path, int width, int height, const std::vector<float>& values)
{
    if (values.size() != size_t(width) * size_t(height))
        fail("{}: depth map {}x{} with {} values is inconsistent", path.string(), width, height, values.size());
    std::string bytes = "Pf\n" + std::to_string(width) + " " + std::to_string(height) + "\n-1.0\n";
    const size_t header = bytes.size();
    bytes.resize(header + values.size() * sizeof(float));
    for (int y = 0; y < height; ++y)  // PFM rows go bottom to top
        std::memcpy(bytes.data() + header + size_t(y) * width * sizeof(float),
                    values.data() + size_t(height - 1 - y) * width, size_t(width) * sizeof(float));
    writeFileAtomic(path, bytes);
}

}  // namespace raypc::render
