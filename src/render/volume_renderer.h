// The spherical volume ray caster: renders one StepVolume directly on its (lat, r, lon) grid.
//
// Typical use (CLI, server):
//   VolumeRenderer renderer(volume);              // reload class: new step or level
//   renderer.setParams(params);                   // restart class: camera, TF, brushes, size
//   FrameBuffer frame(params.width, params.height);
//   while (!converged) renderer.renderPass(frame, &cancelFlag);   // progressive, cancellable
//   frame.resolveRgba8(...) / frame.averagedDepthKm()
//
// The level of detail for a time budget: level_choice.h. From a whole state: state_renderer.h.
//
// Units: km for positions and depths, degrees for angles. Depth of a pixel = distance along the
// (unit) view ray from the eye to the first sample where the accumulated opacity reaches
// RenderParams::depthOpacity, or to the core if it is hit first; +infinity where neither happens.
//
// Thread safety: renderPass uses all cores (oneTBB) and must not be called concurrently on the same
// renderer or frame buffer; setParams must not race with renderPass. Distinct renderers are independent.
#pragma once

#include "dataset/dataset.h"
#include "analysis/selection.h"
#include "render/camera.h"
#include "render/color_map.h"
#include "state/view_types.h"
#include "render/frame_buffer.h"
#include "render/transfer_function.h"

#include <array>
#include <atomic>
#include <cstdint>
#include <memory>
#include <nlohmann/json.hpp>
#include <optional>
#include <vector>

namespace raypc::render {

namespace kernel {
struct KernelParams;
struct KernelVariable;
}  // namespace kernel

class PathlineScene;  // render/pathline_scene.h

struct CoreStyle {
    bool visible = true;
    int variable = -1;  // -1: plain colour; otherwise coloured by this variable at the core radius
    Rgb color{0.55f, 0.55f, 0.58f};
    ColorMapId colorMap = ColorMapId::Inferno;
    dataset::ValueRange range{0, 1};
};

using state::ShadingStyle;  // state/view_types.h

enum class KernelKind { Simd, Scalar };

struct RenderParams {
    OrbitCamera camera;
    int width = 512, height = 512;
    int colorVariable = 0;
    TransferFunction transfer;
    std::vector<analysis::RangeFilter> brushes;  // a sample outside any brush contributes nothing (analysis/selection.h)
    CoreStyle core;
    ShadingStyle shading;
    float stepFactor = 0.5f;    // step = stepFactor x local cell extent along the ray
    float depthOpacity = 0.5f;  // accumulated opacity that defines the depth
    float stopOpacity = 0.995f; // early ray termination
    bool skipBricks = true;     // empty-space skipping (never changes the image; off for testing)
    // "Show the selection": while brushes are set, a selected sample's opacity over
    // transfer.opacityUnitKm is at least this, whatever transfer.opacity says; 0: off. In [0, 1].
    float selectionMinOpacity = 0.0f;
    KernelKind kernel = KernelKind::Simd;
    uint32_t seed = 0x9e3779b9u;
};

struct PassStats {
    double seconds = 0;
    uint64_t samples = 0;          // samples whose data were read
    uint64_t samplesSkipped = 0;   // samples in skipped bricks
    uint64_t chunks = 0, chunksSkipped = 0, rays = 0;
    uint64_t chunksJumped = 0;     // skipped chunks passed over by interval skipping (no sample located)
    size_t bricksTotal = 0, bricksSkipped = 0;  // bricks excluded by brushes or transparency
    int threads = 1;
    int simdLanes = 1;
    bool cancelled = false;
    // No block had stopped refining (adaptive refinement): the pass rendered every pixel, so its
    // time measures the machine's throughput (the interactive level choice uses only such passes).
    bool everyBlock = true;
    // Sample positions (including those in skipped space) per second per thread.
    double samplesPerSecondPerThread() const { return seconds > 0 ? double(samples + samplesSkipped) / seconds / threads : 0; }
    // Samples that read data per second per thread: the sampling rate proper.
    double dataSamplesPerSecondPerThread() const { return seconds > 0 ? double(samples) / seconds / threads : 0; }
    // The counters that add up over passes, eyes and ranks, in this order (the messages between
    // ranks carry them so): samples, samplesSkipped, chunks, chunksSkipped, chunksJumped, rays.
    using Counts = std::array<uint64_t, 6>;
    Counts counts() const { return {samples, samplesSkipped, chunks, chunksSkipped, chunksJumped, rays}; }
    void addCounts(const Counts& c)
    {
        samples += c[0];
        samplesSkipped += c[1];
        chunks += c[2];
        chunksSkipped += c[3];
        chunksJumped += c[4];
        rays += c[5];
    }
    // Adds a later pass (or the other eye's): times and counts sum, the machine and brick figures
    // are the later one's.
    PassStats& operator+=(const PassStats& s)
    {
        seconds += s.seconds;
        addCounts(s.counts());
        bricksTotal = s.bricksTotal;
        bricksSkipped = s.bricksSkipped;
        threads = s.threads;
        simdLanes = s.simdLanes;
        cancelled = cancelled || s.cancelled;
        everyBlock = everyBlock && s.everyBlock;
        return *this;
    }
};

// The JSON forms of PassStats, one for each of its readers. Their keys differ because the readers
// do: a frame header on the WebSocket (docs/protocol.md, "PassStats") counts every sample position
// and times in ms; `raypc render --stats` keeps the samples read and skipped apart, with rates per
// thread, and adds the machine and brick figures to a frame's total.
enum class PassStatsJson {
    pass,         // a pass of `raypc render --stats`: seconds, samples, samplesSkipped, the two rates
    frame,        // a frame's total there: a pass's keys and threads, simdLanes, bricks and chunks
    frameHeader,  // the "stats" of a frame header: passMs, samples, samplesPerSecond, bricks
};
nlohmann::json toJson(const PassStats& stats, PassStatsJson form);

class VolumeRenderer {
public:
    // Prepares per-volume tables (coordinate maps, pole ring means). Throws raypc::Error if the grid
    // has fewer than 2 points along an axis or the brick size is not a power of two.
    explicit VolumeRenderer(std::shared_ptr<const dataset::StepVolume> volume);
    ~VolumeRenderer();

