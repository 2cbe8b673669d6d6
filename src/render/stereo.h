// Stereo pairs of a render state (docs/rendering.md, "Stereo"): which pictures a stereo state
// makes and how the two eyes' pictures become one image.
//
// The eyes' cameras come from render/camera.h (stereoEye: parallel axes, off-axis frustum); the
// eyes' render states from render/resolve_state.h (stereoViews). Here: the layout of the output
// and the composition of two finished 8-bit RGBA pictures (after reference geometry and legends,
// so that every overlay of a picture is drawn once per eye by the one picture path).
//
// Units: km. Images are row-major from the top left, 4 bytes (RGBA) or one float per pixel.
// Thread safety: pure functions.
#pragma once

#include "state/view_types.h"

#include <cstdint>
#include <optional>
#include <string_view>
#include <vector>

namespace raypc::render {

// The stereo mode and settings are the state's (state/view_types.h).
using state::StereoMode;
using state::StereoState;

// Sizes of one eye's picture and of the composed image for a state of width x height.
struct StereoLayout {
    int eyeWidth = 0, eyeHeight = 0;  // each eye's picture
    int width = 0, height = 0;        // the composed image
    double pixelAspect = 1;           // of the eyes' pixels (2 for the squeezed half-width eyes)
    int eyes = 1;                     // 1 (off) or 2
    // Pixels the ray caster renders (and frame buffers hold): every eye's.
    int64_t renderedPixels() const { return int64_t(eyes) * eyeWidth * eyeHeight; }
};
// Off and anaglyph: W x H eyes and image; side-by-side: W x H eyes, 2W x H image; half:
// max(1, W/2) x H eyes with pixel aspect W / eye width, 2 max(1, W/2) x H image (W for even W).
StereoLayout stereoLayout(StereoMode mode, int width, int height);

// The composed image of two eyes' 8-bit RGBA pictures (layout.eyeWidth x eyeHeight each). The
// anaglyph is "half colour": red = round(0.299 R + 0.587 G + 0.114 B) of the left eye (its
// luma, so that blue and green parts of the left picture still reach the left eye behind a red
// filter), green and blue = the right eye's; alpha the larger of the two.
std::vector<uint8_t> composeStereo(StereoMode mode, const StereoLayout& layout, const std::vector<uint8_t>& left,
                                   const std::vector<uint8_t>& right);
// The eyes' depths (or any one-channel images) side by side, (2 x eyeWidth) x eyeHeight, in every
// mode: an anaglyph's depth is not one image.
std::vector<float> sideBySide(const StereoLayout& layout, const std::vector<float>& left, const std::vector<float>& right);

}  // namespace raypc::render
