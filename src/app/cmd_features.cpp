// raypc features DATASET --state S.json -o features.csv: the features (connected regions) of the
// selection in every step, each measured (analysis/features.h, docs/features.md).
#include "app/command.h"
#include "app/feature_table.h"
#include "app/options.h"
#include "core/atomic_file.h"
#include "core/error.h"
#include "core/mpi.h"
#include "core/progress.h"
#include "dataset/dataset.h"
#include "analysis/feature_csv.h"
#include "analysis/feature_run.h"
#include "analysis/feature_series.h"
#include "analysis/features.h"
#include "analysis/selection.h"
#include "state/render_state.h"

#include <fmt/format.h>

#include <fmt/ranges.h>

#include <algorithm>
#include <cmath>
#include <map>
#include <optional>

namespace raypc::app {
namespace {

struct FeaturesArgs {
    SeriesSelectionFlags selection;
    std::string output, tracks, events, stalls;
    std::vector<double> depths{410, 660, 1000, 1600};
    double bandHalfWidthKm = 50, minVolumeKm3 = 0, minOverlapShare = 0.1;
    std::string stallBy;  // --stall-by; empty: the state's, else mean-depth
    analysis::StallMeasure stallMeasure = analysis::StallMeasure::MeanDepth;
    bool quiet = false;
    // Which settings the command line gave: the others come from the state's `features` (version 10)
    // when --state is given.
    bool depthsGiven = false, bandGiven = false, minVolumeGiven = false, minOverlapGiven = false, levelGiven = false;
};

// The state's feature settings for what the command line left out.
void applyStateSettings(FeaturesArgs& args)
{
    if (args.selection.statePath.empty())
        return;
    const state::FeatureSettings s = state::loadRenderState(args.selection.statePath).features;
    if (!args.depthsGiven)
        args.depths.assign(s.depthsKm.begin(), s.depthsKm.end());
    if (!args.bandGiven)
        args.bandHalfWidthKm = s.bandHalfWidthKm;
    if (!args.minVolumeGiven)
        args.minVolumeKm3 = s.minVolumeKm3;
    if (!args.minOverlapGiven)
        args.minOverlapShare = s.minOverlapShare;
    if (args.stallBy.empty())
        args.stallMeasure = s.stallBy;
    if (!args.levelGiven) {
        args.selection.level = s.level;
        args.selection.levelFrom = args.selection.statePath + ": features.level";
    }
}

// A rank's block of steps, begin..end-1 (forEachBlockStep: with tracking, each step's links from
// the previous step's features, the block's first step's too, whose previous step is another
// rank's), packed for rank 0.
std::string blockFeatures(const SeriesSelection& sel, const analysis::FeatureOptions& options, int level, int begin, int end,
                          const analysis::FeatureSeries* tracks, Progress* progress)
{
    const dataset::Dataset& dataset = *sel.dataset;
    analysis::FeatureBlockOptions block;
    if (tracks)
        block.velocity = tracks->velocity();
    block.linkFrom = sel.first;
    analysis::FeatureRunControl control;
    if (progress)
        control.progress = [&](int done, int) {
            if (done > 0)
                progress->advance();
        };
    std::string packed;
    analysis::forEachBlockStep(
        dataset, begin, end - 1, [&](int step) { return dataset.load(step, level); }, sel.filters, options, block,
        [&](const analysis::FeatureBlockStep& s) { analysis::packBlockStep(packed, s); }, control);
    return packed;
}

// Under mpirun the steps are split into contiguous blocks over the ranks (as `raypc stats` does);
// rank 0 gathers the blocks' features in rank order, which is step order, and writes the rows. With
// tracking, each rank also links its steps' features to the previous step's (finding the features of
// the step before its block as well), and rank 0 follows the tracks through the gathered features and
// links: the files are those of one process, byte for byte.
void run(FeaturesArgs args)
{
    SeriesSelection sel;
    analysis::FeatureOptions options;
    mpi::together([&] {
        for (const auto& [path, option] : {std::pair{args.output, "-o"}, {args.tracks, "--tracks"},
                                           {args.events, "--events"}, {args.stalls, "--stalls"}})
            if (!path.empty())
                checkOutputExtension(path, {".csv", ".txt"}, "CSV", option);
        if (!args.stallBy.empty())
            args.stallMeasure = analysis::parseStallMeasure(args.stallBy);
        applyStateSettings(args);
        sel = resolveSeriesSelection(args.selection);
        if (sel.filters.empty())
            fail("features: no selection: give --state with brushes or --range NAME=MIN:MAX (the whole mantle "
                 "would be one feature)");
        state::FeatureSettings settings;
        settings.minVolumeKm3 = float(args.minVolumeKm3);
        settings.depthsKm.assign(args.depths.begin(), args.depths.end());
        settings.bandHalfWidthKm = float(args.bandHalfWidthKm);
        settings.minOverlapShare = float(args.minOverlapShare);
        state::checkFeatureSettings(settings, {{"minVolumeKm3", "--min-volume"},
                                                {"depthsKm", "--depth"},
                                                {"bandHalfWidthKm", "--band-half-width"},
                                                {"minOverlapShare", "--min-overlap"}});
        options = analysis::featureOptions(args.minVolumeKm3, args.depths, args.bandHalfWidthKm);
    });
    const dataset::Dataset& dataset = *sel.dataset;
    const std::vector<analysis::RangeFilter>& filters = sel.filters;
    const int first = sel.first, last = sel.last;
    const bool tracking = !args.tracks.empty() || !args.events.empty() || !args.stalls.empty();
    std::optional<analysis::FeatureSeries> tracks;
    mpi::together([&] {
        if (tracking)
            tracks.emplace(dataset, args.minOverlapShare, "--tracks/--events/--stalls");
    });
    const mpi::Block block = mpi::blockOf(last - first + 1);
    std::string mine;
    std::optional<Progress> progress;
    if (!args.quiet && mpi::isRoot())
        progress.emplace(mpi::distributed() ? fmt::format("features (rank 0 of {})", mpi::size()) : "features",
                         block.end - block.begin, "steps");
    mpi::together([&] {
        mine = blockFeatures(sel, options, args.selection.level, first + int(block.begin), first + int(block.end),
                             tracks ? &*tracks : nullptr, progress ? &*progress : nullptr);
    });
    if (progress)
        progress->finish();
    const auto parts = mpi::gatherToRoot(mine);
    mpi::together([&] {
        if (!mpi::isRoot())
            return;
        std::string csv = featureTableHeader(dataset, options);
        size_t total = 0;
        for (const std::string& part : parts)  // rank order: step order
            for (const analysis::FeatureBlockStep& s : analysis::unpackBlockSteps(part)) {
                csv += featureTableRows(s.step, dataset.steps()[size_t(s.step)].timeMyr, s.features);
                total += s.features.features.size();
                if (tracks)
                    tracks->addLinked(s.step, s.features, s.links);
            }
        writeFileAtomic(args.output, csv);
        if (!args.tracks.empty())
            writeFileAtomic(args.tracks, analysis::trackCsv(*tracks));
        if (!args.events.empty())
            writeFileAtomic(args.events, analysis::eventCsv(*tracks, dataset));
        if (!args.stalls.empty())
            writeFileAtomic(args.stalls,
                            analysis::stallCsv(*tracks, options.bandDepthsKm, options.bandHalfWidthKm, last, args.stallMeasure));
        fmt::print("{}: {} features in {} steps ({}..{}) of {} range(s){}\n", args.output, total, last - first + 1,
                   first, last, filters.size(), mpi::distributed() ? fmt::format(" on {} ranks", mpi::size()) : "");
    });
}

const CommandRegistration kFeaturesCommand(
    "features",
    "The features of a selection in every step: its connected regions, with volume, depths, centroid and variables",
    [](CLI::App& cmd) {
        auto args = std::make_shared<FeaturesArgs>();
        args->selection.add(cmd);
        cmd.add_option("-o,--output", args->output,
                       "CSV: a row per feature and step (volume, depths, centroid, each variable's mean/min/max, "
                       "percent near each --depth)")
            ->required();
        const auto* minVolume =
            cmd.add_option("--min-volume", args->minVolumeKm3, "Drop features smaller than this, km³ (default: the state's "
                                                               "features.minVolumeKm3, else 0)");
        const auto* depths = cmd.add_option("--depth", args->depths,
                                            "Depths (km) to report each feature's share near; repeatable (default: the "
                                            "state's features.depthsKm, else 410, 660, 1000, 1600)");
        const auto* band = cmd.add_option("--band-half-width", args->bandHalfWidthKm,
                                          "Half-width of the band around each --depth, km (default: the state's, else 50)");
        cmd.add_option("--tracks", args->tracks, "CSV: each feature's track through the steps (moved with the flow)");
        cmd.add_option("--events", args->events, "CSV: births, deaths, merges and splits of the tracks");
        cmd.add_option("--stalls", args->stalls,
                       "CSV: how long each track stays at each --depth (its --stall-by depth within the band) and how "
                       "it left");
        cmd.add_option("--stall-by", args->stallBy,
                       "Which depth of a feature times its stalls: mean-depth, deepest (a sinking slab's tip) or "
                       "shallowest (a rising plume's head) (default: the state's features.stallBy, else mean-depth)");
        const auto* minOverlap = cmd.add_option("--min-overlap", args->minOverlapShare,
                                                "Share of a feature's volume carried onto another for a link between steps "
                                                "(default: the state's, else 0.1)");
        cmd.add_flag("-q,--quiet", args->quiet, "No progress output");
        const auto* lod = cmd.get_option("--lod");
        cmd.callback([args, minVolume, depths, band, minOverlap, lod] {
            args->minVolumeGiven = minVolume->count() > 0;
            args->depthsGiven = depths->count() > 0;
            args->bandGiven = band->count() > 0;
            args->minOverlapGiven = minOverlap->count() > 0;
            args->levelGiven = lod->count() > 0;
            run(*args);
        });
    },
    71, Ranks::AllRanks);

}  // namespace
}  // namespace raypc::app
