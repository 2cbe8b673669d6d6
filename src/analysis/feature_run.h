// The features of a selection step after step: the one loop behind `raypc features` (a block of
// steps per MPI rank), the server's POST /api/features (through its step cache, cancellable, with
// the job's progress; a block per rank of a distributed server) and Python's Dataset.features. Each
// step's volume comes from the caller's loader, so each keeps its own way to load (Dataset::load,
// the server's shared cache); what a step's features become (table rows, tracks) is the caller's.
//
// A block of steps (forEachBlockStep) adds to each step what needs its volume — the links from the
// previous step's features and the flux across shells — so that a block can be found by another
// process and sent, packed, to the one that follows the tracks (FeatureSeries::addLinked): the same
// numbers as one process that did every step.
//
// Thread safety: `onStep` and `progress` are called on the calling thread, in step order; the next
// steps are loaded and extracted meanwhile on other threads (oneTBB tasks), so `load` may be called
// from any thread, for a few steps at once. `cancel` may be set from any thread.
#pragma once

#include "dataset/dataset.h"
#include "analysis/features.h"
#include "analysis/flux.h"

#include <atomic>
#include <functional>
#include <memory>
#include <optional>
#include <span>
#include <string>
#include <string_view>
#include <vector>

namespace raypc::analysis {

// A step's volume, as the caller loads it (e.g. Dataset::load at a level). May throw raypc::Error.
using StepVolumeLoader = std::function<std::shared_ptr<const dataset::StepVolume>(int step)>;

// One step's features with the volume they were extracted from. The callback may move from them
// (e.g. keep the labels for linking to the next step).
struct FeatureStep {
    int step = 0;
    std::shared_ptr<const dataset::StepVolume> volume;
    StepFeatures features;
};

struct FeatureRunControl {
    // Checked before each step; a run it stops calls neither the step nor the last progress.
    const std::atomic<bool>* cancel = nullptr;
    // Steps done of all, before each step (0 before the first) and once more after the last.
    std::function<void(int done, int total)> progress;
};

// Loads, extracts (extractFeatures with `filters` and `options`) and hands to `onStep` every step
// of first..last in order (a step's load and extraction may run before the previous steps' onStep).
// Returns the step at which `cancel` stopped the run, or nullopt when every
// step was done. Throws what `load`, extractFeatures and `onStep` throw.
std::optional<int> forEachStepFeatures(int first, int last, const StepVolumeLoader& load,
                                       std::span<const RangeFilter> filters, const FeatureOptions& options,
                                       const std::function<void(FeatureStep&)>& onStep,
                                       const FeatureRunControl& control = {});

// What a block of steps finds besides the features.
struct FeatureBlockOptions {
    // Link each step's features to the previous step's (linkFeatures over the steps' interval) from
    // `linkFrom` on; a block beginning after it extracts the features of the step before it again to
    // link its first step. nullopt: no links.
    std::optional<VelocityVariables> velocity;
    int linkFrom = 0;
    // The flux across the shells at these depths (shellFluxes of the filters, with `density` for the
    // mass flux), when `radialVelocity` is given and the depths are not empty.
    std::optional<size_t> radialVelocity, density;
    std::vector<double> fluxDepthsKm;
};

// One step of a block: its features (with their labels while onStep runs; packing leaves them out),
// the links from the previous step's and the fluxes.
struct FeatureBlockStep {
    int step = 0;
    StepFeatures features;
    std::vector<FeatureLink> links;
    std::vector<ShellFlux> fluxes;
};

// forEachStepFeatures over first..last of `dataset` with the links and fluxes `block` asks for,
// each step handed to `onStep` in order (it may copy the labels but not take them: the next step is
// linked to them). Returns and throws as forEachStepFeatures; a cancel before the step before the
// block is extracted returns `first`.
std::optional<int> forEachBlockStep(const dataset::Dataset& dataset, int first, int last, const StepVolumeLoader& load,
                                    std::span<const RangeFilter> filters, const FeatureOptions& options,
                                    const FeatureBlockOptions& block, const std::function<void(const FeatureBlockStep&)>& onStep,
                                    const FeatureRunControl& control = {});

// A block's steps as bytes for another process of the same build (numbers as in memory), labels
// left out: append each step, then unpack them all. Unpacking throws raypc::Error for bytes that end
// early or do not end where a step does.
void packBlockStep(std::string& out, const FeatureBlockStep& step);
std::vector<FeatureBlockStep> unpackBlockSteps(std::string_view bytes);

}  // namespace raypc::analysis
