#include "render/level_choice.h"

#include "core/error.h"
#include "render/volume_renderer.h"

#include <algorithm>
#include <cmath>

namespace raypc::render {

InteractiveChoice chooseInteractive(const std::vector<std::shared_ptr<const StepVolume>>& levels,
                                    const RenderParams& params, double budgetSeconds, double samplesPerSecond)
{
    if (levels.empty())
        fail("level choice: no levels");
    const int coarsest = int(levels.size()) - 1;
    InteractiveChoice c{coarsest, params.width, params.height, 0};
    if (!(samplesPerSecond > 0))
        return c;
    std::vector<std::unique_ptr<VolumeRenderer>> renderers(levels.size());
    const int level = finestLevelWithin(
        int(levels.size()), kInteractiveBudgetShare * budgetSeconds,
        [&](int l) {
            auto& r = renderers[size_t(l)];
            if (!r)
                r = std::make_unique<VolumeRenderer>(levels[size_t(l)]);
            r->setParams(params);
            return r->estimateSamplesPerPass() / samplesPerSecond;
        },
        &c.estimatedSeconds);
    if (level >= 0) {
        c.level = level;
        return c;
    }
    // Even the coarsest level is too slow: fewer pixels.
    const int divisor = resolutionDivisor(c.estimatedSeconds, kInteractiveBudgetShare * budgetSeconds);
    c.width = std::max(1, (params.width + divisor - 1) / divisor);
    c.height = std::max(1, (params.height + divisor - 1) / divisor);
    c.estimatedSeconds *= double(c.width) * double(c.height) / (double(params.width) * double(params.height));
    return c;
}

}  // namespace raypc::render
