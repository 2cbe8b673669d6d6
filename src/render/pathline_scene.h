// Tubes along pathlines, ray traced with Embree in the same frame as the volume.
//
// A PathlineScene holds the lines of one step window (loadPathlineWindow) as round linear curves
// (cones between points, spheres at the joints) of one radius in one Embree BVH, built once.
// Which lines count is a per-line mask read by an Embree intersection/occlusion filter, so brushing
// and attribute filters change the picture without rebuilding the BVH; the radius changes by
// rewriting the vertex radii and recommitting (a rebuild of this BVH only, no reload).
//
// Typical use (server, CLI):
//   auto scene = std::make_shared<PathlineScene>(loadPathlineWindow(dir, step, state.pathlines.window));
//   size_t shown = scene->applyState(state);   // restart class: radius, colour, mask
//   renderer.setPathlines(scene);              // the renderer only reads it
//
// Colouring: "age" = point time - the line's injection time (Myr), or one line attribute column
// (constant along a line), through a colour map over a range (PathlineStyle).
// Units: km, Myr, degrees (as in analysis/pathlines.h).
//
// Thread safety: const member functions may be called from any thread (the renderer traces from
// all cores). applyState, setVisibility, setStyle and setRadiusKm must not run while a renderPass
// uses this scene (the same rule as VolumeRenderer::setParams). Embree types stay in the .cpp.
#pragma once

#include "analysis/pathline_storage.h"
#include "render/legend.h"
#include "state/render_state.h"

#include <cstdint>
#include <memory>
#include <span>
#include <string>
#include <vector>

namespace raypc::render {

namespace kernel {
struct KernelParams;
}

// How visible lines look (resolved from PathlineState by applyState, or set directly by tests).
struct PathlineStyle {
    int colorColumn = -1;  // -1: colour by age; otherwise an index into columns()
    ColorMapId colorMap = ColorMapId::BlueWhiteRed;
    dataset::ValueRange range{0, 20};  // value (age in Myr or the column's units) mapped to the map's ends
    bool ambientOcclusion = true;
    int aoRays = 4;            // occlusion rays per tube pixel and pass (the mean over passes converges)
    float aoDistanceFactor = 12;  // occlusion rays reach this many tube radii
};

// The lines of a step window without geometry: numbered over the sets (set 0's lines first),
// checked, with their attributes, which of them a state shows and how it colours them. The tubes
// (PathlineScene) and the maps and sections (slice_view.h) draw from it.
//
// Thread safety: immutable after construction.
class PathlineLines {
public:
    // Throws raypc::Error when the sets' columns differ or a set is malformed (offsets, attributes).
    explicit PathlineLines(std::shared_ptr<const std::vector<analysis::PathlineSet>> sets);

    const std::vector<analysis::PathlineSet>& sets() const { return *m_sets; }
    size_t lineCount() const { return m_lineSet.size(); }
    const std::vector<std::string>& columns() const { return m_columns; }
    float attribute(size_t line, size_t column) const { return set(line).attribute(m_lineLocal[line], column); }
    int injectionStep(size_t line) const { return set(line).injectionStep; }
    double injectionTimeMyr(size_t line) const { return set(line).injectionTimeMyr; }
    // The line's points, 4 floats each: x, y, z (km), time (Myr).
    std::span<const float> points(size_t line) const;
    // Time between steps (Myr) from the sets' injection times, or from the lines' durations for a
    // single set; 0 if unknown.
    double stepMyr() const { return m_stepMyr; }
    float maxAgeMyr() const { return m_maxAgeMyr; }

    // See PathlineScene::visibilityFor and styleFor.
    std::vector<uint8_t> visibilityFor(const state::RenderState& state) const;
    PathlineStyle styleFor(const state::PathlineState& state) const;
    // The value `style` colours point `point` (0 = the line's first) of `line` by: its age (Myr)
    // or the line's attribute.
    float colorValue(const PathlineStyle& style, size_t line, size_t point) const;

private:
    const analysis::PathlineSet& set(size_t line) const { return (*m_sets)[m_lineSet[line]]; }

