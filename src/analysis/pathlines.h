// Pathlines of the mantle flow, seeded at critical points of a scalar field (paper, "Data
// Preprocessing": seeds at critical points of the temperature anomaly, traced forward for 10
// steps), and their stored form (docs/format.md, "Pathlines").
//
// Conventions: positions are Cartesian km in the frame of core/spherical.h (x = r cos lat cos lon,
// y = r cos lat sin lon, z = r sin lat); lat/lon in degrees, r in km; time in Myr. Velocities on
// the grid are Cartesian components vx, vy, vz in m/s; 1 m/s = kSecondsPerMyr / 1000 km/Myr.
// Between grid points velocity is sampled by GridSampler (trilinear, lon seam, pole caps); between
// steps it is linear in time. Integrating in Cartesian coordinates has no pole singularity.
//
// Thread safety: PathlineTracer is immutable after construction and may be shared by threads.
#pragma once

#include "core/spherical.h"
#include "analysis/critical_points.h"
#include "dataset/dataset.h"
#include "grid/grid.h"
#include "grid/names.h"
#include "grid/sampler.h"

#include <array>
#include <cstdint>
#include <filesystem>
#include <memory>
#include <optional>
#include <span>
#include <string>
#include <vector>

namespace raypc::analysis {

inline constexpr double kMpsToKmPerMyr = kSecondsPerMyr / 1000.0;  // 3.15576e10

// Fields of several steps on one grid: fields[step][variable] points at grid.cellCount() values
// in canonical order (not owned); or, when `volumes` is set, each step's values come from its
// volume, so that a u16 dataset decodes only the arrays a trace reads (StepVolume::values).
struct FieldSeries {
    grid::SphericalGrid grid;
    std::vector<double> timesMyr;                  // ascending, one per step
    std::vector<std::vector<const float*>> fields;  // [step][variable]; empty when `volumes` is set
    std::vector<std::shared_ptr<const dataset::StepVolume>> volumes;  // [step]

    size_t stepCount() const { return volumes.empty() ? fields.size() : volumes.size(); }
    size_t variableCount(size_t step) const
    {
        return volumes.empty() ? fields[step].size() : volumes[step]->variableCount();
    }
    const float* field(size_t step, size_t variable) const
    {
        return volumes.empty() ? fields[step][variable] : volumes[step]->values(variable);
    }
    // One value, without decoding the whole variable (StepVolume::value).
    float value(size_t step, size_t variable, size_t iLat, size_t iR, size_t iLon) const
    {
        return volumes.empty() ? fields[step][variable][grid.index(iLat, iR, iLon)]
                               : volumes[step]->value(variable, iLat, iR, iLon);
    }
};

struct TracerOptions {
    double toleranceKm = 0.01;  // local error per step (Dormand–Prince embedded 4th-order estimate)
    double maxStepMyr = 0.5;    // also the longest time between two stored points
    double maxSegmentKm = 25;   // longest distance between two stored points, so tubes bend smoothly
    size_t maxPoints = 20000;   // a line stops when it has this many points
};

enum class PathlineEnd : uint8_t { ReachedEndTime = 0, LeftShell = 1, PointLimit = 2 };

struct TracedPathline {
    std::vector<Vec3d> pointsKm;
    std::vector<double> timesMyr;
    PathlineEnd end = PathlineEnd::ReachedEndTime;
    double lengthKm = 0;  // polyline length
};

// A line part way through its trace (PathlineTracer::begin, advance): the line so far and the
// integrator's state at its last point, so that tracing interval by interval, each with a series of
// only the steps it needs, gives the same line as one trace over the whole series.
struct PathlineTrace {
    TracedPathline line;
    Vec3d velocityKmPerMyr{};  // at the last point (Dormand–Prince's first-same-as-last stage)
    double nextStepMyr = 0;    // the step size the controller chose last
    bool done = false;         // the line ended (line.end says why)
};

// Integrates dx/dt = v(x, t) with the Dormand–Prince 5(4) pair (Dormand & Prince 1980; step
// control as in Hairer, Nørsett & Wanner, "Solving ODEs I", II.4), steps ending exactly on the
// series' step times (where v has a kink in time). A line stops at `endMyr`, or where it leaves
// the shell [first radius, last radius] of the grid (its last point then lies on the boundary,
// found by bisecting the step), or after options.maxPoints points.
class PathlineTracer {
public:
    // `series` must outlive the tracer; vx, vy, vz are the indices of the velocity components
    // (m/s) in series.fields[step]. Throws raypc::Error when the series has no step, its times
    // are not ascending or an index is out of range.
    PathlineTracer(const FieldSeries& series, size_t vx, size_t vy, size_t vz, TracerOptions options = {});

    // Velocity in km/Myr at `pKm` and `timeMyr` (clamped to the series' time range); nullopt
    // outside the shell.
    std::optional<Vec3d> velocityKmPerMyr(const Vec3d& pKm, double timeMyr) const;
    // Value of variable `var` at `pKm` and `timeMyr` (linear in time); NaN outside the shell.
    double sample(size_t var, const Vec3d& pKm, double timeMyr) const;

