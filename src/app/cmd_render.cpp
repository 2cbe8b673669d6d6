// raypc render DATASET|FILE.nc… [--dataset DIR] --time T -o out.png [--size WxH] [--state STATE.json] [--var NAME]
//   [--colormap NAME] [--range NAME=MIN:MAX]... [--lod N|auto] [--passes N] [--depth depth.pfm] [--stats]
//   [--pathlines] [--pathline-radius KM] [--legend] [--reference shells|graticule|coastlines]...
//   [--stereo off|side-by-side|side-by-side-half|anaglyph]
#include "app/command.h"
#include "app/options.h"
#include "app/series_inputs.h"
#include "core/error.h"
#include "core/mpi.h"
#include "core/numbered_name.h"
#include "core/strings.h"
#include "data/dataset.h"
#include "render/image_io.h"
#include "render/pathline_scene.h"
#include "render/render_state.h"
#include "render/state_renderer.h"

#include <fmt/format.h>
#include <fmt/ranges.h>
#include <nlohmann/json.hpp>

#include <algorithm>
#include <array>
#include <optional>
#include <functional>
#include <filesystem>

namespace raypc::app {
namespace {

using namespace raypc::render;

struct RenderArgs {
    SeriesFlags series;  // a dataset, or netCDF files
    std::string dataset, time = "0", output, size, statePath, var, colormap, lod, depthPath;
    std::vector<std::string> ranges;
    int passes = 0;
    bool stats = false;
    bool pathlines = false;
    double pathlineRadiusKm = 0;  // 0: the state's
    bool legend = false;
    std::vector<std::string> reference;  // shells, graticule, coastlines
    std::string stereo;                  // a stereo mode; empty: the state's
};

// "1024x768" -> width, height.
std::pair<int, int> parseSize(const std::string& text)
{
    const auto parts = split(text, 'x');
    try {
        if (parts.size() == 2) {
            size_t a = 0, b = 0;
            const int w = std::stoi(parts[0], &a), h = std::stoi(parts[1], &b);
            if (a == parts[0].size() && b == parts[1].size() && w >= 1 && h >= 1 && w <= 16384 && h <= 16384)
                return {w, h};
        }
    } catch (const std::exception&) {
    }
    fail("--size '{}': expected WIDTHxHEIGHT with 1..16384 pixels per side, e.g. 1024x768", text);
}


// What the options resolve to, before anything is rendered.
struct RenderSetup {
    std::shared_ptr<const Dataset> dataset;
    ResolvedState resolved;
    int first = 0, last = 0;
    bool sequence = false, lodAuto = false;
    // -o and --depth: the step goes where they say %d or %03d (core/numbered_name.h).
    std::optional<NumberedName> output, depth;
};

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
    return {std::move(output), std::move(depth)};
}

RenderSetup setUp(const RenderArgs& args)
{
    // Steps: one index/time, or A:B for a numbered sequence.
    const bool sequence = args.time.find(':') != std::string::npos;
    auto [output, depth] = outputNames(args, sequence);
    const auto dataset = Dataset::open(args.dataset);
    // Without a state: the UI's first view (render::defaultState), so that a figure made from the
    // command line and the browser's first picture are the same.
    RenderState state = args.statePath.empty() ? defaultState(*dataset) : loadRenderState(args.statePath);

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
            state.colorMap = parseColorMap(args.colormap);
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
            state.stereo.mode = parseStereoMode(args.stereo);
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

    const auto [first, last] = parseStepRange(*dataset, args.time);
    state.step = first;
    // Before anything is allocated: a picture larger than memory is refused with the figures.
    checkPictureFitsMemory(state, depth.has_value(), availableMemory());
    return {dataset, resolveState(state, *dataset), first, last, sequence, lodAuto, std::move(output), std::move(depth)};
}

// Renders one step (only the tiles of `share`; rank 0 then gathers them all when `share` is shared
// out), writes its PNG (and depth) from the rank that holds the whole frame, and returns its
// statistics. With a shared-out frame every rank must call it (collective).
nlohmann::json renderStep(const RenderArgs& args, const RenderSetup& setup, StateRenderer& renderer,
                          const LevelPolicy& policy, int step, TileShare share)
{
    const Dataset& dataset = *setup.dataset;
    ResolvedState resolved = setup.resolved;
    resolved.state.step = step;
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
            passes.push_back({{"seconds", s.seconds},
                              {"samples", s.samples},
                              {"samplesSkipped", s.samplesSkipped},
                              {"samplesPerSecondPerThread", s.samplesPerSecondPerThread()},
                              {"dataSamplesPerSecondPerThread", s.dataSamplesPerSecondPerThread()}});
            total += s;
        }
    });
    mpi::dieHook("render-frame");
    if (!share.all()) {
        for (FrameBuffer& frame : frames)
            gatherTilesToRoot(frame);
        // The work of every rank; "passes" and "seconds" stay rank 0's.
        std::array<int64_t, 4> counts{int64_t(total.samples), int64_t(total.samplesSkipped), int64_t(total.chunks),
                                      int64_t(total.chunksJumped)};
        mpi::sum(counts);
        total.samples = uint64_t(counts[0]);
        total.samplesSkipped = uint64_t(counts[1]);
        total.chunks = uint64_t(counts[2]);
        total.chunksJumped = uint64_t(counts[3]);
    }
    const std::string out = (*setup.output)(step);
    phase([&] {
        if (!share.all() && !mpi::isRoot())
            return;
        if (const auto parent = std::filesystem::path(out).parent_path(); !parent.empty()) {
            // Ranks writing frames may create the directory at the same time: existing is fine.
            std::error_code ec;
            std::filesystem::create_directories(parent, ec);
            if (ec && !std::filesystem::is_directory(parent))
                fail("{}: cannot create the directory ({})", parent.string(), ec.message());
        }
        writePng(out, renderer.picture(frames, resolved, true));
        if (setup.depth) {
            int width = 0, height = 0;
            const std::vector<float> depth = averagedDepthKm(frames, width, height);  // stereo: the eyes side by side
            writePfm((*setup.depth)(step), width, height, depth);
        }
    });
    const StereoLayout layout = stereoLayout(resolved.state.stereo.mode, resolved.state.width, resolved.state.height);
    return {{"step", step},
            {"timeMyr", dataset.steps()[size_t(step)].timeMyr},
            {"level", level},
            {"pathlinesShown", pathlinesShown},
            {"output", out},
            {"size", {layout.width, layout.height}},
            {"ranks", share.count},
            {"threads", total.threads},
            {"simdLanes", total.simdLanes},
            {"passes", passes},
            {"seconds", total.seconds},
            {"samples", total.samples},
            {"samplesSkipped", total.samplesSkipped},
            {"bricksVisited", total.bricksTotal - total.bricksSkipped},
            {"bricksSkipped", total.bricksSkipped},
            {"chunks", total.chunks},
            {"chunksJumped", total.chunksJumped},
            {"samplesPerSecondPerThread", total.samplesPerSecondPerThread()},
            {"dataSamplesPerSecondPerThread", total.dataSamplesPerSecondPerThread()}};
}

