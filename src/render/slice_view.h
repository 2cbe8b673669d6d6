// Maps of a depth slice and great-circle cross-sections (RenderState::map and ::section, docs/state.md;
// `raypc map`, `raypc section`, `raypc render --view map|section`).
//
// Both sample the native grid at every pixel (GridSampler: the interpolation of the ray caster and
// `raypc probe`, pole caps and the lon seam included; no resampled copy: a map interpolates in radius
// once, into the shell's lat-lon layer, then each pixel in lat and lon), colour the state's colour
// variable by its transfer function's colours (not its opacity), grey what lies outside the
// brushes, and draw contours, the flow as arrows, coastlines and graticule (maps), the reference
// shells' depths (sections), a title and the legend. The grids they export (CF netCDF, for GMT,
// xarray, Panoply) are sampled the same way.
//
// Units: km (radius, depth, distance along the surface), degrees (lat north, lon east), the
// variable's own units; velocities (vx, vy, vz: m/s in the contest's Cartesian frame) in cm/yr.
// Thread safety: plain functions over immutable inputs; parallel over rows (oneTBB) inside. Maps keep
// every pixel's inverse projection of the last two frames (projection, centre, size) in a
// thread-safe cache shared by all callers.
//
// Maps are drawn in map_view.cpp, sections in section_view.cpp; how both sample the grid and what
// they draw alike (with the time–depth pictures of time_depth_view.h) in slice_sampling.h and
// slice_drawing.h.
#pragma once

#include "core/vec3.h"
#include "dataset/dataset.h"
#include "analysis/selection.h"
#include "render/image_io.h"
#include "render/map_projection.h"
#include "render/pathline_scene.h"
#include "render/reference_geometry.h"
#include "state/render_state.h"
#include "render/state_renderer.h"

#include <array>
#include <optional>
#include <string>
#include <vector>

namespace raypc::render {

// Where a map's pixels fall: the projected sphere fitted into a rectangle of the picture, centred.
class MapFrame {
public:
    // `left`, `top`, `width`, `height`: the rectangle in pixels. Throws raypc::Error for a centre
    // outside [-180, 180] x [-90, 90] (Projector) or an empty rectangle.
    MapFrame(const state::MapState& map, double left, double top, double width, double height);

