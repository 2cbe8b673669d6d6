#include "analysis/pathlines.h"

#include "core/error.h"

#include <tbb/parallel_for.h>

#include <algorithm>
#include <cmath>

namespace raypc::analysis {
namespace {

namespace fs = std::filesystem;

// Dormand–Prince 5(4) tableau (Hairer, Nørsett & Wanner, Table II.5.2).
constexpr double kC[7] = {0, 1.0 / 5, 3.0 / 10, 4.0 / 5, 8.0 / 9, 1, 1};
constexpr double kA[7][6] = {
    {},
    {1.0 / 5},
    {3.0 / 40, 9.0 / 40},
    {44.0 / 45, -56.0 / 15, 32.0 / 9},
    {19372.0 / 6561, -25360.0 / 2187, 64448.0 / 6561, -212.0 / 729},
    {9017.0 / 3168, -355.0 / 33, 46732.0 / 5247, 49.0 / 176, -5103.0 / 18656},
    {35.0 / 384, 0, 500.0 / 1113, 125.0 / 192, -2187.0 / 6784, 11.0 / 84},
};
// 5th-order weights minus the embedded 4th-order ones: the local error estimate.
constexpr double kE[7] = {71.0 / 57600,      0, -71.0 / 16695, 71.0 / 1920, -17253.0 / 339200,
                          22.0 / 525, -1.0 / 40};

}  // namespace

// --- Tracer ----------------------------------------------------------------------------------

PathlineTracer::PathlineTracer(const FieldSeries& series, size_t vx, size_t vy, size_t vz, TracerOptions options)
    : m_series(series), m_sampler(series.grid), m_v{vx, vy, vz}, m_options(options)
{
    if (series.timesMyr.empty() || series.stepCount() != series.timesMyr.size())
        fail("pathlines: {} step times for {} steps of fields", series.timesMyr.size(), series.stepCount());
    for (size_t k = 1; k < series.timesMyr.size(); ++k)
        if (!(series.timesMyr[k] > series.timesMyr[k - 1]))
            fail("pathlines: step times are not ascending ({} then {} Myr)", series.timesMyr[k - 1],
                 series.timesMyr[k]);
    for (size_t k = 0; k < series.stepCount(); ++k)
        for (size_t v : m_v)
            if (v >= series.variableCount(k))
                fail("pathlines: velocity component {} out of range, a step has {} fields", v,
                     series.variableCount(k));
    if (!(options.toleranceKm > 0 && options.maxStepMyr > 0 && options.maxSegmentKm > 0 && options.maxPoints >= 2))
        fail("pathlines: tolerance, step, segment and point limits must be positive");
    for (const auto& volume : series.volumes)
        m_velocity.push_back({volume->pointValues(vx), volume->pointValues(vy), volume->pointValues(vz)});
    m_rMinKm = series.grid.rKm.front();
    m_rMaxKm = series.grid.rKm.back();
    // Integration error moves a particle that rides on a boundary slightly off it; within this
    // distance it still counts as inside (and samples the boundary).
    double minDr = m_rMaxKm - m_rMinKm;
    for (size_t i = 1; i < series.grid.nR(); ++i)
        minDr = std::min(minDr, series.grid.rKm[i] - series.grid.rKm[i - 1]);
    m_rToleranceKm = 1e-3 * minDr;
}

std::optional<grid::GridSampler::Location> PathlineTracer::locate(const Vec3d& pKm) const
{
    const SphericalPoint s = cartesianToSpherical(pKm);
    if (!(s.rKm >= m_rMinKm - m_rToleranceKm && s.rKm <= m_rMaxKm + m_rToleranceKm))
        return std::nullopt;
    return m_sampler.locate(s.latDeg, s.lonDeg, std::clamp(s.rKm, m_rMinKm, m_rMaxKm));
}

void PathlineTracer::bracketTime(double timeMyr, size_t& k0, size_t& k1, double& w) const
{
    const auto& t = m_series.timesMyr;
    if (t.size() == 1 || timeMyr <= t.front()) {
        k0 = k1 = 0;
        w = 0;
        return;
    }
    if (timeMyr >= t.back()) {
        k0 = k1 = t.size() - 1;
        w = 0;
        return;
    }
    k1 = static_cast<size_t>(std::upper_bound(t.begin(), t.end(), timeMyr) - t.begin());
    k0 = k1 - 1;
    w = (timeMyr - t[k0]) / (t[k1] - t[k0]);
}

std::optional<Vec3d> PathlineTracer::velocityKmPerMyr(const Vec3d& pKm, double timeMyr) const
{
    const auto at = locate(pKm);
    if (!at)
        return std::nullopt;
    size_t k0, k1;
    double w;
    bracketTime(timeMyr, k0, k1, w);
    double v[3];
    for (int c = 0; c < 3; ++c) {
        double a, b;
        if (m_velocity.empty()) {
            a = m_sampler.sample(m_series.field(k0, m_v[c]), *at);
            b = w > 0 ? m_sampler.sample(m_series.field(k1, m_v[c]), *at) : a;
        } else {
            const grid::SphericalGrid& g = m_series.grid;
            const auto& p0 = m_velocity[k0][size_t(c)];
            const auto& p1 = m_velocity[k1][size_t(c)];
            a = m_sampler.sample([&](size_t i, size_t j, size_t k) { return p0.at(g.index(i, j, k), i, j, k); }, *at);
            b = w > 0 ? m_sampler.sample([&](size_t i, size_t j, size_t k) { return p1.at(g.index(i, j, k), i, j, k); }, *at)
                      : a;
        }
        v[c] = (a + (b - a) * w) * kMpsToKmPerMyr;
    }
    return Vec3d{v[0], v[1], v[2]};
}

double PathlineTracer::sample(size_t var, const Vec3d& pKm, double timeMyr) const
{
    const auto at = locate(pKm);
    if (!at)
        return NAN;
    size_t k0, k1;
    double w;
    bracketTime(timeMyr, k0, k1, w);
    // A few samples per line (its attributes): a u16 variable is not decoded for them.
    auto at0 = [&](size_t i, size_t j, size_t k) { return m_series.value(k0, var, i, j, k); };
    auto at1 = [&](size_t i, size_t j, size_t k) { return m_series.value(k1, var, i, j, k); };
    const double a = m_sampler.sample(at0, *at);
    const double b = w > 0 ? m_sampler.sample(at1, *at) : a;
    return a + (b - a) * w;
}

TracedPathline PathlineTracer::trace(const Vec3d& startKm, double startMyr, double endMyr) const
{
    PathlineTrace tr = begin(startKm, startMyr);
    if (!tr.done)
        advance(tr, endMyr, endMyr);
    return std::move(tr.line);
}

PathlineTrace PathlineTracer::begin(const Vec3d& startKm, double startMyr) const
{
    PathlineTrace tr;
    tr.line.pointsKm.push_back(startKm);
    tr.line.timesMyr.push_back(startMyr);
    const auto k1 = velocityKmPerMyr(startKm, startMyr);
    if (!k1) {
        tr.line.end = PathlineEnd::LeftShell;
        tr.done = true;
        return tr;
    }
    tr.velocityKmPerMyr = *k1;
    tr.nextStepMyr = m_options.maxStepMyr;
    return tr;
}

void PathlineTracer::advance(PathlineTrace& tr, double untilMyr, double endMyr) const
{
    if (tr.done)
        return;
    TracedPathline& line = tr.line;
    auto finish = [&](PathlineEnd end) {
        line.end = end;
        tr.done = true;
    };
    const auto& times = m_series.timesMyr;
    const double timeEps = 1e-9 * std::max(1.0, std::abs(endMyr));

    // Strictly inside the shell. A point riding on a boundary may drift past it by up to
    // m_rToleranceKm through integration error and still be sampled (r clamped); a point strictly
    // inside must stay strictly inside, so that an exit is found on the boundary itself.
    auto strictlyInside = [&](const Vec3d& x) {
        const double r = length(x);
        return r >= m_rMinKm && r <= m_rMaxKm;
    };
    // One Dormand–Prince step of size h from (p, t) with k[0] = v(p, t); false when a stage leaves
    // the shell. On success k[6] = v(p5, t + h) (first-same-as-last) and `error` is the local
    // error estimate in km.
    Vec3d k[7];
    auto attempt = [&](const Vec3d& p, double t, double h, Vec3d& p5, double& error) {
        const bool strict = strictlyInside(p);
        for (int s = 1; s < 7; ++s) {
            Vec3d x = p;
            for (int j = 0; j < s; ++j)
                x = x + (h * kA[s][j]) * k[j];
            if (s == 6)
                p5 = x;  // row 7 of the tableau is the 5th-order solution
            if (strict && !strictlyInside(x))
                return false;
            const auto v = velocityKmPerMyr(x, t + kC[s] * h);
            if (!v)
                return false;
            k[s] = *v;
        }
        Vec3d e{};
        for (int s = 0; s < 7; ++s)
            e = e + (h * kE[s]) * k[s];
        error = length(e);
        return true;
    };
    auto factor = [&](double error) {
        // Standard controller with safety factor 0.9 and growth limited to [0.2, 5].
        return error <= 0 ? 5.0 : std::clamp(0.9 * std::pow(m_options.toleranceKm / error, 0.2), 0.2, 5.0);
    };

    Vec3d p = line.pointsKm.back();
    double t = line.timesMyr.back();
    double h = tr.nextStepMyr;
    k[0] = tr.velocityKmPerMyr;
    // Save the state for the next call (a line that ended needs none).
    auto pause = [&] {
        tr.velocityKmPerMyr = k[0];
        tr.nextStepMyr = h;
    };
    const double stopMyr = std::min(untilMyr, endMyr);
    while (t < stopMyr - timeEps) {
        if (line.pointsKm.size() >= m_options.maxPoints) {
            finish(PathlineEnd::PointLimit);
            return;
        }
        // Land exactly on the next step time (velocity is only piecewise linear in time) and keep
        // stored points close enough for smooth tubes.
        const auto next = std::upper_bound(times.begin(), times.end(), t + timeEps);
        const double stepEnd = next == times.end() ? endMyr : std::min(endMyr, *next);
        const double speed = length(k[0]);
        double cap = std::min({m_options.maxStepMyr, stepEnd - t});
        if (speed > 0)
            cap = std::min(cap, m_options.maxSegmentKm / speed);
        h = std::min(h, cap);

        Vec3d p5;
        double error = 0;
        if (!attempt(p, t, h, p5, error)) {
            // A stage left the shell: bisect the step for the largest one that stays inside.
            double lo = 0, hi = h, loError = 0;
            Vec3d loP{};
            for (int i = 0; i < 60 && hi - lo > 1e-10 * std::max(1.0, h); ++i) {
                const double mid = 0.5 * (lo + hi);
                Vec3d pm;
                double em = 0;
                if (attempt(p, t, mid, pm, em)) {
                    lo = mid;
                    loP = pm;
                    loError = em;
                } else {
                    hi = mid;
                }
            }
            if (lo > 0 && loError <= m_options.toleranceKm) {
                // A point that drifted within the tolerance past a boundary ends on it.
                const double r = length(loP), rb = std::clamp(r, m_rMinKm, m_rMaxKm);
                loP = (rb / r) * loP;
                line.lengthKm += length(loP - p);
                line.pointsKm.push_back(loP);
                line.timesMyr.push_back(t + lo);
                finish(PathlineEnd::LeftShell);
                return;
            }
            if (lo <= 0) {
                finish(PathlineEnd::LeftShell);
                return;
            }
            // The exit step is not accurate enough: shorten and try again.
            h = lo * factor(loError);
            continue;
        }
        if (error <= m_options.toleranceKm) {
            t = h >= stepEnd - t ? stepEnd : t + h;
            line.lengthKm += length(p5 - p);
            p = p5;
            k[0] = k[6];
            line.pointsKm.push_back(p);
            line.timesMyr.push_back(t);
        }
        h *= factor(error);
    }
    if (t >= endMyr - timeEps)
        finish(PathlineEnd::ReachedEndTime);
    else
        pause();
}

// --- Tracing a set ---------------------------------------------------------------------------

int PathlineSet::column(const std::string& name) const
{
    for (size_t i = 0; i < columns.size(); ++i)
        if (columns[i] == name)
            return static_cast<int>(i);
    return -1;
}

std::vector<std::string> pathlineColumns(const std::vector<std::string>& variableNames)
{
    std::vector<std::string> columns;
    for (const columns::TableColumn& c : kPathlineFixedColumns)
        columns.push_back(c.name);
    for (const char* prefix : columns::kPathlineVariablePrefixes)
        for (const auto& name : variableNames)
            columns.push_back(prefix + name);
    return columns;
}

PathlineSet emptyPathlineSet(int injectionStep, double injectionTimeMyr, int endStep,
                             const std::vector<std::string>& names, const std::vector<std::string>& units)
{
    RAYPC_CHECK_EQ(names.size(), units.size());
    PathlineSet set;
    set.injectionStep = injectionStep;
    set.injectionTimeMyr = injectionTimeMyr;
    set.endStep = endStep;
    set.columns = pathlineColumns(names);
    for (const columns::TableColumn& c : kPathlineFixedColumns)
        set.units.push_back(c.units);
    for (size_t side = 0; side < columns::kPathlineVariablePrefixes.size(); ++side)
        set.units.insert(set.units.end(), units.begin(), units.end());
    set.offsets.push_back(0);
    return set;
}

std::vector<float> sampleVariables(const PathlineTracer& tracer, size_t variableCount, const Vec3d& pKm, double timeMyr)
{
    std::vector<float> values(variableCount);
    for (size_t v = 0; v < variableCount; ++v)
        values[v] = static_cast<float>(tracer.sample(v, pKm, timeMyr));
    return values;
}

void appendPathline(PathlineSet& set, const CriticalPoint& seed, const TracedPathline& line,
                    std::span<const float> startValues, std::span<const float> endValues)
{
    const size_t nc = set.columns.size();
    RAYPC_CHECK_EQ(kPathlineFixedColumnCount + startValues.size() + endValues.size(), nc);
    for (size_t j = 0; j < line.pointsKm.size(); ++j) {
        const Vec3d& p = line.pointsKm[j];
        for (double x : {p.x, p.y, p.z, line.timesMyr[j]})
            set.points.push_back(static_cast<float>(x));
    }
    set.offsets.push_back(static_cast<uint32_t>(set.pointCount()));
    const Vec3d a = line.pointsKm.front(), b = line.pointsKm.back();
    const double ta = line.timesMyr.front(), tb = line.timesMyr.back();
    const SphericalPoint sa = cartesianToSpherical(a), sb = cartesianToSpherical(b);
    // A seed without a persistence (chosen by hand, or by a rule that computed none) gets 0.
    const double persistence = std::isnan(seed.persistence) ? 0.0 : seed.persistence;
    const double fixed[] = {static_cast<double>(seed.kind), seed.value, persistence, set.injectionTimeMyr, tb - ta,
                            line.lengthKm, static_cast<double>(line.end), sa.latDeg, sa.lonDeg, sa.rKm,
                            sb.latDeg, sb.lonDeg, sb.rKm};
    static_assert(sizeof(fixed) / sizeof(fixed[0]) == kPathlineFixedColumnCount);
    for (double x : fixed)
        set.attributes.push_back(static_cast<float>(x));
    set.attributes.insert(set.attributes.end(), startValues.begin(), startValues.end());
    set.attributes.insert(set.attributes.end(), endValues.begin(), endValues.end());
}

PathlineSet tracePathlines(const FieldSeries& series, const PathlineTracer& tracer,
                           const std::vector<CriticalPoint>& seeds, int injectionStep, int endStep,
                           const std::vector<std::string>& names, const std::vector<std::string>& units)
{
    RAYPC_CHECK(injectionStep >= 0 && endStep >= injectionStep &&
                endStep < static_cast<int>(series.timesMyr.size()));
    PathlineSet set = emptyPathlineSet(injectionStep, series.timesMyr[injectionStep], endStep, names, units);
    const double t0 = series.timesMyr[injectionStep], t1 = series.timesMyr[endStep];
    std::vector<TracedPathline> lines(seeds.size());
    tbb::parallel_for(size_t(0), seeds.size(), [&](size_t i) {
        const auto& s = seeds[i];
        lines[i] = tracer.trace(sphericalToCartesianKm(s.latDeg, s.lonDeg, s.rKm), t0, t1);
    });
    for (size_t i = 0; i < seeds.size(); ++i) {
        const auto& line = lines[i];
        appendPathline(set, seeds[i], line,
                       sampleVariables(tracer, names.size(), line.pointsKm.front(), line.timesMyr.front()),
                       sampleVariables(tracer, names.size(), line.pointsKm.back(), line.timesMyr.back()));
    }
    return set;
}

}  // namespace raypc::analysis
