// Choosing the level of detail for a time budget, from predicted pass times and the measured
// throughput. StateRenderer::prepare chooses with chooseLevel (the one rule; the benchmarks call it
// too), the server keeps the throughput and a frame's overhead with averagedMeasure.
#pragma once

#include "dataset/dataset.h"

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
// pixels) fits. Used by chooseLevel.
inline int resolutionDivisor(double seconds, double budgetSeconds)
{
    return seconds <= budgetSeconds ? 1 : seconds / 4 <= budgetSeconds ? 2 : 4;
}

// The share of an interactive time budget the predicted pass time may use. The prediction counts
// samples; per-pixel work it does not model made real passes ~20% slower than predicted on the
// full-resolution benchmark (docs/rendering.md, "Measured choices"), so keep that much in reserve.
inline constexpr double kInteractiveBudgetShare = 0.75;

// The time one view's pass may take of an interactive frame's budget (`budgetMs`, the state's
// timeBudgetMs): kInteractiveBudgetShare of it, less the frame's measured time outside its pass
// (`overheadSeconds`: preparing, the picture and its JPEG, on the server), shared by `views` views
// (the eyes of a stereo pair). Whatever the overhead, at least a quarter of that share, so a slow
// encoder does not push every frame to the smallest size. On 2 cores shared with the browser the
// overhead was 10-16 ms of a 50 ms budget: counted, a drag's frames keep to the budget's rate
// (docs/rendering.md, "Measured choices").
inline double passBudgetSeconds(double budgetMs, double overheadSeconds, int views)
{
    const double share = kInteractiveBudgetShare * budgetMs / 1000.0;
    const double pass = share - overheadSeconds > 0.25 * share ? share - overheadSeconds : 0.25 * share;
    return pass / double(views > 0 ? views : 1);
}

// A level of detail and the image's size divisor per axis (1, 2 or 4).
struct LevelChoice {
    int level = 0;
    int divisor = 1;
};

// The finest of `levelCount` levels whose predicted pass (`samplesAt(level)` samples at
// `samplesPerSecond`) fits `budgetSeconds`; if none does, the coarsest, and with `reduceResolution`
// 1/2 or 1/4 of the pixels per axis (resolutionDivisor). `samplesAt` prepares a level's renderer
// when asked (coarse to fine, finestLevelWithin).
template <class SamplesAt>
LevelChoice chooseLevel(int levelCount, double budgetSeconds, double samplesPerSecond, bool reduceResolution,
                        SamplesAt&& samplesAt)
{
    const int fits =
        finestLevelWithin(levelCount, budgetSeconds, [&](int l) { return double(samplesAt(l)) / samplesPerSecond; });
    LevelChoice c{fits >= 0 ? fits : levelCount - 1, 1};
    if (fits < 0 && reduceResolution)
        c.divisor = resolutionDivisor(double(samplesAt(c.level)) / samplesPerSecond, budgetSeconds);
    return c;
}

// What the level choice predicts with (the throughput, in samples per second; a frame's time outside
// its pass, passBudgetSeconds): an exponential average of `measured` with `average` (0: none yet).
inline double averagedMeasure(double average, double measured)
{
    return average > 0 ? 0.7 * average + 0.3 * measured : measured;
}

}  // namespace raypc::render