    // Validates and bakes: transfer table, brick flags. Throws raypc::Error on bad parameters
    // (variable index out of range, brush min > max, bad size, bad transfer function, bad camera).
    void setParams(const RenderParams& params);
    const RenderParams& params() const { return m_params; }
    const std::shared_ptr<const dataset::StepVolume>& volume() const { return m_volume; }

    // Renders one jittered pass (pass number = frame.passes()) and accumulates it into `frame`
    // unless `cancel` becomes true, which is checked before every tile; a cancelled pass leaves
    // the frame as it was. The frame must have the params' size.
    // With a TileShare other than {0, 1} only the tiles it owns are rendered and accumulated (the
    // rest of `frame` is left as it was); the pass number still advances. With the frame's
    // Refinement on, only its blocks that still refine are rendered (a pass's pixels are those of
    // the full pass; the estimate after it may stop more blocks); once every block has stopped a
    // pass renders nothing.
    // With shading.shadows the pass first brings the occlusion grids up to date with what changed
    // since the last pass (shadow_volume.h: after a transfer function, brush or tube change all of
    // them, after a camera or light move the light's), which its seconds include.
    PassStats renderPass(FrameBuffer& frame, const std::atomic<bool>* cancel = nullptr, TileShare share = {});

    // Cost of a pass at these params on this volume in sample equivalents, estimated from a sparse
    // set of rays with the kernels' own step and skipping rules: samples in active bricks count 1,
    // skipped space and per-ray work count what they cost relative to a sample (early ray
    // termination is not foreseen). Proportional to the pass time, so (estimate / measured seconds)
    // is a throughput that transfers between levels, views and image sizes. Cached per setParams.
    double estimateSamplesPerPass() const;

    // The baked kernel view (for tests and benchmarks of the kernels themselves).
    const kernel::KernelParams& kernelParams() const;

    // Tubes along pathlines, ray traced in the same frame (nullptr: none). Restart class: the
    // caller clears the frame. The renderer reads the scene's BVH, mask and style during
    // renderPass, so the scene must not be changed while a pass runs. Per ray the closest visible
    // tube is found first, the volume is marched up to it and the shaded tube is composited behind
    // the accumulated volume; the depth includes the tube.
    void setPathlines(std::shared_ptr<const PathlineScene> scene);
    const std::shared_ptr<const PathlineScene>& pathlines() const;

private:
    // The stages of setParams (restart class).
    void validateParams(const RenderParams& params) const;
    void bakeTables(const RenderParams& params);
    void flagActiveBricks(const RenderParams& params);
    void fillKernelParams(const RenderParams& params);
    void buildSkipGrid();
    kernel::KernelVariable kernelVariable(int variable) const;
    const std::vector<float>& capMeans(int variable) const;
    // With shading.shadows: brings the shadow volume up to date (what changed since the last pass)
    // and binds it into `k`, the pass's kernel view.
    void bindShadows(kernel::KernelParams& k);
    // A pass's statistics that do not depend on what it rendered: bricks, threads, SIMD lanes.
    PassStats passStats(bool simd) const;
    // Points the kernel's gradient (KernelParams::gradLat, gradR, gradLon) at the volume's
    // nodeGradient of `variable` (computed on the volume's first use of it).
    void bindGradient(int variable);

    struct Impl;
    std::shared_ptr<const dataset::StepVolume> m_volume;
    RenderParams m_params;
    std::unique_ptr<Impl> m_impl;
};

// Per-brick bounds of a coordinate over a grid's bricks (min, max pairs), conservative: every
// trilinear sample inside the brick has its coordinate inside. Used for coordinate brushes.
std::vector<float> coordinateBrickBounds(const grid::SphericalGrid& grid, const grid::BrickLayout& bricks, grid::Coordinate coordinate);

}  // namespace raypc::render

#include "render/level_choice.h"  // IWYU pragma: export (callers of the renderer choose levels)
