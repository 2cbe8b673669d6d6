// In-memory image encoders for the network: JPEG (libturbojpeg) for frames, PNG (libpng) for
// screenshots. Throw raypc::Error on encoder failure.
//
// Thread safety: reentrant (each call uses its own encoder handle).
#pragma once

#include <cstdint>
#include <span>
#include <string>

namespace raypc::server {

// `rgba` is width x height x 4 bytes, row-major from the top-left; alpha is ignored.
std::string encodeJpeg(std::span<const uint8_t> rgba, int width, int height, int quality);
// zlib's `compressionLevel` (1 quickest .. 9 smallest): 6 for screenshots; the interactive maps
// and sections take 1 (a 1920x1080 map in about a fifth of the time, bench/render_bench.cpp).
std::string encodePng(std::span<const uint8_t> rgba, int width, int height, int compressionLevel = 6);

}  // namespace raypc::server