    TracedPathline trace(const Vec3d& startKm, double startMyr, double endMyr) const;

    // trace() in parts: begin() at the seed, then advance() to successive step times until done.
    // advance(trace, untilMyr, endMyr) integrates until `untilMyr` (a time of this tracer's series,
    // at most the line's `endMyr`) or the line ends; it reads the series' steps bracketing
    // [last time, untilMyr] and, for a step that lands within rounding past `untilMyr`, the step
    // after it (include it when it is <= the end step). begin then advance(endMyr) once is trace().
    // A line whose time lands within 1e-9 endMyr short of a step time without reaching it continues
    // on the next call with the velocity of that step rather than interpolated to it: a change far
    // below the integration tolerance, not seen in practice (the controller lands on step times
    // exactly).
    PathlineTrace begin(const Vec3d& startKm, double startMyr) const;
    void advance(PathlineTrace& trace, double untilMyr, double endMyr) const;

private:
    std::optional<grid::GridSampler::Location> locate(const Vec3d& pKm) const;
    // The bracketing steps of `timeMyr` and the weight of the later one.
    void bracketTime(double timeMyr, size_t& k0, size_t& k1, double& w) const;

    const FieldSeries& m_series;
    grid::GridSampler m_sampler;
    size_t m_v[3];
    // With `volumes`: each step's velocity components read point by point, a u16 one decoded at the
    // points a trace samples (the same bits as decoding it whole), so that tracing holds no decoded
    // array of the grid.
    std::vector<std::array<dataset::StepVolume::PointValues, 3>> m_velocity;
    TracerOptions m_options;
    double m_rMinKm, m_rMaxKm, m_rToleranceKm;
};

// The pathlines injected at one step, as stored (docs/format.md, "Pathlines"): points of all
// lines in one array, lines as ranges of it, and one row of attributes per line.
struct PathlineSet {
    int injectionStep = 0;
    double injectionTimeMyr = 0;
    int endStep = 0;         // the step whose time ends the lines (unless they leave the shell)
    std::string seedField;   // the field whose critical points seeded the lines
    double threshold = 0;    // the significance threshold used (seedField's units)
    std::vector<size_t> criticalCounts = std::vector<size_t>(5, 0);  // all found, by CriticalKind
    std::string settingsJson;  // the settings that made the set (preprocessing compares them)

    std::vector<std::string> columns, units;  // line attributes, see pathlineColumns
    std::vector<uint32_t> offsets;  // lineCount() + 1 entries: line i is points [offsets[i], offsets[i+1])
    std::vector<float> points;      // 4 floats per point: x, y, z (km), time (Myr)
    std::vector<float> attributes;  // lineCount() * columns.size(), row-major

    size_t lineCount() const { return offsets.empty() ? 0 : offsets.size() - 1; }
    size_t pointCount() const { return points.size() / 4; }
    float attribute(size_t line, size_t column) const { return attributes[line * columns.size() + column]; }
    // Index of the attribute column `name`, or -1.
    int column(const std::string& name) const;
};

// Fixed attribute columns (names and units from src/grid/names.json), before the "start <variable>"
// and "end <variable>" columns (one each per dataset variable, in dataset order). Codes: seed kind =
// CriticalKind, end reason = PathlineEnd. "seed persistence" is the persistence of the seed's pair
// (the largest of its pairs; 0 for a saddle the value rule chose that ends no extremum pair), in the
// seed field's units; sets stored before it (lines.json version 1) lack the column.
inline constexpr const auto& kPathlineFixedColumns = columns::kPathlineAttributes;
inline constexpr size_t kPathlineFixedColumnCount = std::size(kPathlineFixedColumns);

// Every attribute column of the pathline sets of a dataset with these variables, in stored order:
// the fixed columns, then "start <variable>" and "end <variable>" for each variable.
std::vector<std::string> pathlineColumns(const std::vector<std::string>& variableNames);

// Traces one line from every seed from series time `injectionStep` to `endStep` and fills a
// PathlineSet (lines in seed order). `names`/`units` name the series' variables (for the
// attribute columns). Uses oneTBB over seeds.
PathlineSet tracePathlines(const FieldSeries& series, const PathlineTracer& tracer,
                           const std::vector<CriticalPoint>& seeds, int injectionStep, int endStep,
                           const std::vector<std::string>& names, const std::vector<std::string>& units);

// tracePathlines in parts, for a set traced interval by interval (preprocessing's one pass): a set
// with the columns of `names` and no lines yet; each variable at a point and time (the tracer's
// sample(), as stored: float); a traced line appended with its attribute row, `startValues` and
// `endValues` being sampleVariables at its first and last point.
PathlineSet emptyPathlineSet(int injectionStep, double injectionTimeMyr, int endStep,
                             const std::vector<std::string>& names, const std::vector<std::string>& units);
std::vector<float> sampleVariables(const PathlineTracer& tracer, size_t variableCount, const Vec3d& pKm, double timeMyr);
void appendPathline(PathlineSet& set, const CriticalPoint& seed, const TracedPathline& line,
                    std::span<const float> startValues, std::span<const float> endValues);

}  // namespace raypc::analysis
