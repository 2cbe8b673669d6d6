// The features of a selection step after step: the one loop behind `raypc features` (a block of
// steps per MPI rank), the server's POST /api/features (through its step cache, cancellable, with
// the job's progress) and Python's Dataset.features. Each step's volume comes from the caller's
// loader, so each keeps its own way to load (Dataset::load, the server's shared cache); what a step's
// features become (table rows, links, tracks, flux) is the caller's callback.
//
// Thread safety: `onStep` and `progress` are called on the calling thread, in step order; the next
// steps are loaded and extracted meanwhile on other threads (oneTBB tasks), so `load` may be called
// from any thread, for a few steps at once. `cancel` may be set from any thread.
#pragma once

#include "dataset/dataset.h"
#include "analysis/features.h"

#include <atomic>
#include <functional>
#include <memory>
#include <optional>
#include <span>

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

}  // namespace raypc::analysis
