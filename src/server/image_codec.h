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
std::string encodePng(std::span<const uint8_t> rgba, int width, int height);

}  // namespace raypc::server
