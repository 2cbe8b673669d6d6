#include "preprocess/difference.h"

#include "core/error.h"
#include "core/error_kinds.h"
#include "dataset/dataset_format.h"
#include "grid/regrid.h"
#include "grid/variable_names.h"
#include "preprocess/preprocess_phases.h"

#include <fmt/format.h>
#include <fmt/ranges.h>
#include <spdlog/spdlog.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <utility>

namespace raypc::preprocess {
namespace {

namespace fs = std::filesystem;
using nlohmann::json;

// A dataset's name in labels: its directory's name ("run1.ds"), also when given with a trailing '/'.
std::string dirName(const fs::path& dir)
{
    const fs::path normal = dir.lexically_normal();
    return normal.has_filename() ? normal.filename().string() : normal.parent_path().filename().string();
}

std::string absoluteName(const fs::path& dir)
{
    std::error_code ec;
    const fs::path canonical = fs::weakly_canonical(dir, ec);
    return (ec ? fs::absolute(dir).lexically_normal() : canonical).string();
}

const dataset::VariableInfo* findVariable(const dataset::Dataset& d, const std::string& name)
{
    const int i = d.variableIndex(name);
    return i < 0 ? nullptr : &d.variables()[size_t(i)];
}

// The variables both datasets store, in A's order: the ones read from the inputs (the derived ones
// are derived again from the differences).
std::vector<std::string> commonStored(const dataset::Dataset& a, const dataset::Dataset& b)
{
    std::vector<std::string> names;
    for (const dataset::VariableInfo& v : a.variables()) {
        const dataset::VariableInfo* other = findVariable(b, v.name);
        if (v.stored && !v.derived && other && other->stored)
            names.push_back(v.name);
    }
    return names;
}

// Where a grid holds data, for messages: "lat -90..90 deg, lon 0..359 deg, r 3485..6371 km".
std::string extentText(const grid::SphericalGrid& g)
{
    const auto lat = g.dataLatDeg.value_or(std::array<double, 2>{g.latDeg.front(), g.latDeg.back()});
    const auto lon = g.dataLonDeg.value_or(std::array<double, 2>{g.lonDeg.front(), g.lonDeg.back()});
    return fmt::format("lat {:g}..{:g} deg, lon {:g}..{:g} deg, r {:g}..{:g} km", lat[0], lat[1], lon[0], lon[1],
                       g.rKm.front(), g.rKm.back());
}

}  // namespace

StepMatch parseStepMatch(std::string_view text, std::string_view what)
{
    if (text == "index")
        return StepMatch::Index;
    if (text == "time")
        return StepMatch::Time;
    fail("{}: '{}', expected 'index' or 'time'", what, text);
}

std::string_view stepMatchName(StepMatch match)
{
    return match == StepMatch::Index ? "index" : "time";
}

DifferenceSource::DifferenceSource(const DifferenceRequest& request) : m_request(request)
{
    const bool lag = request.b.empty();
    if (lag && request.stepLag <= 0)
        fail("diff: give a dataset B to subtract from {}, or --steps k for the differences of its steps",
             request.a.string());
    if (!lag && request.stepLag != 0)
        fail("diff: give a dataset B or --steps k, not both (B is {})", request.b.string());
    m_a = dataset::Dataset::open(request.a);
    m_b = lag ? m_a : dataset::Dataset::open(request.b);
    const dataset::Dataset &a = *m_a, &b = *m_b;
    const grid::SphericalGrid& gridA = a.levels().front().grid;
    const grid::SphericalGrid& gridB = b.levels().front().grid;

    // The grids: B must cover some of A's grid; the rest of D is missing.
    m_covered = grid::coveredFraction(gridB, gridA);
    if (!(m_covered > 0))
        fail("diff: the grids of {} ({}) and {} ({}) do not overlap: no point of {} has a value of {}", aName(),
             extentText(gridA), bName(), extentText(gridB), aName(), bName());

    // The variables: the ones named (stored in both, with the same units), else the stored ones both have.
    if (request.variables.empty()) {
        m_variables = commonStored(a, b);
        if (m_variables.empty())
            fail("diff: {} and {} have no stored variable in common ({}: {}; {}: {})", aName(), bName(), aName(),
                 fmt::join(a.variableNames(), ", "), bName(), fmt::join(b.variableNames(), ", "));
    } else {
        const auto named = [&](const char* n) {
            return std::find(request.variables.begin(), request.variables.end(), n) != request.variables.end();
        };
        for (const dataset::VariableInfo& v : a.variables()) {
            if (std::find(request.variables.begin(), request.variables.end(), v.name) == request.variables.end())
                continue;
            // A derived variable whose inputs are differenced too is derived again from them.
            if (v.stored && v.derived && varname::hasVelocity(named))
                continue;
            m_variables.push_back(v.name);
        }
        for (const std::string& name : request.variables) {
            for (const auto& [d, which] : {std::pair{m_a, aName()}, std::pair{m_b, bName()}}) {
                const dataset::VariableInfo* v = findVariable(*d, name);
                if (!v)
                    throw UnknownNameError(fmt::format("diff: variable '{}': {} has no such variable (it has {})", name,
                                                       which, fmt::join(d->variableNames(), ", ")));
                if (!v->stored)
                    fail("diff: variable '{}' is computed from '{}' when {} is read; name '{}' (the difference's own "
                         "'{}' is computed from it)",
                         name, v->source, which, v->source, name);
            }
        }
    }
    for (const std::string& name : m_variables) {
        const dataset::VariableInfo *va = findVariable(a, name), *vb = findVariable(b, name);
        if (va->units != vb->units)
            fail("diff: variable '{}' is in {} in {} but in {} in {}; a difference needs the same units", name,
                 va->units, aName(), vb->units, bName());
    }

    // The steps: pairs (step of A, step of B).
    const int nA = int(a.steps().size()), nB = int(b.steps().size());
    if (lag) {
        if (request.stepLag >= nA)
            throw OutOfRangeError(fmt::format("--steps: {} out of range 1..{} ({} has {} steps)", request.stepLag,
                                              nA - 1, aName(), nA));
        for (int t = request.stepLag; t < nA; ++t)
            m_pairs.emplace_back(t, t - request.stepLag);
        return;
    }
    const double tolerance = kTimeToleranceFraction * a.dtMyr();
    if (request.match == StepMatch::Index) {
        if (nA != nB)
            fail("diff: {} has {} steps and {} has {}; --match index pairs steps by index (--match time pairs them "
                 "by time)",
                 aName(), nA, bName(), nB);
        bool warned = false;
        for (int s = 0; s < nA; ++s) {
            m_pairs.emplace_back(s, s);
            const double tA = a.steps()[size_t(s)].timeMyr, tB = b.steps()[size_t(s)].timeMyr;
            if (std::abs(tA - tB) > tolerance && !std::exchange(warned, true))
                spdlog::warn("diff: step {} is at {:g} Myr in {} and at {:g} Myr in {}; paired by index, D's steps "
                             "have {}'s times",
                             s, tA, aName(), tB, bName(), aName());
        }
        return;
    }
    for (int s = 0; s < nA; ++s) {
        const double tA = a.steps()[size_t(s)].timeMyr;
        int best = 0;
        for (int j = 1; j < nB; ++j)
            if (std::abs(b.steps()[size_t(j)].timeMyr - tA) < std::abs(b.steps()[size_t(best)].timeMyr - tA))
                best = j;
        const double tB = b.steps()[size_t(best)].timeMyr;
        if (std::abs(tB - tA) > tolerance)
            fail("diff: {} has no step at {}'s step {} ({:g} Myr): its nearest is step {} at {:g} Myr (times agree "
                 "within {:g} Myr, {:g} of {}'s step interval)",
                 bName(), aName(), s, tA, best, tB, tolerance, kTimeToleranceFraction, aName());
        m_pairs.emplace_back(s, best);
    }
}

std::string DifferenceSource::aName() const { return dirName(m_request.a); }
std::string DifferenceSource::bName() const { return m_request.b.empty() ? aName() : dirName(m_request.b); }

std::string DifferenceSource::whatOf() const
{
    if (m_request.b.empty())
        return fmt::format("{}: step t − step t−{}", aName(), m_request.stepLag);
    return fmt::format("{} − {}", aName(), bName());
}

std::string DifferenceSource::path(size_t s) const
{
    return fmt::format("{} step {} − {} step {}", m_request.a.string(), m_pairs[s].first,
                       (m_request.b.empty() ? m_request.a : m_request.b).string(), m_pairs[s].second);
}

std::string DifferenceSource::label(size_t s) const
{
    return fmt::format("{}:{} − {}:{}", aName(), m_pairs[s].first, bName(), m_pairs[s].second);
}

std::vector<double> DifferenceSource::timesMyr() const
{
    std::vector<double> times;
    for (const auto& [sa, sb] : m_pairs)
        times.push_back(m_a->steps()[size_t(sa)].timeMyr);
    return times;
}

io::FileHeader DifferenceSource::plan()
{
    io::FileHeader header;
    header.grid = m_a->levels().front().grid;
    header.format = "RayPC dataset difference";
    header.steps = m_pairs.size();
    for (const std::string& name : m_variables) {
        const dataset::VariableInfo& v = *findVariable(*m_a, name);
        header.variables.push_back({name, name, v.units, fmt::format("{} of {}", name, whatOf())});
    }
    return header;
}

grid::Snapshot DifferenceSource::read(size_t s) const
{
    const auto [sa, sb] = m_pairs[s];
    const auto volumeA = m_a->load(sa, 0), volumeB = m_b->load(sb, 0);
    const grid::SphericalGrid& gridA = m_a->levels().front().grid;
    const grid::SphericalGrid& gridB = m_b->levels().front().grid;
    grid::Snapshot snap;
    snap.grid = gridA;
    for (const std::string& name : m_variables) {
        const float* a = volumeA->values(size_t(m_a->variableIndex(name)));
        // B's values at A's grid points (the same grid: copied), NaN where B has no data.
        std::vector<float> values = grid::regrid(gridB, volumeB->values(size_t(m_b->variableIndex(name))), gridA);
        // A missing value on either side stays missing: NaN − x = NaN.
        tbb::parallel_for(tbb::blocked_range<size_t>(0, values.size()), [&](const tbb::blocked_range<size_t>& r) {
            for (size_t i = r.begin(); i < r.end(); ++i)
                values[i] = a[i] - values[i];
        });
        snap.fields.push_back({name, m_a->variables()[size_t(m_a->variableIndex(name))].units, std::move(values)});
    }
    return snap;
}

json DifferenceSource::fingerprint(size_t s) const
{
    const auto [sa, sb] = m_pairs[s];
    return phases::filesFingerprint({dataset::format::stepDir(m_a->dir(), sa) / dataset::format::kStepManifest,
                                     dataset::format::stepDir(m_b->dir(), sb) / dataset::format::kStepManifest});
}

json DifferenceSource::describe() const
{
    json j{{"a", absoluteName(m_request.a)}, {"variables", m_variables}, {"covered_fraction", m_covered}};
    if (m_request.b.empty()) {
        j["b"] = nullptr;
        j["step_lag"] = m_request.stepLag;
    } else {
        j["b"] = absoluteName(m_request.b);
        j["match"] = stepMatchName(m_request.match);
    }
    j["pairs"] = json::array();
    for (const auto& [sa, sb] : m_pairs)
        j["pairs"].push_back({sa, sb});
    return j;
}

std::string DifferenceSource::derivedLongName(const std::string& name) const
{
    if (name == varname::kVelocityMagnitude)
        return fmt::format("magnitude of the velocity difference of {} (|vA − vB|, not |vA| − |vB|)", whatOf());
    return fmt::format("{} of {} (derived from the differences)", name, whatOf());
}

PreprocessSummary preprocessDifference(const DifferenceRequest& request, const fs::path& outDir,
                                       const PreprocessOptions& given)
{
    DifferenceSource source(request);
    PreprocessOptions options = given;
    options.timesMyr = source.timesMyr();
    options.dtMyr = source.a().dtMyr();
    options.pathlines.enabled = false;
    options.pathlines.absentBecause = "a difference dataset: its velocity is a difference of two flows, not a flow "
                                      "to trace";
    if (source.coveredFraction() < 1 && !options.quiet)
        spdlog::info("diff: {} covers {:.1f} % of {}'s grid; the rest of the difference is missing",
                     request.b.string(), 100 * source.coveredFraction(), request.a.string());
    return preprocess(source, outDir, options);
}

}  // namespace raypc::preprocess