    std::shared_ptr<const std::vector<analysis::PathlineSet>> m_sets;
    std::vector<std::string> m_columns;
    std::vector<uint32_t> m_lineSet, m_lineLocal;  // per global line: its set and index in the set
    double m_stepMyr = 0;
    float m_maxAgeMyr = 0;
};

// The legend of pathlines drawn in `style`: its colour map over its range (linear, as the tubes
// map it), titled by what it colours ("pathline age [Myr]" or the attribute).
LegendSpec pathlineLegend(const PathlineStyle& style, const std::vector<std::string>& columns);

class PathlineScene {
public:
    // Builds the BVH of every line of `sets` (any order; typically a window, oldest first) with
    // tubes of `radiusKm`. Lines with fewer than 2 points draw nothing. Throws raypc::Error when
    // the radius is not positive, the sets' columns differ, or a set is malformed (offsets).
    explicit PathlineScene(std::vector<analysis::PathlineSet> sets, float radiusKm = 12.0f);
    PathlineScene(std::shared_ptr<const std::vector<analysis::PathlineSet>> sets, float radiusKm);
    ~PathlineScene();
    PathlineScene(const PathlineScene&) = delete;
    PathlineScene& operator=(const PathlineScene&) = delete;

    const std::vector<analysis::PathlineSet>& sets() const;
    const PathlineLines& lines() const;
    // Lines over all sets, numbered set by set (set 0's lines first). Masks are in this order.
    size_t lineCount() const;
    // Attribute columns shared by all sets (empty without lines).
    const std::vector<std::string>& columns() const;
    // Value of `column` for global line `line`.
    float attribute(size_t line, size_t column) const;
    int injectionStep(size_t line) const;
    // Time between steps (Myr) from the sets' injection times, or from the lines' durations for a
    // single set; 0 if unknown. The default age range is [0, window x stepMyr].
    double stepMyr() const;

    // --- Restart class (no BVH rebuild) ------------------------------------------------------

    // Which lines the state shows (see docs/state.md, "pathlines"): lines injected in
    // [step - window + 1, step] whose start lies inside every brush range (coordinates from the
    // "start lat/lon/radius" columns, variables from "start <variable>") when filterByBrushes, and
    // inside every attribute filter. All zero when pathlines are not visible. Throws raypc::Error
    // naming a filter or brush whose column the lines do not have (listing the columns).
    std::vector<uint8_t> visibilityFor(const state::RenderState& state) const;
    // The style the state asks for: colorBy resolved to a column (or age), the colour map and the
    // range (default: age [0, window x stepMyr]; a column's range over all loaded lines, symmetric
    // for maps centred on zero). Throws raypc::Error for an unknown colorBy (listing the columns).
    PathlineStyle styleFor(const state::PathlineState& state) const;

    // Radius, style and visibility from the state; returns the number of visible lines.
    size_t applyState(const state::RenderState& state);
    // One byte per line (non-zero = visible); returns the number of visible lines. Throws
    // raypc::Error if the mask has the wrong size.
    size_t setVisibility(std::vector<uint8_t> mask);
    const std::vector<uint8_t>& visibility() const;
    size_t visibleCount() const;
    void setStyle(const PathlineStyle& style);
    const PathlineStyle& style() const;
    // Rewrites the tube radii and refits the BVH. Throws raypc::Error unless radiusKm > 0.
    void setRadiusKm(float radiusKm);
    float radiusKm() const;

    // For VolumeRenderer: binds this scene's tracer into the kernel parameters (left unbound when
    // no line is visible, so such a frame costs nothing and equals one without tubes).
    void bind(kernel::KernelParams& k) const;

    struct Impl;

private:
    std::unique_ptr<Impl> m_impl;
};

}  // namespace raypc::render
