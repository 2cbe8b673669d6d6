// The one path from a render state to pixels, shared by `raypc render`, `raypc demo`, the server's
// screenshots and its interactive sessions:
//
//   RenderState --resolveState--> ResolvedState (checked against the dataset, names -> indices)
//               --StateRenderer::prepare--> level, the views (one, or a stereo pair's two eyes) with
//                                           their renderers of (step, level), pathline scene, size
//               --renderPass x N--> ViewFrames (one FrameBuffer a view)
//               --picture (reference geometry, legends per view; stereo composition) / depthKm--> image, depth
//
// Cost classes (house style): a new step or level loads a volume and builds a renderer (reload);
// a new pathline window builds a tube scene (reload); everything else restarts passes.
//
// Thread safety: one StateRenderer per thread of work (a session, a CLI run, a screenshot); the
// sources it is given must be thread-safe when shared.
#pragma once

#include "core/huge_pages.h"
#include "core/system_memory.h"
#include "dataset/dataset.h"
#include "analysis/features.h"
#include "analysis/pathline_storage.h"
#include "render/pathline_scene.h"
#include "render/reference_geometry.h"
#include "render/image_io.h"
#include "render/resolve_state.h"
#include "render/stereo.h"
#include "render/volume_renderer.h"

#include <nlohmann/json.hpp>

#include <atomic>
#include <functional>
#include <map>
#include <memory>
#include <mutex>
#include <optional>
#include <span>
#include <utility>
#include <vector>

namespace raypc::render {

// The tube radius that draws the pathlines at least pathlines.minWidthPx pixels wide at the camera
// target's distance (the state's radiusKm when that is wider), km.
float tubeRadiusKm(const state::RenderState& state);

// The accumulation buffers of a picture: one per view (stereoViews), in the same order.
using ViewFrames = std::vector<FrameBuffer>;
// The mean depth of every view (FrameBuffer::averagedDepthKm), the eyes side by side (left |
// right) for a stereo pair whatever its mode; the size in `width` x `height`.
// `eachView`, when given, transforms each view's map before they are put side by side (e.g. the
// server's downsampling; it sets the map's new size in its width and height arguments), so that no
// block of a transform straddles the eyes.
using DepthTransform = std::function<std::vector<float>(std::vector<float> depthKm, int& width, int& height)>;
std::vector<float> averagedDepthKm(const ViewFrames& frames, int& width, int& height,
                                   const DepthTransform& eachView = {});

// The memory a picture of `state` takes at its peak (bytes), an upper bound: the accumulation
// buffers of every view (FrameBuffer::bytesPerPixel), each view's picture in float and 8-bit RGBA,
// a stereo pair's composed image, and with `withDepth` the depth map with its file's bytes. The
// volumes are mapped from the dataset and not counted. Measured against peak RSS in
// docs/reliability.md.
uint64_t pictureMemoryBytes(const state::RenderState& state, bool withDepth);
// Throws raypc::Error when pictureMemoryBytes exceeds `available`, with both figures, e.g.
// "a picture of 16384x16384 pixels needs 18.8 GB of memory to render, 3.9 GB available (ulimit -v);
// choose a smaller --size".
void checkPictureFitsMemory(const state::RenderState& state, bool withDepth, const AvailableMemory& available);

// Where a StateRenderer gets volumes, pathlines and the painted features' labels. Unset members read
// the dataset directly (Dataset::load, loadPathlineWindow, extractFeatures); the server passes its
// shared caches (the labels those of its features answers: server/analysis_caches.h).
struct StateSources {
    std::function<std::shared_ptr<const dataset::StepVolume>(int step, int level)> volume;
    std::function<std::shared_ptr<const std::vector<analysis::PathlineSet>>(int step, int window)> pathlines;
    // analysis::extractFeatures(volume(step, level), filters, options).labels, may be shared.
    std::function<std::shared_ptr<const HugePageVector<int32_t>>(int step, int level, std::span<const analysis::RangeFilter> filters,
                                                                 const analysis::FeatureOptions& options)>
        featureLabels;
};

// How the level is chosen when the state leaves it open (RenderState::level unset).
struct LevelPolicy {
    // > 0: the finest level whose predicted pass (VolumeRenderer::estimateSamplesPerPass /
    // samplesPerSecond) fits kInteractiveBudgetShare of the state's timeBudgetMs (interactive
    // frames, `raypc render --lod auto`). 0: level 0 (still frames and scripted figures, so that a
    // figure does not depend on the machine's speed).
    double samplesPerSecond = 0;
    // The measured time of an interactive frame outside its pass (preparing it, its picture and
    // JPEG), which the budget must also hold: passBudgetSeconds (level_choice.h).
    double overheadSeconds = 0;
    // When even the coarsest level misses the budget, render 1/2 or 1/4 of the pixels per axis (the
    // interactive UI scales the frame up).
    bool reduceResolution = false;
    // Set: the level and the size divisor another process's prepare() chose (Prepared::level and
    // ::divisor), used as they are: a worker rank of the distributed server repeats rank 0's choice.
    std::optional<LevelChoice> chosen;
};

// The policy of interactive frames and playback steps (docs/protocol.md, the state message): the
// finest level within the budget at `measuredSamplesPerSecond` (averagedMeasure of the passes
// rendered so far) and 1/2 or 1/4 of the pixels when even the coarsest misses it; before any pass
// was measured (0), an assumed 100 M samples/s per thread and the full size, so that the first pass
// measures the machine. `overheadSeconds`: LevelPolicy::overheadSeconds.
LevelPolicy interactiveLevelPolicy(double measuredSamplesPerSecond, double overheadSeconds = 0);

// Image-parallel frames under mpirun (core/mpi.h, docs/scaling.md): rank r of N renders the tiles
// t with t % N == r of every pass (the jitter of a sample depends only on its pixel and the pass
// number, so a tile is the same whoever renders it); {0, 1} without MPI.
TileShare rankTileShare();
// Collective: rank 0's `frame` receives the accumulated sums of every rank's tiles of a frame
// rendered with rankTileShare(); it then equals the frame one process renders, bit for bit. Other
// ranks' frames are unchanged. Does nothing without MPI.
void gatherTilesToRoot(FrameBuffer& frame);

class StateRenderer {
public:
    explicit StateRenderer(std::shared_ptr<const dataset::Dataset> dataset, StateSources sources = {});
    ~StateRenderer();
    StateRenderer(const StateRenderer&) = delete;
    StateRenderer& operator=(const StateRenderer&) = delete;

