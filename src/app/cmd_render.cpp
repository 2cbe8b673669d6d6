// raypc render DATASET|FILE.nc… [--dataset DIR] --time T -o out.png [--size WxH] [--state STATE.json] [--var NAME]
//   [--colormap NAME] [--range NAME=MIN:MAX]... [--lod N|auto] [--passes N] [--depth depth.pfm] [--stats]
//   [--pathlines] [--pathline-radius KM] [--legend] [--reference shells|graticule|coastlines]...
//   [--stereo off|side-by-side|side-by-side-half|anaglyph] [--view 3d|map|section]
// raypc map DATASET … [--depth KM] [--projection NAME] [--central-meridian DEG] [--contours V,…] [--flow]
//   [--netcdf slice.nc [--grid-step DEG]]
// raypc section DATASET … --from LAT,LON (--to LAT,LON | --azimuth DEG --length DEG) [--contours V,…] [--flow]
//   [--netcdf section.nc [--grid-step DEG] [--depth-step KM]]
// All three draw through StateRenderer (render/state_renderer.h); maps and sections are
// render/slice_view.h's pictures of the state's "map" and "section" (docs/maps.md).
#include "app/command.h"
#include "app/options.h"
#include "app/series_inputs.h"
#include "app/slice_grid.h"
#include "core/atomic_file.h"
#include "core/error.h"
#include "core/error_kinds.h"
#include "core/mpi.h"
#include "core/numbered_name.h"
#include "core/strings.h"
#include "io/cf_grid.h"
#include "dataset/dataset.h"
#include "render/image_io.h"
#include "render/pathline_scene.h"
#include "state/render_state.h"
#include "render/slice_view.h"
#include "render/pair_state.h"
#include "render/state_renderer.h"

#include <fmt/format.h>
#include <fmt/ranges.h>
#include <nlohmann/json.hpp>

#include <algorithm>
#include <chrono>
#include <array>
#include <optional>
#include <functional>
#include <filesystem>

