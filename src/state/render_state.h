// The render state document (STATE.json): what the browser UI saves and loads and what
// `raypc render --state` reads. Schema: docs/state.md. Names of variables and coordinates are
// strings here; render/resolve_state.h checks them against a dataset and turns them into the
// renderer's parameters.
//
// Parsing is strict: unknown keys and bad values throw raypc::Error naming the key
// (e.g. "STATE.json: camera.distanceKm: expected a number in [0.001, 1000000000], found -3").
// Every key is described once, in state_schema.cpp: parseRenderState, toJson, the JSON Schema
// and the docs table are derived from that description; a new key is an entry there and a member here.
#pragma once

#include "analysis/features.h"
#include "analysis/selection.h"
#include "dataset/dataset.h"
#include "state/color_maps.h"
#include "state/view_types.h"

#include <nlohmann/json.hpp>

#include <filesystem>
#include <initializer_list>
#include <optional>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

namespace raypc::state {

// Version 2 added "pathlines", version 3 "reference" (shells, graticule, coastlines) and "legend",
// version 4 several ranges on one axis (a repeated brush name ORs its ranges) and "axes", version
// 5 "stereo", version 6 "shading.shadows" and "shading.shadowStrength", version 7 "camera.views"
// (explicit camera poses, e.g. WebXR eyes), version 8 "selection" (show the selection whatever the
// transfer function's opacity), version 9 "map" and "section" (depth slices and great-circle
// sections, render/slice_view.h), version 10 "features" (how features are found), version 11
// "features.colorById" and "features.highlight", version 12 "features.stallBy", version 13 "pair" (two
// datasets side by side); older documents are still read (they have none of these).
inline constexpr int kRenderStateVersion = 13;

// A brush range: a variable or a coordinate (x, y, z, lat, lon, radius, depth) and [min, max]. The
// brush model is analysis/selection.h's: a name that repeats adds a range to its axis (OR).
using BrushSpec = analysis::NamedRange;

// A range over one pathline attribute column (the pathline parallel-coordinates plot), e.g.
// "length", "start temperature anomaly"; as brushes, a repeated column ORs its ranges.
using PathlineFilter = analysis::NamedRange;

// The "pathlines" object: tubes along the pathlines injected in the last `window` steps
// (docs/state.md). Cost classes: window (and the state's step) reload the line window and
// rebuild the tube scene; everything else restarts passes (PathlineScene::applyState).
struct PathlineState {
    bool visible = false;
    float radiusKm = 12.0f;  // tube radius, > 0
    // Version 3: tubes at least this many pixels wide at the camera target's distance (the radius
    // grows when zoomed out); 0: the radius alone. The UI's default state asks for 2.
    float minWidthPx = 0.0f;
    int window = 10;         // steps: lines injected in [step - window + 1, step]
    std::string colorBy = "age";  // "age" or a line attribute column
    std::optional<ColorMapId> colorMap;  // nullopt: blue-white-red for age, viridis for attributes
    std::optional<dataset::ValueRange> range;     // nullopt: [0, window x step length] for age, else the column's range
    bool filterByBrushes = true;  // a line's start must satisfy the volume brushes
    std::vector<PathlineFilter> filters;
    bool ambientOcclusion = true;

