// raypc render DATASET --time T -o out.png [--size WxH] [--state STATE.json] [--var NAME]
//   [--colormap NAME] [--range NAME=MIN:MAX]... [--lod N|auto] [--passes N] [--depth depth.pfm] [--stats]
//   [--pathlines] [--pathline-radius KM] [--legend] [--reference shells|graticule|coastlines]...
#include "app/command.h"
#include "app/options.h"
#include "core/error.h"
#include "core/strings.h"
#include "data/dataset.h"
#include "render/image_io.h"
#include "render/pathline_scene.h"
#include "render/render_state.h"
#include "render/state_renderer.h"

#include <fmt/format.h>
#include <nlohmann/json.hpp>

#include <cstdio>
#include <filesystem>

namespace raypc::app {
namespace {

using namespace raypc::render;

struct RenderArgs {
    std::string dataset, time = "0", output, size, statePath, var, colormap, lod, depthPath;
    std::vector<std::string> ranges;
    int passes = 0;
    bool stats = false;
    bool pathlines = false;
    double pathlineRadiusKm = 0;  // 0: the state's
    bool legend = false;
    std::vector<std::string> reference;  // shells, graticule, coastlines
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


// Expands a printf-style "%03d" pattern for sequences; a plain name is used as is.
std::string frameName(const std::string& pattern, int step, bool sequence)
{
    if (!sequence)
        return pattern;
    const size_t pct = pattern.find('%');
    const size_t d = pct == std::string::npos ? pct : pattern.find('d', pct);
    if (d == std::string::npos)
        fail("-o '{}': a --time range needs a numbered pattern such as frames/frame_%03d.png", pattern);
    std::string spec = pattern.substr(pct, d - pct + 1);
    char buffer[64];
    std::snprintf(buffer, sizeof buffer, spec.c_str(), step);
    return pattern.substr(0, pct) + buffer + pattern.substr(d + 1);
}

void run(const RenderArgs& args)
{
    const auto dataset = Dataset::open(args.dataset);
    RenderState state = args.statePath.empty() ? RenderState{} : loadRenderState(args.statePath);

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
    if (args.pathlineRadiusKm != 0) {
        if (!(args.pathlineRadiusKm > 0) || !std::isfinite(args.pathlineRadiusKm))
            fail("--pathline-radius {}: expected a positive number of km", args.pathlineRadiusKm);
        state.pathlines.radiusKm = float(args.pathlineRadiusKm);
        state.pathlines.visible = true;
    }

    // Steps: one index/time, or A:B for a numbered sequence.
    const bool sequence = args.time.find(':') != std::string::npos;
    const auto [first, last] = parseStepRange(*dataset, args.time);
    state.step = first;
    ResolvedState resolved = resolveState(state, *dataset);
    const RenderParams& params = resolved.params;

    StateRenderer renderer(dataset);
    LevelPolicy policy;  // level 0 unless the state names one
    if (lodAuto && !state.level)
        policy.samplesPerSecond = renderer.measureSamplesPerSecond(first, params);
    nlohmann::json statsJson = nlohmann::json::array();
    for (int step = first; step <= last; ++step) {
        resolved.state.step = step;
        const StateRenderer::Prepared prepared = renderer.prepare(resolved, policy);
        const int level = prepared.level;
        const size_t pathlinesShown = prepared.scene ? prepared.scene->visibleCount() : 0;
        FrameBuffer frame(params.width, params.height);
        nlohmann::json passes = nlohmann::json::array();
        PassStats total;
        for (int pass = 0; pass < state.passes; ++pass) {
            const PassStats s = prepared.renderer->renderPass(frame);
            passes.push_back({{"seconds", s.seconds},
                              {"samples", s.samples},
                              {"samplesSkipped", s.samplesSkipped},
                              {"samplesPerSecondPerThread", s.samplesPerSecondPerThread()},
                              {"dataSamplesPerSecondPerThread", s.dataSamplesPerSecondPerThread()}});
            total.seconds += s.seconds;
            total.samples += s.samples;
            total.samplesSkipped += s.samplesSkipped;
            total.chunks += s.chunks;
            total.chunksJumped += s.chunksJumped;
            total.threads = s.threads;
            total.simdLanes = s.simdLanes;
            total.bricksTotal = s.bricksTotal;
            total.bricksSkipped = s.bricksSkipped;
        }
        const std::string out = frameName(args.output, step, sequence);
        if (const auto parent = std::filesystem::path(out).parent_path(); !parent.empty())
            std::filesystem::create_directories(parent);
        writePng(out, {params.width, params.height, renderer.picture(frame, resolved, true)});
        if (!args.depthPath.empty())
            writePfm(frameName(args.depthPath, step, sequence), params.width, params.height, frame.averagedDepthKm());
        statsJson.push_back({{"step", step},
                             {"timeMyr", dataset->steps()[size_t(step)].timeMyr},
                             {"level", level},
                             {"pathlinesShown", pathlinesShown},
                             {"output", out},
                             {"size", {params.width, params.height}},
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
                             {"dataSamplesPerSecondPerThread", total.dataSamplesPerSecondPerThread()}});
    }
    if (args.stats)
        fmt::print("{}\n", (sequence ? statsJson : statsJson[0]).dump(2));
}

const CommandRegistration kRegistration(
    "render", "Render a step (or a sequence of steps) of a dataset to PNG with the spherical volume ray caster",
    [](CLI::App& cmd) {
        auto args = std::make_shared<RenderArgs>();
        cmd.add_option("dataset", args->dataset, "Preprocessed dataset directory (raypc preprocess)")->required();
        cmd.add_option("-t,--time", args->time,
                       "Step index (0-based) or time like 24Myr; A:B renders steps A..B into a numbered sequence")
            ->capture_default_str();
        cmd.add_option("-o,--output", args->output, "Output PNG; for --time A:B a pattern like frames/frame_%03d.png")
            ->required();
        cmd.add_option("--size", args->size, "Image size WIDTHxHEIGHT (default 512x512 or the state's)");
        cmd.add_option("--state", args->statePath, "STATE.json saved by the browser UI (docs/state.md)");
        cmd.add_option("--var", args->var, "Colouring variable (default: the state's, else the first)");
        cmd.add_option("--colormap", args->colormap, "viridis, inferno, cool-to-warm, blue-white-red, grayscale");
        cmd.add_option("--range", args->ranges,
                       "Brush NAME=MIN:MAX on a variable or coordinate (x, y, z, lat, lon, radius, depth); repeatable, a "
                       "name given twice selects either range (OR); replaces the state's ranges of that name");
        cmd.add_option("--lod", args->lod, "Level of detail: 0 (full), 1, 2, or auto (fit the state's time budget)");
        cmd.add_option("--passes", args->passes, "Progressive passes to accumulate (default: the state's, 8)");
        cmd.add_option("--depth", args->depthPath, "Also write the depth (km along the view ray) as PFM");
        cmd.add_flag("--stats", args->stats, "Print JSON statistics: time per pass, samples, bricks, rate");
        cmd.add_flag("--pathlines", args->pathlines,
                     "Show the pathlines injected in the last 10 steps (or the state's window) as tubes");
        cmd.add_option("--pathline-radius", args->pathlineRadiusKm, "Tube radius in km (implies --pathlines; default 12)");
        cmd.add_flag("--legend", args->legend, "Draw colour legends (variable, units, range; pathlines' colouring)");
        cmd.add_option("--reference", args->reference,
                       "Reference geometry to draw: shells (410, 660, 1000, 1600, 2200 km or the state's), "
                       "graticule, coastlines; repeatable");
        cmd.callback([args] { run(*args); });
    },
    60);

}  // namespace
}  // namespace raypc::app