    // What prepare() set up for one state; the renderers stay valid until the next prepare().
    struct View {
        RenderParams params;  // the view's, with the size reduced if LevelPolicy asked for it
        VolumeRenderer* renderer = nullptr;
    };
    struct Prepared {
        int level = 0;
        int divisor = 1;          // the views' size is the state's divided by this (LevelPolicy::reduceResolution)
        std::vector<View> views;  // stereoViews' order: one, or the left and the right eye
        std::shared_ptr<const PathlineScene> scene;  // nullptr when pathlines are hidden
        double estimatedSamplesPerPass = 0;          // of all views
        Refinement refinement;  // of still frames: the state's convergenceGreyLevels

        // Empty buffers of the views' sizes, refining adaptively as `refinement` says (a block
        // that has converged takes no more passes; FrameBuffer::converged when all have).
        ViewFrames frames() const;
        // One progressive pass of every view into `frames` (see VolumeRenderer::renderPass; a
        // cancelled view stops the pass). Stats are summed over the views.
        PassStats renderPass(ViewFrames& frames, const std::atomic<bool>* cancel = nullptr, TileShare share = {}) const;
    };
    // Chooses the level, maps the volume, sets the parameters of every view and the pathline scene.
    // The time budget is shared by the views. Throws raypc::Error when data cannot be read (e.g. a
    // dataset without pathlines asked to show them).
    Prepared prepare(const ResolvedState& resolved, const LevelPolicy& policy = {});
    // The level and divisor prepare() will choose when they do not depend on estimated pass times
    // (a given choice, the state's level, or level 0 without a throughput); nullopt when they do.
    static std::optional<LevelChoice> knownChoice(const state::RenderState& state, const LevelPolicy& policy);

    // The renderer of (step, level) for view `view` (each eye of a stereo pair keeps its own, so
    // that alternating eyes do not redo setParams), created on first use; a new step drops the
    // old step's.
    VolumeRenderer& rendererFor(int step, int level, int view = 0);

