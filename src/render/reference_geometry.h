// Reference geometry drawn with the volume so that a picture says where and how deep: thin
// translucent shells at given depths (e.g. 410 and 660 km), a latitude/longitude graticule and the
// coastlines on the surface (RenderState::reference, docs/state.md).
//
// It is composited by depth with a finished volume image (premultiplied RGBA and the per-pixel depth
// of FrameBuffer: where the accumulated opacity reached depthOpacity, or the core): geometry in
// front of that depth is drawn over the volume, geometry behind it shows only through what the
// volume leaves transparent. A shell is a thin layer: its opacity grows with the path length
// through it (1 / |cos| of the angle to its normal), so it is faint face-on and marks its
// silhouette. Lines are anti-aliased, `lineWidthPx` wide, on the near side of the surface only.
//
// Units: km (contest Cartesian frame, core/spherical.h), degrees for lat/lon.
// Thread safety: plain functions; Coastlines is immutable once read.
#pragma once

#include "render/camera.h"
#include "render/legend.h"
#include "state/render_state.h"

#include <array>
#include <filesystem>
#include <memory>
#include <optional>
#include <span>
#include <vector>

namespace raypc::render {

// Polylines of (lon, lat) degrees: the coastlines of the Earth's land (Natural Earth 1:110m).
struct Coastlines {
    std::vector<std::vector<std::pair<float, float>>> lines;
    size_t pointCount() const;
};

// Reads a coastline file written by the UI build (web/build.mjs from the npm package world-atlas):
// JSON {"source": "...", "lines": [[lon, lat, lon, lat, ...], ...]}. Throws raypc::Error naming
// the file and what is wrong.
Coastlines readCoastlines(const std::filesystem::path& file);

// The coastline file found like the UI's assets: $RAYPC_COASTLINES (a file; when set, the only
// place looked at), else coastlines.json in
// $RAYPC_ASSETS, the source tree's web/dist, and beside the executable (web/, ../web/dist). Read
// once and shared. Throws raypc::Error listing where it looked when there is none.
std::shared_ptr<const Coastlines> defaultCoastlines();

// The colour of the shell at `index` of shells.depthsKm: a fixed palette (yellow, green, magenta,
// orange, violet, then again) that keeps clear of the volume maps' blues, reds and whites, so that
// neighbouring shells such as 410 and 660 km differ, multiplied by shells.color (white: the palette).
Rgb shellColor(const state::ReferenceState::Shells& shells, size_t index);

// Each drawn shell's depth ("660 km") where it goes on the picture: on the shell's silhouette ring,
// the shells' labels staggered in angle from the upper right down (deeper shells lower), so that
// the labels of close shells do not overlap; none for a shell the eye is inside or whose label
// would fall outside the image. Coloured as the shell (shellColor).
std::vector<TextLabel> shellLabels(const state::ReferenceState& reference, const OrbitCamera& camera, int width, int height,
                                   float surfaceRadiusKm, float coreRadiusKm);

// The outline of the sphere of `radiusKm` (the surface) as the camera sees it: `points` points of
// its silhouette circle in image pixels (closed: the last joins the first); empty when the eye is
// inside the sphere or a point of the circle is behind the eye.
std::vector<std::array<float, 2>> sphereOutline(const OrbitCamera& camera, int width, int height, float radiusKm,
                                                int points = 96);

// The shells' key of a legend: each drawn shell's depth and colour (positions unused); pictures'
// legends draw it, and the server's frame headers carry it for the UI's legend.
std::vector<TextLabel> shellKey(const state::ReferenceState& reference, float surfaceRadiusKm, float coreRadiusKm);

// Where the map and the section lie, drawn in the 3D view while they are shown (state.map.showInView):
// the map's depth as a shell of its own colour (cyan) and the section's curtain, the great-circle arc
// at the surface and at the innermost radius and the radial lines at its ends, composited by depth
// as the other lines.
struct SliceMarks {
    float depthKm = 0;
    state::SectionState::Point from, to;
};
inline constexpr Rgb kSliceMarkColor{0.2f, 0.9f, 1.0f};

// The reference geometry of one view, rasterised: each pixel's fragments (shells crossed, lines)
// sorted front to back, at their distance along the pixel's ray, premultiplied. It depends on the
// reference state, the camera and the image size, not on the volume, so the passes of a still state
// and the steps of playback composite one layer over each of their frames (StateRenderer keeps it).
// Arguments as drawReferenceGeometry's. Immutable once made: composite may run on several threads.
class ReferenceLayer {
public:
    ReferenceLayer(const state::ReferenceState& reference, const OrbitCamera& camera, int width, int height,
                   float surfaceRadiusKm, float coreRadiusKm, const Coastlines* coastlines,
                   const SliceMarks* marks = nullptr);
    // Composites the layer with a volume image of the layer's size, as drawReferenceGeometry.
    void composite(std::vector<float>& rgba, const std::vector<float>& depthKm) const;
    bool empty() const { return m_fragments.empty(); }
    size_t bytes() const;  // what keeping it costs

    struct Fragment {
        float t;           // km along the pixel's ray from the eye
        float r, g, b, a;  // premultiplied
    };

private:
    int m_width = 0, m_height = 0;
    std::vector<uint32_t> m_first;  // per pixel, its first fragment; one more at the end
    std::vector<Fragment> m_fragments;
};

// Draws `reference` into `rgba` (premultiplied, width x height x 4 floats, row-major from the top
// left, as FrameBuffer::averagedRgba) using `depthKm` (FrameBuffer::averagedDepthKm, +inf where the
// volume never became opaque). `surfaceRadiusKm` carries the graticule and the coastlines; shells
// lie at surfaceRadiusKm - depth, drawn only between `coreRadiusKm` and the surface. `coastlines`
// may be null when reference.coastlines is hidden.
// `marks`, when given, adds the map's and the section's marks. ReferenceLayer(...).composite.
void drawReferenceGeometry(const state::ReferenceState& reference, const OrbitCamera& camera, int width, int height,
                           float surfaceRadiusKm, float coreRadiusKm, std::vector<float>& rgba,
                           const std::vector<float>& depthKm, const Coastlines* coastlines,
                           const SliceMarks* marks = nullptr);

}  // namespace raypc::render
