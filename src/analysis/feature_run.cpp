#include "analysis/feature_run.h"

namespace raypc::analysis {

std::optional<int> forEachStepFeatures(int first, int last, const StepVolumeLoader& load,
                                       std::span<const RangeFilter> filters, const FeatureOptions& options,
                                       const std::function<void(FeatureStep&)>& onStep,
                                       const FeatureRunControl& control)
{
    const auto cancelled = [&] { return control.cancel && control.cancel->load(); };
    const int total = last - first + 1;
    for (int step = first; step <= last; ++step) {
        if (cancelled())
            return step;
        if (control.progress) {
            control.progress(step - first, total);
            // Again after the progress: reporting it may be what cancels (Python's callback raising).
            if (cancelled())
                return step;
        }
        FeatureStep s{step, load(step), {}};
        s.features = extractFeatures(*s.volume, filters, options);
        onStep(s);
    }
    if (control.progress)
        control.progress(total, total);
    return std::nullopt;
}

}  // namespace raypc::analysis