namespace raypc::app {
namespace {

using namespace raypc::render;

struct RenderArgs {
    SeriesFlags series;  // a dataset, or netCDF files
    std::string dataset, time, output, size, statePath, var, colormap, lod, depthPath;
    std::vector<std::string> ranges;
    int passes = 0;
    bool stats = false;
    bool pathlines = false;
    double pathlineRadiusKm = 0;  // 0: the state's
    bool legend = false;
    std::vector<std::string> reference;  // shells, graticule, coastlines
    std::string stereo;                  // a stereo mode; empty: the state's
    // Maps and sections: the picture drawn, and what the flags change in the state's map and section.
    std::string view = "3d";  // 3d | map | section
    CLI::Option *sliceDepth = nullptr, *centralMeridian = nullptr, *centralLatitude = nullptr, *contoursOption = nullptr;
    double sliceDepthKm = 0, centralMeridianDeg = 0, centralLatitudeDeg = 0;
    std::string projection, from, to, netcdf;
    CLI::Option *azimuth = nullptr, *length = nullptr;  // a section's end by azimuth and length
    double azimuthDeg = 0, lengthDeg = 0;
    std::vector<double> contours;
    bool flow = false, allColour = false;
    double gridStepDeg = 0, depthStepKm = 10;  // gridStepDeg 0: 1 on maps, 0.5 along sections
};

// "LAT,LON" in degrees -> a section's end.
state::SectionState::Point parsePoint(const std::string& text, const std::string& option)
{
    const auto parts = split(text, ',');
    if (parts.size() == 2) {
        try {
            size_t a = 0, b = 0;
            const double lat = std::stod(parts[0], &a), lon = std::stod(parts[1], &b);
            if (a == parts[0].size() && b == parts[1].size() && lat >= -90 && lat <= 90 && lon >= -360 && lon <= 360)
                return {float(lat), float(lon)};
        } catch (const std::exception&) {
        }
    }
    fail("{} '{}': expected LAT,LON in degrees (lat in [-90, 90], lon in [-360, 360]), e.g. -20,170", option, text);
}

// What --view and the commands map and section draw.
std::optional<StateRenderer::Slice> sliceOf(const RenderArgs& args)
{
    if (args.view == "map")
        return StateRenderer::Slice::Map;
    if (args.view == "section")
        return StateRenderer::Slice::Section;
    if (args.view != "3d")
        fail("--view '{}': expected 3d, map or section", args.view);
    return std::nullopt;
}

// The flags of maps and sections over the state's "map" and "section".
void applySliceFlags(const RenderArgs& args, state::RenderState& state)
{
    if (args.sliceDepth && args.sliceDepth->count())
        state.map.depthKm = float(args.sliceDepthKm);
    if (!args.projection.empty()) {
        try {
            state.map.projection = state::parseMapProjection(args.projection);
        } catch (const Error& e) {
            fail("--projection: {}", e.what());
        }
    }
    if (args.centralMeridian && args.centralMeridian->count()) {
        if (!(args.centralMeridianDeg >= -180 && args.centralMeridianDeg <= 180))
            fail("--central-meridian {}: expected degrees east in [-180, 180]", args.centralMeridianDeg);
        state.map.centralMeridianDeg = float(args.centralMeridianDeg);
    }
    if (args.centralLatitude && args.centralLatitude->count()) {
        if (!(args.centralLatitudeDeg >= -90 && args.centralLatitudeDeg <= 90))
            fail("--central-latitude {}: expected degrees north in [-90, 90]", args.centralLatitudeDeg);
        state.map.centralLatitudeDeg = float(args.centralLatitudeDeg);
    }
    if (args.contoursOption && args.contoursOption->count()) {
        if (args.contours.size() > 16)
            fail("--contours: {} values; at most 16", args.contours.size());
        state.map.contours.assign(args.contours.begin(), args.contours.end());
    }
    if (args.allColour)
        state.map.greyUnselected = false;
    if (args.flow)
        (args.view == "map" ? state.map.flow : state.section.flow) = true;
    if (!args.from.empty())
        state.section.from = parsePoint(args.from, "--from");
    if (!args.to.empty())
        state.section.to = parsePoint(args.to, "--to");
    const bool byAzimuth = args.azimuth && args.azimuth->count();
    if (byAzimuth != (args.length && args.length->count()))
        fail("--azimuth and --length: give both (the section's end, from its start)");
    if (byAzimuth) {
        if (!args.to.empty())
            fail("--to and --azimuth: give the section's end by one of them");
        if (!(args.azimuthDeg >= -360 && args.azimuthDeg <= 360))
            fail("--azimuth {}: expected degrees clockwise from north in [-360, 360]", args.azimuthDeg);
        if (!(args.lengthDeg >= 0.01 && args.lengthDeg <= 179.99))
            fail("--length {}: expected degrees along the surface in [0.01, 179.99] (the shorter arc; 1° is {:.0f} km)",
                 args.lengthDeg, degToRad(1.0) * kSurfaceRadiusKm);
        state.section.to = GreatCircle::pointAlong(state.section.from, args.azimuthDeg, args.lengthDeg);
    }
    if (args.view != "3d")
        checkSliceGridSpacing(args.view == "map" ? StateRenderer::Slice::Map : StateRenderer::Slice::Section,
                              args.gridStepDeg, args.depthStepKm, {"--grid-step", "--depth-step"});
}

// What the options resolve to, before anything is rendered.
struct RenderSetup {
    std::shared_ptr<const dataset::Dataset> dataset;
    ResolvedState resolved;
    int first = 0, last = 0;
    bool sequence = false, lodAuto = false;
    // -o and --depth: the step goes where they say %d or %03d (core/numbered_name.h).
    std::optional<NumberedName> output, depth;
    std::optional<StateRenderer::Slice> slice;  // a map or a section instead of the 3D view
    std::optional<NumberedName> netcdf;          // the slice's grid (maps and sections)
    // The volume of a step and level: the last one read kept, so that a slice's picture and its
    // --netcdf grid read a step once.
    std::function<std::shared_ptr<const dataset::StepVolume>(int step, int level)> volume;
    // A state with `pair` (docs/compare.md, "Side by side"): the second dataset, drawn at the right.
    std::shared_ptr<const dataset::Dataset> second;
    std::shared_ptr<StateRenderer> secondRenderer;  // its renderer (run() makes it)
};

std::function<std::shared_ptr<const dataset::StepVolume>(int, int)> lastVolumeKept(std::shared_ptr<const dataset::Dataset> dataset)
{
    struct Kept {
        int step = -1, level = -1;
        std::shared_ptr<const dataset::StepVolume> volume;
    };
    return [dataset = std::move(dataset), kept = std::make_shared<Kept>()](int step, int level) {
        if (!kept->volume || kept->step != step || kept->level != level)
            *kept = {step, level, dataset->load(step, level)};
        return kept->volume;
    };
}

// -o and --depth, checked before anything is read: one step number at most, and a --time range
// needs one, so that no two frames share a name.
std::pair<NumberedName, std::optional<NumberedName>> outputNames(const RenderArgs& args, bool sequence)
{
    NumberedName output(args.output, "-o");
    if (sequence && !output.numbered())
        fail("-o '{}': a --time range needs a numbered pattern such as frames/frame_%03d.png", args.output);
    std::optional<NumberedName> depth;
    if (!args.depthPath.empty()) {
        depth.emplace(args.depthPath, "--depth");
        if (sequence && !depth->numbered())
            fail("--depth '{}': a --time range needs a numbered pattern such as depth/depth_%03d.pfm", args.depthPath);
        if ((*depth)(0) == output(0))
            fail("--depth '{}' names the same file as -o", args.depthPath);
    }
    checkOutputExtension(args.output, {".png"}, "PNG", "-o");
    if (depth)
        checkOutputExtension(args.depthPath, {".pfm"}, "PFM", "--depth");
    return {std::move(output), std::move(depth)};
}

RenderSetup setUp(const RenderArgs& args)
{
    // Steps: one index/time, or A:B for a numbered sequence.
    const bool sequence = args.time.find(':') != std::string::npos;
    auto [output, depth] = outputNames(args, sequence);
    const std::optional<StateRenderer::Slice> slice = sliceOf(args);
    std::optional<NumberedName> netcdf;
    if (!args.netcdf.empty()) {
        netcdf.emplace(args.netcdf, "--netcdf");
        if (sequence && !netcdf->numbered())
            fail("--netcdf '{}': a --time range needs a numbered pattern such as maps/slice_%03d.nc", args.netcdf);
        if ((*netcdf)(0) == output(0))
            fail("--netcdf '{}' names the same file as -o", args.netcdf);
        checkOutputExtension(args.netcdf, {".nc", ".nc4", ".cdf"}, "netCDF", "--netcdf");
        regularOutputPath((*netcdf)(0), "the --netcdf grid");  // before the picture is written
    }
    if (slice) {
        // What only the 3D view has.
        if (depth)
            fail("--depth (the depth along the view rays) is only for --view 3d");
        if (!args.stereo.empty() || args.pathlines || args.pathlineRadiusKm != 0 || args.passes != 0)
            fail("--stereo, --pathlines, --pathline-radius and --passes are only for the 3D view, not for a {}",
                 args.view);
    }
    const auto dataset = dataset::Dataset::open(args.dataset);
    // Without a state: the UI's first view (render::defaultState), so that a figure made from the
    // command line and the browser's first picture are the same.
    state::RenderState state = args.statePath.empty() ? defaultState(*dataset) : state::loadRenderState(args.statePath);

    // Flags override the state.
    if (!args.size.empty())
        std::tie(state.width, state.height) = parseSize(args.size);
    if (!args.var.empty()) {
        if (dataset->variableIndex(args.var) < 0) {
            fail("--var: unknown variable '{}'; the dataset has: {}", args.var,
                 fmt::join(dataset->variableNames(), ", "));
        }
        if (state.colorVariable != args.var)
            state.colorRange.reset();
        state.colorVariable = args.var;
    }
    if (!args.colormap.empty()) {
        try {
            state.colorMap = state::parseColorMap(args.colormap);
        } catch (const Error& e) {
            fail("--colormap: {}", e.what());
        }
    }
    applyRangeOptions(state.brushes, args.ranges);
    // Scripted figures are deterministic: the state's level, else level 0; only --lod auto lets the
    // machine's speed choose (the finest level within the state's time budget).
    const bool lodAuto = args.lod == "auto";
    if (!args.lod.empty()) {
        if (lodAuto) {
            state.level.reset();
        } else {
            int level = -1;
            try {
                size_t used = 0;
                level = std::stoi(args.lod, &used);
                if (used != args.lod.size())
                    level = -1;
            } catch (const std::exception&) {
            }
            if (level < 0 || level >= int(dataset->levels().size()))
                fail("--lod '{}': expected auto or a level in 0..{}", args.lod, dataset->levels().size() - 1);
            state.level = level;
        }
    }
    if (args.passes != 0) {
        if (args.passes < 1)
            fail("--passes {}: expected at least 1", args.passes);
        state.passes = args.passes;
    }

    if (args.pathlines)
        state.pathlines.visible = true;
    if (args.legend)
        state.legend = true;
    for (const std::string& what : args.reference) {
        if (what == "shells")
            state.reference.shells.visible = true;
        else if (what == "graticule")
            state.reference.graticule.visible = true;
        else if (what == "coastlines")
            state.reference.coastlines.visible = true;
        else
            fail("--reference '{}': expected shells, graticule or coastlines", what);
    }
    if (!args.stereo.empty()) {
        try {
            state.stereo.mode = state::parseStereoMode(args.stereo);
        } catch (const Error& e) {
            fail("--stereo: {}", e.what());
        }
    }
    if (args.pathlineRadiusKm != 0) {
        if (!(args.pathlineRadiusKm > 0) || !std::isfinite(args.pathlineRadiusKm))
            fail("--pathline-radius {}: expected a positive number of km", args.pathlineRadiusKm);
        state.pathlines.radiusKm = float(args.pathlineRadiusKm);
        state.pathlines.visible = true;
    }

    // Without --time: the state's step (0 without a state), so that a state saved at step 6 renders
    // step 6, as the UI showed it.
    const auto [first, last] = args.time.empty() ? std::pair<int, int>(state.step, state.step)
                                                 : parseStepRange(*dataset, args.time);
    state.step = first;
    applySliceFlags(args, state);
    // Before anything is allocated: a picture larger than memory is refused with the figures.
    checkPictureFitsMemory(state, depth.has_value(), availableMemory());
    ResolvedState resolved = resolveState(state, *dataset);
    if (slice == StateRenderer::Slice::Section)
        GreatCircle(resolved.state.section.from, resolved.state.section.to, "--from/--to");  // checked before reading
    std::shared_ptr<const dataset::Dataset> second;
    if (state.pair) {
        // The pair's two halves are whole pictures of one process, of the 3D view.
        if (slice || depth || state.stereo.enabled() || mpi::distributed())
            fail("{}: pair: a pair of datasets is drawn as two 3D views side by side by one process; not with "
                 "--view map|section, --depth, stereo or under mpirun",
                 args.statePath);
        try {
            second = dataset::Dataset::open(state.pair->dataset);
        } catch (const Error& e) {
            failLike(e, fmt::format("{}: pair.dataset: {}", args.statePath, e.what()));
        }
        pairHalves(state, *dataset, *second);  // checks the width and the state against both before rendering
    }
    return {dataset,          resolved,          first, last, sequence, lodAuto, std::move(output), std::move(depth),
            slice,            std::move(netcdf), {},    std::move(second), nullptr};
}

// A pair's step (docs/compare.md, "Side by side"): each dataset's half through its StateRenderer, the
// second's state from the first's (render::pairHalves), composed and written as one PNG.
nlohmann::json renderPairStep(const RenderSetup& setup, StateRenderer& renderer, const LevelPolicy& policy,
                              const ResolvedState& resolved)
{
    const int step = resolved.state.step;
    const PairHalves halves = pairHalves(resolved.state, *setup.dataset, *setup.second);
    const ResolvedState left = resolveState(halves.left, *setup.dataset);
    const ResolvedState right = resolveState(halves.right.state, *setup.second);
    nlohmann::json levels = nlohmann::json::array();
    auto draw = [&](StateRenderer& r, const ResolvedState& view) {
        const StateRenderer::Prepared prepared = r.prepare(view, policy);
        levels.push_back(prepared.level);
        ViewFrames frames = prepared.frames();
        for (int pass = 0; pass < view.state.passes; ++pass)
            prepared.renderPass(frames, nullptr, {});
        return r.picture(frames, view, true);
    };
    const auto t0 = std::chrono::steady_clock::now();
    const ImageRgba8 image = sideBySide(draw(renderer, left), draw(*setup.secondRenderer, right));
    const std::string out = (*setup.output)(step);
    if (const auto parent = std::filesystem::path(out).parent_path(); !parent.empty())
        std::filesystem::create_directories(parent);
    writePng(out, image);
    return {{"step", step},
            {"timeMyr", setup.dataset->steps()[size_t(step)].timeMyr},
            {"pair",
             {{"step", right.state.step},
              {"timeMyr", setup.second->steps()[size_t(right.state.step)].timeMyr},
              {"notes", halves.right.notes}}},
            {"levels", levels},
            {"output", out},
            {"size", {image.width, image.height}},
            {"seconds", std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count()}};
}

// Renders one step (only the tiles of `share`; rank 0 then gathers them all when `share` is shared
// out), writes its PNG (and depth) from the rank that holds the whole frame, and returns its
// statistics. With a shared-out frame every rank must call it (collective).
nlohmann::json renderStep(const RenderArgs& args, const RenderSetup& setup, StateRenderer& renderer,
                          const LevelPolicy& policy, int step, TileShare share)
{
    const dataset::Dataset& dataset = *setup.dataset;
    ResolvedState resolved = setup.resolved;
    resolved.state.step = step;
    const auto makeParent = [](const std::string& file) {
        if (const auto parent = std::filesystem::path(file).parent_path(); !parent.empty()) {
            // Ranks writing frames may create the directory at the same time: existing is fine.
            std::error_code ec;
            std::filesystem::create_directories(parent, ec);
            if (ec && !std::filesystem::is_directory(parent))
                fail("{}: cannot create the directory ({})", parent.string(), ec.message());
        }
    };
    if (setup.slice) {
        // A map or a section: one rank draws it whole.
        const auto t0 = std::chrono::steady_clock::now();
        const ImageRgba8 image = renderer.slicePicture(resolved, *setup.slice);
        // Both made before either is written: a grid that cannot be made leaves no picture.
        std::optional<io::CfGridFile> grid;
        if (setup.netcdf)
            grid = sliceGridFile(dataset, *setup.volume(step, resolved.state.level.value_or(0)), resolved,
                                 *setup.slice, args.gridStepDeg, args.depthStepKm, "raypc " + args.view);
        const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
        const std::string out = (*setup.output)(step);
        makeParent(out);
        writePng(out, image);
        nlohmann::json stats{{"step", step},
                             {"timeMyr", dataset.steps()[size_t(step)].timeMyr},
                             {"level", resolved.state.level.value_or(0)},
                             {"view", args.view},
                             {"output", out},
                             {"size", {image.width, image.height}},
                             {"seconds", seconds}};
        if (grid) {
            const std::string path = (*setup.netcdf)(step);
            makeParent(path);
            io::writeCfGrid(path, *grid);
            stats["netcdf"] = path;
        }
        return stats;
    }
    if (setup.second)
        return renderPairStep(setup, renderer, policy, resolved);
    ViewFrames frames;  // one, or a stereo pair's two eyes
    nlohmann::json passes = nlohmann::json::array();
    PassStats total;
    int level = 0;
    size_t pathlinesShown = 0;
    // A shared-out frame's phases end with every rank agreeing; a whole frame is one rank's work
    // (inside mpi::forEachDynamic, which agrees at its end), so no collective here.
    const auto phase = [&](const std::function<void()>& work) {
        if (share.all())
            work();
        else
            mpi::together(work);
    };
    phase([&] {
        const StateRenderer::Prepared prepared = renderer.prepare(resolved, policy);
        level = prepared.level;
        pathlinesShown = prepared.scene ? prepared.scene->visibleCount() : 0;
        frames = prepared.frames();
        for (int pass = 0; pass < resolved.state.passes; ++pass) {
            const PassStats s = prepared.renderPass(frames, nullptr, share);
            passes.push_back(toJson(s, PassStatsJson::pass));
            total += s;
        }
    });
    mpi::dieHook("render-frame");
    if (!share.all()) {
        for (FrameBuffer& frame : frames)
            gatherTilesToRoot(frame);
        // The work of every rank; "passes" and "seconds" stay rank 0's.
        const PassStats::Counts mine = total.counts();
        std::array<int64_t, std::tuple_size_v<PassStats::Counts>> all;
        std::copy(mine.begin(), mine.end(), all.begin());
        mpi::sum(all);
        PassStats::Counts others;  // the other ranks' counters
        for (size_t i = 0; i < mine.size(); ++i)
            others[i] = uint64_t(all[i]) - mine[i];
        total.addCounts(others);
    }
    const std::string out = (*setup.output)(step);
    phase([&] {
        if (!share.all() && !mpi::isRoot())
            return;
        makeParent(out);
        writePng(out, renderer.picture(frames, resolved, true));
        if (setup.depth) {
            int width = 0, height = 0;
            const std::vector<float> depth = averagedDepthKm(frames, width, height);  // stereo: the eyes side by side
            writePfm((*setup.depth)(step), width, height, depth);
        }
    });
    const StereoLayout layout = stereoLayout(resolved.state.stereo.mode, resolved.state.width, resolved.state.height);
    nlohmann::json stats = toJson(total, PassStatsJson::frame);
    stats.update({{"step", step},
                  {"timeMyr", dataset.steps()[size_t(step)].timeMyr},
                  {"level", level},
                  {"pathlinesShown", pathlinesShown},
                  {"output", out},
                  {"size", {layout.width, layout.height}},
                  {"ranks", share.count},
                  {"passes", passes}});
    return stats;
}

// Under mpirun: a sequence spreads its frames over the ranks (handed out one at a time, each
// written by the rank that rendered it); a single frame is shared out by tiles and written by
// rank 0 (docs/scaling.md).
void run(const RenderArgs& args)
{
    RenderSetup setup;
    mpi::together([&] { setup = setUp(args); });
    setup.volume = lastVolumeKept(setup.dataset);
    if (setup.second)
        setup.secondRenderer = std::make_shared<StateRenderer>(setup.second);
    StateRenderer renderer(setup.dataset, setup.slice ? StateSources{.volume = setup.volume, .pathlines = {}, .featureLabels = {}} : StateSources{});
    LevelPolicy policy;  // level 0 unless the state names one
    if (setup.lodAuto && !setup.resolved.state.level && !setup.slice) {
        mpi::together([&] {
            if (mpi::isRoot())
                policy.samplesPerSecond = renderer.measureSamplesPerSecond(setup.first, setup.resolved.params);
        });
        // Every rank must choose the same level: rank 0's measure decides.
        policy.samplesPerSecond = std::stod(mpi::broadcast(fmt::format("{:.17g}", policy.samplesPerSecond)));
    }
    nlohmann::json statsJson = nlohmann::json::array();
    if (mpi::distributed() && setup.first == setup.last && !setup.slice) {
        statsJson.push_back(renderStep(args, setup, renderer, policy, setup.first, rankTileShare()));
    } else {
        mpi::forEachDynamic(setup.last - setup.first + 1, [&](int64_t item) {
            statsJson.push_back(renderStep(args, setup, renderer, policy, setup.first + int(item), {}));
        });
        // Every rank's frames, in step order.
        nlohmann::json all = nlohmann::json::array();
        for (const std::string& part : mpi::gatherToRoot(statsJson.dump()))
            for (auto& frame : nlohmann::json::parse(part))
                all.push_back(std::move(frame));
        std::sort(all.begin(), all.end(), [](const nlohmann::json& a, const nlohmann::json& b) {
            return a.at("step").get<int>() < b.at("step").get<int>();
        });
        statsJson = std::move(all);
    }
    if (args.stats && mpi::isRoot())
        fmt::print("{}\n", (setup.sequence ? statsJson : statsJson[0]).dump(2));
}

// Preprocesses netCDF files given instead of a dataset (quick when complete; collective under
// mpirun), then draws.
void runCommand(RenderArgs& args)
{
    const auto [series, options] = args.series.resolve();
    if (series.fromFiles())
        prepareSeries(series, options);
    args.dataset = series.dataset.string();
    run(args);
}

// The options every picture takes (the 3D view, maps and sections).
void addPictureOptions(CLI::App& cmd, RenderArgs& args)
{
    args.series.add(cmd, "preprocessed first, reused by later runs");
    cmd.add_option("-t,--time", args.time,
                   "Step index (0-based) or time like 24Myr; A:B renders steps A..B into a numbered sequence "
                   "(default: the state's step, else 0)");
    cmd.add_option("-o,--output", args.output,
                   "Output PNG; for --time A:B a pattern like frames/frame_%03d.png (%d or %0Nd, N <= 9: the step; %%: a %)")
        ->required();
    cmd.add_option("--size", args.size, "Image size WIDTHxHEIGHT (default 512x512 or the state's)");
    cmd.add_option("--state", args.statePath, "STATE.json saved by the browser UI (docs/state.md)");
    cmd.add_option("--var", args.var, "Colouring variable (default: the state's, else temperature anomaly as in the UI's first view)");
    std::vector<std::string> mapNames;
    for (const ColorMapId map : state::allColorMaps())
        mapNames.emplace_back(state::colorMapName(map));
    cmd.add_option("--colormap", args.colormap, fmt::format("Colour map of the colouring variable: {}", fmt::join(mapNames, ", ")));
    cmd.add_option("--range", args.ranges,
                   "Brush NAME=MIN:MAX on a variable or coordinate (x, y, z, lat, lon, radius, depth); repeatable, a "
                   "name given twice selects either range (OR); replaces the state's ranges of that name");
    cmd.add_option("--lod", args.lod, "Level of detail: 0 (full), 1, 2, or auto (fit the state's time budget)");
    cmd.add_flag("--stats", args.stats, "Print JSON statistics: time per pass, samples, bricks, rate");
    cmd.add_option("--reference", args.reference,
                   "Reference geometry to draw: shells (410, 660, 1000, 1600, 2200 km or the state's), "
                   "graticule, coastlines; repeatable");
}

// The options of maps and sections (the state's "map" and "section"); `view` is map or section.
void addSliceOptions(CLI::App& cmd, RenderArgs& args, const std::string& view)
{
    args.view = view;
    args.contoursOption = cmd.add_option("--contours", args.contours, "Contour lines at these values of the colouring variable (comma-separated)")
                              ->delimiter(',');
    cmd.add_flag("--flow", args.flow,
                 view == "map" ? "Arrows of the horizontal flow at the depth (needs vx, vy, vz)"
                               : "Arrows of the flow in the section's plane: along the profile and radial (needs vx, vy, vz)");
    cmd.add_flag("--all-colour", args.allColour, "Colour what lies outside the brushes too (default: grey)");
    cmd.add_option("--netcdf", args.netcdf,
                   view == "map" ? "Also write the slice as a CF netCDF lat-lon grid (GMT, xarray, Panoply read it)"
                                 : "Also write the section as a CF netCDF distance-depth grid");
    cmd.add_option("--grid-step", args.gridStepDeg,
                   view == "map" ? "Spacing of the --netcdf grid, degrees (divides 180; default 1)"
                                 : "Spacing of the --netcdf grid along the profile, degrees (default 0.5)");
}

const CommandRegistration kRenderCommand(
    "render", "Render a step (or a sequence of steps) of a dataset to PNG with the spherical volume ray caster",
    [](CLI::App& cmd) {
        auto args = std::make_shared<RenderArgs>();
        addPictureOptions(cmd, *args);
        cmd.add_option("--passes", args->passes, "Progressive passes to accumulate (default: the state's, 8)");
        cmd.add_option("--depth", args->depthPath, "Also write the depth (km along the view ray) as PFM (a pattern as -o)");
        cmd.add_flag("--pathlines", args->pathlines,
                     "Show the pathlines injected in the last 10 steps (or the state's window) as tubes");
        cmd.add_option("--pathline-radius", args->pathlineRadiusKm, "Tube radius in km (implies --pathlines; default 12)");
        cmd.add_flag("--legend", args->legend, "Draw colour legends (variable, units, range; pathlines' colouring)");
        cmd.add_option("--stereo", args->stereo,
                       "Stereo pair: off, side-by-side (2W x H), side-by-side-half (W x H), anaglyph (red-cyan); eye "
                       "separation and convergence from the state (docs/state.md)");
        cmd.add_option("--view", args->view,
                       "What to draw: 3d (the volume, default), map or section (the state's map or section, as "
                       "raypc map and raypc section draw them)");
        cmd.callback([args] { runCommand(*args); });
    },
    60, Ranks::AllRanks);

const CommandRegistration kMapCommand(
    "map",
    "Draw a map of a depth slice (the colouring variable on the sphere at one depth, in a map projection, with "
    "coastlines, contours, flow arrows and the brushes greyed out) to PNG; optionally export it as CF netCDF",
    [](CLI::App& cmd) {
        auto args = std::make_shared<RenderArgs>();
        addPictureOptions(cmd, *args);
        addSliceOptions(cmd, *args, "map");
        args->sliceDepth = cmd.add_option("--depth", args->sliceDepthKm, "Depth of the slice below the surface, km (default: the state's, 660)");
        std::vector<std::string> names;
        for (const MapProjection p : state::allMapProjections())
            names.emplace_back(state::mapProjectionName(p));
        cmd.add_option("--projection", args->projection, fmt::format("Map projection: {} (default: the state's, mollweide)", fmt::join(names, ", ")));
        args->centralMeridian = cmd.add_option("--central-meridian", args->centralMeridianDeg, "Longitude at the map's centre, degrees east");
        args->centralLatitude = cmd.add_option("--central-latitude", args->centralLatitudeDeg, "Latitude at the centre of the orthographic projection, degrees north");
        cmd.callback([args] { runCommand(*args); });
    },
    61, Ranks::AllRanks);

const CommandRegistration kSectionCommand(
    "section",
    "Draw a vertical section along a great circle (surface to the core-mantle boundary, depth down, distance in km "
    "and degrees, reference depths as lines, contours, flow arrows) to PNG; optionally export it as CF netCDF",
    [](CLI::App& cmd) {
        auto args = std::make_shared<RenderArgs>();
        addPictureOptions(cmd, *args);
        addSliceOptions(cmd, *args, "section");
        cmd.add_option("--from", args->from, "Start of the section on the surface, LAT,LON degrees (default: the state's)");
        cmd.add_option("--to", args->to, "End of the section on the surface, LAT,LON degrees (the shorter arc is drawn)");
        args->azimuth = cmd.add_option("--azimuth", args->azimuthDeg,
                                       "Instead of --to: the direction the section leaves its start in, degrees clockwise from north");
        args->length = cmd.add_option("--length", args->lengthDeg,
                                      "With --azimuth: the section's length, degrees along the surface (below 180; 1° is 111 km)");
        cmd.add_option("--depth-step", args->depthStepKm, "Spacing of the --netcdf grid in depth, km (default 10)");
        cmd.callback([args] { runCommand(*args); });
    },
    62, Ranks::AllRanks);

}  // namespace
}  // namespace raypc::app
