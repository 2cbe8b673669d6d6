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
#include "render/render_state.h"

#include <filesystem>
#include <memory>
#include <optional>
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

// Draws `reference` into `rgba` (premultiplied, width x height x 4 floats, row-major from the top
// left, as FrameBuffer::averagedRgba) using `depthKm` (FrameBuffer::averagedDepthKm, +inf where the
// volume never became opaque). `surfaceRadiusKm` carries the graticule and the coastlines; shells
// lie at surfaceRadiusKm - depth, drawn only between `coreRadiusKm` and the surface. `coastlines`
// may be null when reference.coastlines is hidden.
void drawReferenceGeometry(const ReferenceState& reference, const OrbitCamera& camera, int width, int height,
                           float surfaceRadiusKm, float coreRadiusKm, std::vector<float>& rgba,
                           const std::vector<float>& depthKm, const Coastlines* coastlines);

}  // namespace raypc::render
