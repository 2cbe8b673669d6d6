// The difference of two datasets, D = A − B, or of one dataset's steps, D(t) = X(t) − X(t−k): a
// source of steps (preprocess.h, StepSource) that the one dataset pipeline turns into a dataset like
// any other (docs/compare.md, "Differences").
//
// D is on A's grid: B's values at A's grid points through grid::regrid (the sampler's rule; the same
// grid is copied point for point), NaN where B has no data; a missing value stays missing
// (NaN − x = NaN). Values are read from level 0 as the datasets give them (a u16 dataset's decoded
// values). D keeps the variables' names and units, so brushes, presets and transfer functions apply;
// each variable's long_name says what it is the difference of. Derived variables are derived again
// from the differences (radial velocity is linear in vx, vy, vz: it is the difference of the radial
// velocities; the velocity magnitude is |vA − vB|, the magnitude of the difference, so named).
//
// Thread safety: a DifferenceSource reads its datasets (immutable) and may be read from any thread.
#pragma once

#include "dataset/dataset.h"
#include "preprocess/preprocess.h"

#include <filesystem>
#include <memory>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

namespace raypc::preprocess {

// How the steps of A and B are paired: by index (the counts must agree), or by time (each step of A
// with B's step at the same time, within kTimeToleranceFraction of A's step interval).
enum class StepMatch { Index, Time };
StepMatch parseStepMatch(std::string_view text, std::string_view what);
std::string_view stepMatchName(StepMatch match);

// Times that agree within this fraction of A's step interval (dt_myr) are the same time.
inline constexpr double kTimeToleranceFraction = 1e-3;

struct DifferenceRequest {
    std::filesystem::path a;
    // The dataset subtracted; empty for step differences of `a` (stepLag).
    std::filesystem::path b;
    // The variables to difference; empty: the stored ones both have (derived ones are derived again).
    std::vector<std::string> variables;
    StepMatch match = StepMatch::Index;
    // k > 0 with `b` empty: D(t) = A(t) − A(t − k) for the steps t ≥ k, at A(t)'s time.
    int stepLag = 0;
};

class DifferenceSource final : public StepSource {
public:
    // Opens both datasets and checks the request: throws raypc::Error naming what is wrong for grids
    // that do not overlap (grid::coveredFraction 0), no variable in common, a named variable one of them
    // lacks or computes when read, units that differ, step counts that differ (by index), a step of A
    // without a step of B at its time (by time: the first one), a step lag out of range, or both a
    // dataset B and a step lag (or neither).
    explicit DifferenceSource(const DifferenceRequest& request);

    size_t stepCount() const override { return m_pairs.size(); }
    std::string path(size_t s) const override;
    std::string label(size_t s) const override;
    io::FileHeader plan() override;
    grid::Snapshot read(size_t s) const override;
    nlohmann::json fingerprint(size_t s) const override;
    std::string describeKey() const override { return "difference"; }
    nlohmann::json describe() const override;
    std::string derivedLongName(const std::string& name) const override;

    // D's step times (A's), in step order.
    std::vector<double> timesMyr() const;
    // The fraction of A's grid B covers with data (grid::coveredFraction), in (0, 1].
    double coveredFraction() const { return m_covered; }
    // The variables differenced, in A's order (D's stored variables before the derived ones).
    const std::vector<std::string>& variables() const { return m_variables; }
    const dataset::Dataset& a() const { return *m_a; }

private:
    std::string aName() const;
    std::string bName() const;
    std::string whatOf() const;  // "A − B" or "A: step t − step t−k", for long names

    DifferenceRequest m_request;
    std::shared_ptr<const dataset::Dataset> m_a, m_b;
    std::vector<std::string> m_variables;
    std::vector<std::pair<int, int>> m_pairs;  // per step of D: (A's step, B's step)
    double m_covered = 1;
};

// Preprocesses request's difference into `outDir` through the one pipeline (preprocess.h; resumable,
// locked, written atomically as any dataset): D's times are A's, its step interval A's, and it has no
// pathlines (the manifest's no_pathlines says why). Throws raypc::Error as DifferenceSource and
// preprocess() do.
PreprocessSummary preprocessDifference(const DifferenceRequest& request, const std::filesystem::path& outDir,
                                       const PreprocessOptions& options);

}  // namespace raypc::preprocess