// Under mpirun: a sequence spreads its frames over the ranks (handed out one at a time, each
// written by the rank that rendered it); a single frame is shared out by tiles and written by
// rank 0 (docs/scaling.md).
void run(const RenderArgs& args)
{
    RenderSetup setup;
    mpi::together([&] { setup = setUp(args); });
    StateRenderer renderer(setup.dataset);
    LevelPolicy policy;  // level 0 unless the state names one
    if (setup.lodAuto && !setup.resolved.state.level) {
        mpi::together([&] {
            if (mpi::isRoot())
                policy.samplesPerSecond = renderer.measureSamplesPerSecond(setup.first, setup.resolved.params);
        });
        // Every rank must choose the same level: rank 0's measure decides.
        policy.samplesPerSecond = std::stod(mpi::broadcast(fmt::format("{:.17g}", policy.samplesPerSecond)));
    }
    nlohmann::json statsJson = nlohmann::json::array();
    if (mpi::distributed() && setup.first == setup.last) {
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

const CommandRegistration kRenderCommand(
    "render", "Render a step (or a sequence of steps) of a dataset to PNG with the spherical volume ray caster",
    [](CLI::App& cmd) {
        auto args = std::make_shared<RenderArgs>();
        args->series.add(cmd, "preprocessed first, reused by later runs");
        cmd.add_option("-t,--time", args->time,
                       "Step index (0-based) or time like 24Myr; A:B renders steps A..B into a numbered sequence")
            ->capture_default_str();
        cmd.add_option("-o,--output", args->output, "Output PNG; for --time A:B a pattern like frames/frame_%03d.png (%d or %0Nd, N <= 9: the step; %%: a %)")
            ->required();
        cmd.add_option("--size", args->size, "Image size WIDTHxHEIGHT (default 512x512 or the state's)");
        cmd.add_option("--state", args->statePath, "STATE.json saved by the browser UI (docs/state.md)");
        cmd.add_option("--var", args->var, "Colouring variable (default: the state's, else temperature anomaly as in the UI's first view)");
        std::vector<std::string> mapNames;
        for (const ColorMapId map : allColorMaps())
            mapNames.emplace_back(colorMapName(map));
        cmd.add_option("--colormap", args->colormap,
                       fmt::format("Colour map of the colouring variable: {}", fmt::join(mapNames, ", ")));
        cmd.add_option("--range", args->ranges,
                       "Brush NAME=MIN:MAX on a variable or coordinate (x, y, z, lat, lon, radius, depth); repeatable, a "
                       "name given twice selects either range (OR); replaces the state's ranges of that name");
        cmd.add_option("--lod", args->lod, "Level of detail: 0 (full), 1, 2, or auto (fit the state's time budget)");
        cmd.add_option("--passes", args->passes, "Progressive passes to accumulate (default: the state's, 8)");
        cmd.add_option("--depth", args->depthPath, "Also write the depth (km along the view ray) as PFM (a pattern as -o)");
        cmd.add_flag("--stats", args->stats, "Print JSON statistics: time per pass, samples, bricks, rate");
        cmd.add_flag("--pathlines", args->pathlines,
                     "Show the pathlines injected in the last 10 steps (or the state's window) as tubes");
        cmd.add_option("--pathline-radius", args->pathlineRadiusKm, "Tube radius in km (implies --pathlines; default 12)");
        cmd.add_flag("--legend", args->legend, "Draw colour legends (variable, units, range; pathlines' colouring)");
        cmd.add_option("--reference", args->reference,
                       "Reference geometry to draw: shells (410, 660, 1000, 1600, 2200 km or the state's), "
                       "graticule, coastlines; repeatable");
        cmd.add_option("--stereo", args->stereo,
                       "Stereo pair: off, side-by-side (2W x H), side-by-side-half (W x H), anaglyph (red-cyan); eye "
                       "separation and convergence from the state (docs/state.md)");
        cmd.callback([args] {
            const auto [series, options] = args->series.resolve();
            if (series.fromFiles())
                prepareSeries(series, options);  // quick when complete; collective under mpirun
            args->dataset = series.dataset.string();
            run(*args);
        });
    },
    60, Ranks::AllRanks);

}  // namespace
}  // namespace raypc::app
