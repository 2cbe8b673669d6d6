#include "analysis/feature_run.h"

#include <tbb/task_group.h>

#include <deque>

namespace raypc::analysis {
namespace {

// Steps in flight, the one to hand to onStep next included: while the caller's thread waits for one
// step or takes its features (linking, flux, table rows), the next is extracted on another core.
constexpr size_t kStepsInFlight = 2;

// One step extracted on a task of its own.
struct Ahead {
    tbb::task_group group;
    FeatureStep step;
};

// The steps in flight; what a run leaves (an exception, a cancel) is waited for before it goes.
class StepsAhead {
public:
    ~StepsAhead()
    {
        for (auto& a : m_steps) {
            a->group.cancel();
            try {
                a->group.wait();
            } catch (...) {  // a step no one asks for any more: its error goes with it
            }
        }
    }
    void launch(int step, const StepVolumeLoader& load, std::span<const RangeFilter> filters, const FeatureOptions& options)
    {
        Ahead& a = *m_steps.emplace_back(std::make_unique<Ahead>());
        a.step.step = step;
        a.group.run([&a, step, &load, filters, &options] {
            a.step.volume = load(step);
            a.step.features = extractFeatures(*a.step.volume, filters, options);
        });
    }
    size_t size() const { return m_steps.size(); }
    // The oldest step, once extracted; throws what its load or extraction threw.
    FeatureStep next()
    {
        std::unique_ptr<Ahead> a = std::move(m_steps.front());
        m_steps.pop_front();
        a->group.wait();
        return std::move(a->step);
    }

private:
    std::deque<std::unique_ptr<Ahead>> m_steps;
};

}  // namespace

std::optional<int> forEachStepFeatures(int first, int last, const StepVolumeLoader& load,
                                       std::span<const RangeFilter> filters, const FeatureOptions& options,
                                       const std::function<void(FeatureStep&)>& onStep,
                                       const FeatureRunControl& control)
{
    const auto cancelled = [&] { return control.cancel && control.cancel->load(); };
    const int total = last - first + 1;
    StepsAhead ahead;
    int launched = first;
    for (int step = first; step <= last; ++step) {
        if (cancelled())
            return step;
        if (control.progress) {
            control.progress(step - first, total);
            // Again after the progress: reporting it may be what cancels (Python's callback raising).
            if (cancelled())
                return step;
        }
        while (launched <= last && ahead.size() < kStepsInFlight)
            ahead.launch(launched++, load, filters, options);
        FeatureStep s = ahead.next();
        onStep(s);
    }
    if (control.progress)
        control.progress(total, total);
    return std::nullopt;
}

}  // namespace raypc::analysis
