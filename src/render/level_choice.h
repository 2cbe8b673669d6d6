// Choosing the level of detail for a time budget, from predicted pass times.
// StateRenderer::prepare is the one caller on the path from a state to pixels; the benchmarks call
// chooseInteractive directly on in-memory volumes.
#pragma once

#include "data/dataset.h"

#include <memory>
#include <vector>

namespace raypc::render {

struct RenderParams;  // volume_renderer.h

// The finest of `levelCount` levels (0 finest) whose predicted pass time `secondsAt(level)` fits
// `budgetSeconds`, or -1 if even the coarsest does not. Levels are tried from the coarsest towards
// finer ones and the search stops at the first that misses (pass time grows with resolution), so the
// finer levels are not even prepared when the coarse ones are all that fit — during playback that
// spares loading and preparing the full-resolution step. `seconds` (optional) receives the prediction
// for the level returned, or for the coarsest level when none fits.
template <class SecondsAt>
int finestLevelWithin(int levelCount, double budgetSeconds, SecondsAt&& secondsAt, double* seconds = nullptr)
{
    int fits = -1;
    for (int level = levelCount - 1; level >= 0; --level) {
        const double s = secondsAt(level);
        if (s > budgetSeconds) {
            if (fits < 0 && seconds)
                *seconds = s;
            break;
        }
        fits = level;
        if (seconds)
            *seconds = s;
    }
    return fits;
}

// When even the coarsest level misses the budget: the image is rendered with 1/divisor of the pixels
// per axis and upscaled — 1, 2 or 4, the smallest whose predicted pass time (proportional to the
// pixels) fits. Used by StateRenderer::prepare and chooseInteractive.
inline int resolutionDivisor(double seconds, double budgetSeconds)
{
    return seconds <= budgetSeconds ? 1 : seconds / 4 <= budgetSeconds ? 2 : 4;
}

// What the interactive mode renders: a level and an internal image size (the requested size, or
// smaller when even the coarsest level would miss the budget; the caller upscales the result or
// asks for the smaller image), with the pass time predicted from the throughput.
struct InteractiveChoice {
    int level = 0;
    int width = 0, height = 0;
    double estimatedSeconds = 0;
};

// The share of an interactive time budget the predicted pass time may use. The prediction counts
// samples; per-pixel work it does not model made real passes ~20% slower than predicted on the
// full-resolution benchmark (docs/rendering.md, "Measured choices"), so keep that much in reserve.
inline constexpr double kInteractiveBudgetShare = 0.75;

// The finest level whose predicted pass time (estimateSamplesPerPass / samplesPerSecond) fits
// kInteractiveBudgetShare of `budgetSeconds`; if none does, the coarsest level at an internal resolution
// divided by resolutionDivisor. `samplesPerSecond` should be measured (measuredSamplesPerSecond of recent
// passes); without a measurement (<= 0) the coarsest level at full size is returned so that its
// pass measures the machine. `levels[i]` are the volumes of level i (finest first). Throws
// raypc::Error if `levels` is empty or the params are invalid.
InteractiveChoice chooseInteractive(const std::vector<std::shared_ptr<const StepVolume>>& levels,
                                    const RenderParams& params, double budgetSeconds, double samplesPerSecond);

}  // namespace raypc::render