    // (lon, lat) degrees at a point of the picture (pixel centres at +0.5), or nullopt off the sphere.
    std::optional<std::array<double, 2>> lonLatAt(double px, double py) const;
    // The picture's point of (lon, lat), or nullopt where the projection does not show it.
    std::optional<std::array<double, 2>> pixelOf(double lonDeg, double latDeg) const;
    // Pixels per unit of the projection's plane (the sphere's radius is this many pixels for the
    // orthographic projection).
    double scale() const { return m_scale; }
    // The picture's point of the projection's centre.
    std::array<double, 2> centrePx() const { return {m_cx, m_cy}; }
    const Projector& projector() const { return m_projector; }

private:
    Projector m_projector;
    double m_scale, m_cx, m_cy;
};

// The shorter great-circle arc between two surface points.
class GreatCircle {
public:
    // Throws raypc::Error when the points coincide or are antipodal (no unique arc), naming
    // `what` (e.g. "section").
    GreatCircle(state::SectionState::Point from, state::SectionState::Point to, const std::string& what = "section");
    double lengthDeg() const { return m_angleRad * 180 / M_PI; }
    double lengthKm() const;  // along the surface
    // The direction the arc leaves `from` in, degrees clockwise from north in [0, 360) (at a pole:
    // the limit of a start approaching it along the meridian of its longitude).
    double azimuthDeg() const;
    // The surface point `distanceDeg` along the great circle leaving `from` at `azimuthDeg` (lon in
    // [-180, 180]): a section given by its start, azimuth and length.
    static state::SectionState::Point pointAlong(state::SectionState::Point from, double azimuthDeg, double distanceDeg);
    // The unit vector (contest frame) at `fraction` of the arc (0: from, 1: to).
    Vec3d at(double fraction) const;
    // Where a point (any radius) lies: the fraction of the arc its direction projects to (outside
    // [0, 1] before `from` or beyond `to`) and its angle off the great circle's plane (radians).
    std::array<double, 2> locate(const Vec3d& p) const;
    // The unit tangent there, pointing along the arc towards `to`.
    Vec3d tangentAt(double fraction) const;

private:
    Vec3d m_from, m_ortho;  // m_ortho: unit vector orthogonal to m_from in the arc's plane
    double m_angleRad;
};

// The frame mapPicture draws a state's map in: the picture less a title band above and the
// legend's band below (the UI's pointer and tests find a pixel's point with it).
MapFrame mapFrameOf(const state::RenderState& state);

// Where sectionPicture draws a state's section: the plot's rectangle in pixels, depth 0 at `top`
// down to `depthSpanKm` (the grid's innermost radius) at `bottom`, the arc from `left` to `right`.
struct SectionLayout {
    double left, right, top, bottom, depthSpanKm;
};
// Throws raypc::Error when the picture is too small for the section.
SectionLayout sectionLayoutOf(const state::RenderState& state, const grid::SphericalGrid& grid);

// "30.0°S 160.0°W": a point as titles write it.
std::string latLonText(double latDeg, double lonDeg);

// What a slice is drawn from: the volume of the state's step and level, the resolved state, and
// the words of the title.
struct SliceInputs {
    const dataset::StepVolume* volume = nullptr;
    const ResolvedState* resolved = nullptr;  // render/state_renderer.h; params give colour and brushes
    std::vector<std::string> variableNames;   // the volume's, in order (brushes, the flow's vx, vy, vz)
    std::string colorTitle;                   // "temperature anomaly [K]"
    std::string when;                         // "step 3, 12.0 Myr"
    const Coastlines* coastlines = nullptr;   // needed when state.reference.coastlines is visible
    const PathlineLines* pathlines = nullptr;  // the state's window; needed when state.pathlines.visible
};

// Pathlines (state.pathlines, the lines the 3D view shows, coloured as its tubes): on a map each
// line's track, fainter the farther it is from the map's depth (full within kMapPathlineBandKm);
// on a section the parts within kSectionPathlineBandKm of its plane, fainter the farther.
inline constexpr double kMapPathlineBandKm = 100, kSectionPathlineBandKm = 300;

// The map picture of inputs.resolved->state.map at the state's size. Throws raypc::Error for a
// flow without vx, vy, vz, or when the coastlines or the legend font cannot be read.
ImageRgba8 mapPicture(const SliceInputs& inputs);
// The section picture of inputs.resolved->state.section at the state's size. Throws raypc::Error
// as mapPicture does, and for a section whose ends coincide or are antipodal.
ImageRgba8 sectionPicture(const SliceInputs& inputs);

// A regular grid of samples of one variable (row-major: rows along the first axis).
struct SliceGrid {
    std::vector<double> rows, columns;  // lat ascending (deg), or distance along the profile (km)
    std::vector<double> depthsKm;       // sections: the depth of every row; maps: empty
    std::vector<float> values;          // rows.size() x columns.size(); NaN where nothing was sampled
};
// The variable at `depthKm` on a lat-lon grid of cell centres: `stepDeg` apart, lat from
// -90 + step/2 to 90 - step/2, lon from step/2 east. Throws raypc::Error for a depth outside the
// grid's shell (naming `what`) or a step that does not divide 180.
SliceGrid latLonSlice(const dataset::StepVolume& volume, size_t variable, double depthKm, double stepDeg,
                      const std::string& what = "--depth");
// The variable on the section: `columns` distances (km along the surface, 0 at `from`) by `rows`
// depths from the surface to the grid's innermost radius, both with their end points.
struct SectionGrid {
    SliceGrid grid;  // rows: depth (km) in grid.rows, columns: distance (km)
    std::vector<double> distanceDeg, latDeg, lonDeg;  // per column
};
SectionGrid sectionGrid(const dataset::StepVolume& volume, size_t variable, const state::SectionState& section, int columns, int rows);

}  // namespace raypc::render