    // The colour map in effect (the default depends on colorBy).
    ColorMapId effectiveColorMap() const
    {
        return colorMap ? *colorMap : (colorBy == "age" ? ColorMapId::BlueWhiteRed : ColorMapId::Viridis);
    }
};

// Reference geometry drawn with the volume (reference_geometry.h): thin translucent spheres at
// given depths, a latitude/longitude graticule and the coastlines on the surface. Restart class.
struct ReferenceState {
    struct Shells {
        bool visible = false;
        std::vector<float> depthsKm{410.0f, 660.0f, 1000.0f, 1600.0f, 2200.0f};
        float opacity = 0.04f;  // of a shell seen face-on; towards its silhouette the path through it lengthens
        Rgb color{1.0f, 1.0f, 1.0f};  // multiplies each shell's palette colour (shellColor)
    } shells;
    struct Graticule {
        bool visible = false;
        float spacingDeg = 30.0f;  // between parallels and between meridians
        float opacity = 0.5f;
        Rgb color{0.8f, 0.8f, 0.8f};
    } graticule;
    struct Coastlines {
        bool visible = false;
        float opacity = 0.9f;
        Rgb color{0.95f, 0.95f, 0.75f};
    } coastlines;
    float lineWidthPx = 1.5f;  // graticule and coastline width in pixels of the image
};

// The "map" object (version 9): the colour variable on the sphere at one depth, projected
// (render/slice_view.h; `raypc map`, the UI's map panel). Restart class: nothing is reloaded.
struct MapState {
    float depthKm = 660.0f;
    MapProjection projection = MapProjection::Mollweide;
    float centralMeridianDeg = 0.0f;
    float centralLatitudeDeg = 0.0f;  // the orthographic projection's centre; the others' is the equator
    bool greyUnselected = true;       // with brushes: what lies outside the selection in grey
    std::vector<float> contours;      // lines at these values of the colour variable
    bool flow = false;                // arrows of the horizontal flow at the depth
    bool showInView = false;          // the 3D view marks the depth and the section (SliceMarks)
};

// The "section" object (version 9): a vertical section along the great circle from `from` to `to`
// (the shorter arc), from the surface to the core-mantle boundary.
struct SectionState {
    struct Point {
        float latDeg = 0.0f, lonDeg = 0.0f;
    };
    Point from{0.0f, -60.0f}, to{0.0f, 60.0f};
    bool flow = false;  // arrows of the flow in the section's plane (along the profile and radial)
};

// The "features" object (version 10): how the connected regions of the selection are found and
// followed (analysis/features.h; `raypc features`, Python's Dataset.features), so that a saved state
// reproduces their table.
struct FeatureSettings {
    float minVolumeKm3 = 0.0f;                               // smaller regions are dropped
    std::vector<float> depthsKm{410.0f, 660.0f, 1000.0f, 1600.0f};  // each feature's share near them; the stall depths
    float bandHalfWidthKm = 50.0f;                          // the band around each depth
    int level = 0;                                          // of detail the regions are found at
    float minOverlapShare = 0.1f;                           // of a feature carried onto another for a link
    analysis::StallMeasure stallBy = analysis::StallMeasure::MeanDepth;         // version 12: which depth of a feature stalls
    // Version 11: the 3D view paints the step's features (render/feature_paint.h).
    bool colorById = false;
    std::vector<int> highlight;  // feature ids of the state's step
};

// The data layer's options of the state's feature settings (minimum volume, depths, band).
analysis::FeatureOptions featureOptions(const FeatureSettings& settings);

// Checks feature settings given outside a state document (command-line options, Python's arguments)
// against the state's description of `features` (state_schema.cpp), so that both accept the same
// values. Throws raypc::Error naming the option that `optionNames` gives for the state's key
// (e.g. {"depthsKm", "--depth"}).
void checkFeatureSettings(const FeatureSettings& settings,
                          std::initializer_list<std::pair<std::string_view, std::string_view>> optionNames);

// The "pair" object (version 13, docs/compare.md, "Side by side"): the state is drawn for a second
// dataset too, beside the first, with the same camera, transfer function and brushes (by name; a
// brush on a variable it lacks is left out for it, render/pair_state.h). nullopt (null): one dataset.
struct PairState {
    std::string dataset;  // the second dataset's directory (relative: to the working directory)
    PairSteps steps = PairSteps::Time;  // how its step is matched to the state's `step`
};

struct RenderState {
    int version = kRenderStateVersion;
    int step = 0;  // time step index (reload class)
    OrbitCamera camera;
    int width = 512, height = 512;
    std::string colorVariable;  // empty: the first variable
    ColorMapId colorMap = ColorMapId::Viridis;
    std::optional<dataset::ValueRange> colorRange;  // default: render::defaultColorRange (symmetric and robust for centred maps)
    std::vector<OpacityPoint> opacity;  // empty: defaultOpacity(colorMap)
    float opacityUnitKm = 100.0f;
    std::vector<ColorStop> colorPoints;  // version 3: custom colours replacing colorMap when not empty
    bool colorReversed = false;          // version 3
    bool logScale = false;               // version 3: positions over log10 of the value (range > 0)
    std::vector<BrushSpec> brushes;
    // Version 4: the UI's parallel-coordinates axes in display order (nullopt: its default); the
    // renderer does not read it.
    std::optional<std::vector<std::string>> axes;
    std::optional<int> level;  // nullopt: chosen for timeBudgetMs (reload class)
    double timeBudgetMs = 50.0;
    int passes = 8;
    // Adaptive refinement of still images (render::Refinement): 8-bit levels; 0: off.
    float convergenceGreyLevels = 2.0f;
    float stepFactor = 0.5f;
    float depthOpacity = 0.5f;
    struct Core {
        bool visible = true;
        std::string variable;  // empty: plain colour
        Rgb color{0.55f, 0.55f, 0.58f};
        ColorMapId colorMap = ColorMapId::Inferno;
        std::optional<dataset::ValueRange> range;
    } core;
    ShadingStyle shading;
    Rgb background{0.0f, 0.0f, 0.0f};
    PathlineState pathlines;  // version 2
    ReferenceState reference;  // version 3
    bool legend = false;       // version 3: colour legends in still pictures (raypc render, screenshots)
    StereoState stereo;        // version 5: stereo pairs (render/stereo.h)
    // Version 8: "show the selection". While brushes are set and `show` is on, a selected sample's
    // opacity (over opacityUnitKm) is at least minOpacity, whatever `opacity` says there: a
    // selection in values the transfer function hides is still seen. Restart class.
    struct Selection {
        bool show = false;
        float minOpacity = 0.5f;
    } selection;
    MapState map;          // version 9
    SectionState section;  // version 9
    FeatureSettings features;  // version 10
    std::optional<PairState> pair;  // version 13
};

// The opacity used when the state gives none: a ramp from 0 to 0.5 over the range, or for maps
// centred on zero (blue-white-red) a V, 0.5 at both ends and transparent at zero.
std::vector<OpacityPoint> defaultOpacity(ColorMapId map);

// What is wrong with the state's camera.views for its stereo mode (one view without stereo, two
// with it), or "" when nothing is: checked when a document is read and again when a state is
// resolved (command-line flags may change the stereo mode after reading).
std::string cameraViewsMismatch(const RenderState& state);

// `what` names the source in messages (a file name or "state").
RenderState parseRenderState(const nlohmann::json& json, const std::string& what = "state");
RenderState loadRenderState(const std::filesystem::path& path);
nlohmann::json toJson(const RenderState& state);

}  // namespace raypc::state
