#include "analysis/feature_run.h"

#include "core/error.h"

#include <tbb/task_group.h>

#include <cstring>
#include <deque>
#include <type_traits>

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
            // Its points are read all over every variable: from disk, in large reads rather than a
            // small one per page fault (a new brush over 24 full-resolution steps not in the page
            // cache: docs/scaling.md).
            a.step.volume->adviseWillNeed();
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

std::optional<int> forEachBlockStep(const dataset::Dataset& dataset, int first, int last, const StepVolumeLoader& load,
                                    std::span<const RangeFilter> filters, const FeatureOptions& options,
                                    const FeatureBlockOptions& block, const std::function<void(const FeatureBlockStep&)>& onStep,
                                    const FeatureRunControl& control)
{
    const bool fluxes = block.radialVelocity && !block.fluxDepthsKm.empty();
    std::shared_ptr<const dataset::StepVolume> previousVolume;
    StepFeatures previous;  // labels only
    const auto timeOf = [&](int step) { return dataset.steps().at(size_t(step)).timeMyr; };
    if (block.velocity && first > block.linkFrom && first <= last) {
        if (control.cancel && control.cancel->load())
            return first;
        previousVolume = load(first - 1);
        previous.labels = extractFeatures(*previousVolume, filters, options).labels;
    }
    FeatureBlockStep out;
    return forEachStepFeatures(first, last, load, filters, options, [&](FeatureStep& s) {
        out.step = s.step;
        out.features = std::move(s.features);
        out.links.clear();
        if (block.velocity && previousVolume)
            out.links = linkFeatures(*previousVolume, previous, out.features, *block.velocity, timeOf(s.step) - timeOf(s.step - 1));
        out.fluxes.clear();
        if (fluxes)
            out.fluxes = shellFluxes(*s.volume, *block.radialVelocity, block.fluxDepthsKm, filters, std::nullopt, block.density);
        onStep(out);
        if (block.velocity) {
            previousVolume = std::move(s.volume);
            previous.labels = std::move(out.features.labels);
        }
    }, control);
}

namespace {

class Packer {
public:
    explicit Packer(std::string& out) : m_out(out) {}
    template <class T>
    void put(const T& value)
    {
        static_assert(std::is_trivially_copyable_v<T>);
        m_out.append(reinterpret_cast<const char*>(&value), sizeof(T));
    }
    template <class T>
    void putAll(const std::vector<T>& values)
    {
        put(uint64_t(values.size()));
        for (const T& v : values)
            put(v);
    }

private:
    std::string& m_out;
};

class Unpacker {
public:
    explicit Unpacker(std::string_view bytes) : m_bytes(bytes) {}
    bool done() const { return m_at == m_bytes.size(); }
    template <class T>
    T get()
    {
        static_assert(std::is_trivially_copyable_v<T>);
        if (m_bytes.size() - m_at < sizeof(T))
            fail("features: a block of steps' packed features ends early ({} of {} bytes)", m_at, m_bytes.size());
        T value;
        std::memcpy(&value, m_bytes.data() + m_at, sizeof(T));
        m_at += sizeof(T);
        return value;
    }
    template <class T>
    void getAll(std::vector<T>& values)
    {
        const uint64_t n = get<uint64_t>();
        if (n > (m_bytes.size() - m_at) / sizeof(T))
            fail("features: a block of steps' packed features ends early ({} items of {} bytes announced, {} bytes "
                 "left)", n, sizeof(T), m_bytes.size() - m_at);
        values.resize(size_t(n));
        for (T& v : values)
            v = get<T>();
    }

private:
    std::string_view m_bytes;
    size_t m_at = 0;
};

}  // namespace

void packBlockStep(std::string& out, const FeatureBlockStep& step)
{
    Packer p(out);
    p.put(int32_t(step.step));
    p.put(uint64_t(step.features.features.size()));
    for (const Feature& x : step.features.features) {
        p.put(int32_t(x.id));
        p.put(uint64_t(x.points));
        for (const double v : {x.volumeKm3, x.fractionOfMantle, x.topDepthKm, x.bottomDepthKm, x.centroidLatDeg,
                               x.centroidLonDeg, x.centroidDepthKm, x.meanDepthKm})
            p.put(v);
        p.putAll(x.variables);
        p.putAll(x.bandFractions);
    }
    p.putAll(step.links);
    p.putAll(step.fluxes);
}

std::vector<FeatureBlockStep> unpackBlockSteps(std::string_view bytes)
{
    Unpacker in(bytes);
    std::vector<FeatureBlockStep> steps;
    while (!in.done()) {
        FeatureBlockStep& s = steps.emplace_back();
        s.step = in.get<int32_t>();
        const uint64_t n = in.get<uint64_t>();
        for (uint64_t i = 0; i < n; ++i) {
            Feature& x = s.features.features.emplace_back();
            x.id = in.get<int32_t>();
            x.points = size_t(in.get<uint64_t>());
            for (double* v : {&x.volumeKm3, &x.fractionOfMantle, &x.topDepthKm, &x.bottomDepthKm, &x.centroidLatDeg,
                              &x.centroidLonDeg, &x.centroidDepthKm, &x.meanDepthKm})
                *v = in.get<double>();
            in.getAll(x.variables);
            in.getAll(x.bandFractions);
        }
        in.getAll(s.links);
        in.getAll(s.fluxes);
    }
    return steps;
}

}  // namespace raypc::analysis