    // A converged picture: prepare() with LevelPolicy{} (level 0 unless the state names one), then
    // `passes` passes (the state's when 0); with adaptive refinement (the state's
    // convergenceGreyLevels) the blocks that have converged take no more of them, and passes after
    // every block has cost nothing. Stops early when `cancel` becomes true (the frame then holds
    // fewer passes; check frame.passes()).
    struct Still {
        ViewFrames frames;
        int level = 0;
        size_t pathlinesShown = 0;
        std::vector<PassStats> passes;
    };
    // With a TileShare, only its tiles are rendered (gatherTilesToRoot assembles the frame).
    // `onPass(done, total)` is called after each pass (progress; Python's render).
    Still renderStill(const ResolvedState& resolved, int passes = 0, const std::atomic<bool>* cancel = nullptr,
                      TileShare share = {}, const std::function<void(int done, int total)>& onPass = {});

    // The finished picture of `frames`, rendered for `resolved` (after prepare or renderStill with
    // that state): per view, the state's reference geometry (shells, graticule, coastlines)
    // composited by depth with the volume, over the state's background, and with `withLegends` and
    // state.legend the colour legends (the volume's variable; the pathlines' colouring when they
    // are shown); a stereo pair's two views then composed as stereo.mode says (composeStereo).
    // 8-bit RGBA, row-major from the top left. Throws raypc::Error when the coastlines or the
    // legend font cannot be read. Without `withShellLabels` the shells' depths are not written on
    // their rings: the UI writes them over the frame (shellLabels, for the frame header).
    ImageRgba8 picture(const ViewFrames& frames, const ResolvedState& resolved, bool withLegends,
                       bool withShellLabels = true) const;

    // A map or a section of `resolved` (state.map, state.section; render/slice_view.h) at the state's
    // size, from the volume of its step at its level (0 unless the state names one), with its title
    // and legend. Throws raypc::Error as mapPicture and sectionPicture do.
    enum class Slice { Map, Section };
    ImageRgba8 slicePicture(const ResolvedState& resolved, Slice slice) const;

    // The machine's throughput now, in estimated samples per second (all threads): two passes at
    // the coarsest level of `step` (the first also starts the worker threads). For `--lod auto`.
    double measureSamplesPerSecond(int step, const RenderParams& params);

private:
    std::shared_ptr<const PathlineScene> pathlinesFor(const state::RenderState& state);
    // One view's picture (`resolved` is the view's).
    std::vector<uint8_t> viewPicture(const FrameBuffer& frame, const ResolvedState& resolved, bool withLegends,
                                     bool withShellLabels) const;
    // The reference geometry of `state`'s view at this size, made once for the passes and steps that
    // share it (the last two kept: the eyes of a stereo pair).
    std::shared_ptr<const ReferenceLayer> referenceLayer(const state::RenderState& state, int width, int height) const;

    // The features painted (feature_paint.h): sets the key of what the renderers' volumes hold; a new
    // key drops the renderers. Returns whether the state paints features.
    bool usePaint(const ResolvedState& resolved);
    // The volume a renderer of (step, level) draws: the source's, with the painted features' slots
    // as a last variable while the state paints them.
    std::shared_ptr<const dataset::StepVolume> volumeFor(int step, int level);

    std::shared_ptr<const dataset::Dataset> m_dataset;
    StateSources m_sources;
    std::string m_paintKey;  // empty: nothing painted
    std::vector<analysis::RangeFilter> m_paintFilters;
    state::FeatureSettings m_paintSettings;
    // Of m_paintKey, found on first use: the step's feature labels (on the grid of features.level),
    // and the painted volume of each level (the views of a stereo pair share one).
    std::shared_ptr<const HugePageVector<int32_t>> m_paintLabels;
    std::map<int, std::shared_ptr<const dataset::StepVolume>> m_paintedVolumes;
    int m_rendererStep = -1;
    std::map<std::pair<int, int>, std::unique_ptr<VolumeRenderer>> m_renderers;  // by (level, view), of m_rendererStep
    std::shared_ptr<PathlineScene> m_scene;
    int m_sceneStep = -1, m_sceneWindow = -1;
    mutable std::mutex m_referenceMutex;
    mutable std::vector<std::pair<std::string, std::shared_ptr<const ReferenceLayer>>> m_referenceLayers;  // newest last
};

}  // namespace raypc::render
