#include "data/pathlines.h"

#include "core/atomic_file.h"
#include "core/error.h"
#include "core/strings.h"

#include <fmt/format.h>
#include <nlohmann/json.hpp>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <fstream>

namespace raypc {
namespace {

namespace fs = std::filesystem;
using nlohmann::json;


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

std::string xmlEscape(const std::string& s)
{
    std::string out;
    for (char c : s) {
        switch (c) {
        case '&': out += "&amp;"; break;
        case '<': out += "&lt;"; break;
        case '>': out += "&gt;"; break;
        case '"': out += "&quot;"; break;
        default: out += c;
        }
    }
    return out;
}


std::string header(const std::string& name, const std::string& units)
{
    return csvQuote(units.empty() ? name : fmt::format("{} [{}]", name, units));
}

template <typename T>
void writeBinary(const fs::path& path, const std::vector<T>& values)
{
    std::ofstream out(path, std::ios::binary);
    out.write(reinterpret_cast<const char*>(values.data()), static_cast<std::streamsize>(values.size() * sizeof(T)));
    if (!out)
        fail("{}: write failed (disk full?)", path.string());
}

template <typename T>
std::vector<T> readBinary(const fs::path& path, size_t count)
{
    const std::string bytes = readFile(path);
    if (bytes.size() != count * sizeof(T))
        fail("{}: {} bytes, expected {} ({} values)", path.string(), bytes.size(), count * sizeof(T), count);
    std::vector<T> values(count);
    if (count)
        std::memcpy(values.data(), bytes.data(), bytes.size());
    return values;
}

// Points of line `i` as a span of 4-float records.
struct LineRange {
    size_t begin, end;
};
LineRange lineRange(const PathlineSet& set, size_t i) { return {set.offsets[i], set.offsets[i + 1]}; }

}  // namespace

// --- Tracer ----------------------------------------------------------------------------------

PathlineTracer::PathlineTracer(const FieldSeries& series, size_t vx, size_t vy, size_t vz, TracerOptions options)
    : m_series(series), m_sampler(series.grid), m_v{vx, vy, vz}, m_options(options)
{
    if (series.timesMyr.empty() || series.fields.size() != series.timesMyr.size())
        fail("pathlines: {} step times for {} steps of fields", series.timesMyr.size(), series.fields.size());
    for (size_t k = 1; k < series.timesMyr.size(); ++k)
        if (!(series.timesMyr[k] > series.timesMyr[k - 1]))
            fail("pathlines: step times are not ascending ({} then {} Myr)", series.timesMyr[k - 1],
                 series.timesMyr[k]);
    for (const auto& step : series.fields)
        for (size_t v : m_v)
            if (v >= step.size())
                fail("pathlines: velocity component {} out of range, a step has {} fields", v, step.size());
    if (!(options.toleranceKm > 0 && options.maxStepMyr > 0 && options.maxSegmentKm > 0 && options.maxPoints >= 2))
        fail("pathlines: tolerance, step, segment and point limits must be positive");
    m_rMinKm = series.grid.rKm.front();
    m_rMaxKm = series.grid.rKm.back();
    // Integration error moves a particle that rides on a boundary slightly off it; within this
    // distance it still counts as inside (and samples the boundary).
    double minDr = m_rMaxKm - m_rMinKm;
    for (size_t i = 1; i < series.grid.nR(); ++i)
        minDr = std::min(minDr, series.grid.rKm[i] - series.grid.rKm[i - 1]);
    m_rToleranceKm = 1e-3 * minDr;
}

std::optional<GridSampler::Location> PathlineTracer::locate(const Vec3d& pKm) const
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
        const double a = m_sampler.sample(m_series.fields[k0][m_v[c]], *at);
        const double b = w > 0 ? m_sampler.sample(m_series.fields[k1][m_v[c]], *at) : a;
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
    const double a = m_sampler.sample(m_series.fields[k0][var], *at);
    const double b = w > 0 ? m_sampler.sample(m_series.fields[k1][var], *at) : a;
    return a + (b - a) * w;
}

TracedPathline PathlineTracer::trace(const Vec3d& startKm, double startMyr, double endMyr) const
{
    TracedPathline line;
    line.pointsKm.push_back(startKm);
    line.timesMyr.push_back(startMyr);
    auto k1 = velocityKmPerMyr(startKm, startMyr);
    if (!k1) {
        line.end = PathlineEnd::LeftShell;
        return line;
    }
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

    Vec3d p = startKm;
    double t = startMyr;
    double h = m_options.maxStepMyr;
    k[0] = *k1;
    while (t < endMyr - timeEps) {
        if (line.pointsKm.size() >= m_options.maxPoints) {
            line.end = PathlineEnd::PointLimit;
            return line;
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
                line.end = PathlineEnd::LeftShell;
                return line;
            }
            if (lo <= 0) {
                line.end = PathlineEnd::LeftShell;
                return line;
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
    line.end = PathlineEnd::ReachedEndTime;
    return line;
}

// --- Tracing a set ---------------------------------------------------------------------------

int PathlineSet::column(const std::string& name) const
{
    for (size_t i = 0; i < columns.size(); ++i)
        if (columns[i] == name)
            return static_cast<int>(i);
    return -1;
}

PathlineSet tracePathlines(const FieldSeries& series, const PathlineTracer& tracer,
                           const std::vector<CriticalPoint>& seeds, int injectionStep, int endStep,
                           const std::vector<std::string>& names, const std::vector<std::string>& units)
{
    RAYPC_CHECK_EQ(names.size(), units.size());
    RAYPC_CHECK(injectionStep >= 0 && endStep >= injectionStep &&
                endStep < static_cast<int>(series.timesMyr.size()));
    PathlineSet set;
    set.injectionStep = injectionStep;
    set.injectionTimeMyr = series.timesMyr[injectionStep];
    set.endStep = endStep;
    const std::string fixedUnits[] = {"", "", "Myr", "Myr", "km", "", "degrees_north", "degrees_east", "km",
                                      "degrees_north", "degrees_east", "km"};
    for (size_t i = 0; i < kPathlineFixedColumnCount; ++i) {
        set.columns.push_back(kPathlineFixedColumns[i]);
        set.units.push_back(fixedUnits[i]);
    }
    for (const char* prefix : {"start ", "end "})
        for (size_t v = 0; v < names.size(); ++v) {
            set.columns.push_back(prefix + names[v]);
            set.units.push_back(units[v]);
        }

    const double t0 = series.timesMyr[injectionStep], t1 = series.timesMyr[endStep];
    std::vector<TracedPathline> lines(seeds.size());
    tbb::parallel_for(size_t(0), seeds.size(), [&](size_t i) {
        const auto& s = seeds[i];
        lines[i] = tracer.trace(sphericalToCartesianKm(s.latDeg, s.lonDeg, s.rKm), t0, t1);
    });

    const size_t nc = set.columns.size();
    set.attributes.resize(seeds.size() * nc);
    set.offsets.push_back(0);
    for (size_t i = 0; i < seeds.size(); ++i) {
        const auto& line = lines[i];
        for (size_t j = 0; j < line.pointsKm.size(); ++j) {
            const Vec3d& p = line.pointsKm[j];
            for (double x : {p.x, p.y, p.z, line.timesMyr[j]})
                set.points.push_back(static_cast<float>(x));
        }
        set.offsets.push_back(static_cast<uint32_t>(set.pointCount()));
        const Vec3d a = line.pointsKm.front(), b = line.pointsKm.back();
        const double ta = line.timesMyr.front(), tb = line.timesMyr.back();
        const SphericalPoint sa = cartesianToSpherical(a), sb = cartesianToSpherical(b);
        float* row = set.attributes.data() + i * nc;
        const double fixed[] = {static_cast<double>(seeds[i].kind), seeds[i].value, t0, tb - ta, line.lengthKm,
                                static_cast<double>(line.end), sa.latDeg, sa.lonDeg, sa.rKm,
                                sb.latDeg, sb.lonDeg, sb.rKm};
        for (size_t c = 0; c < kPathlineFixedColumnCount; ++c)
            row[c] = static_cast<float>(fixed[c]);
        for (size_t v = 0; v < names.size(); ++v) {
            row[kPathlineFixedColumnCount + v] = static_cast<float>(tracer.sample(v, a, ta));
            row[kPathlineFixedColumnCount + names.size() + v] = static_cast<float>(tracer.sample(v, b, tb));
        }
    }
    return set;
}

// --- Storage ---------------------------------------------------------------------------------

fs::path pathlineDir(const fs::path& dataset, int step) { return dataset / "pathlines" / fmt::format("{:04d}", step); }

void writePathlineSet(const fs::path& dir, const PathlineSet& set)
{
    fs::create_directories(dir);
    json j;
    j["format"] = "raypc-pathlines";
    j["version"] = 1;
    j["injection_step"] = set.injectionStep;
    j["injection_time_myr"] = set.injectionTimeMyr;
    j["end_step"] = set.endStep;
    j["seed_field"] = set.seedField;
    j["threshold"] = set.threshold;
    json counts;
    for (int k = 0; k < 5; ++k)
        counts[criticalKindName(static_cast<CriticalKind>(k))] = set.criticalCounts[k];
    j["critical_points"] = counts;
    j["line_count"] = set.lineCount();
    j["point_count"] = set.pointCount();
    j["columns"] = json::array();
    for (size_t c = 0; c < set.columns.size(); ++c)
        j["columns"].push_back({{"name", set.columns[c]}, {"units", set.units[c]}});
    j["settings"] = set.settingsJson.empty() ? json() : json::parse(set.settingsJson);
    writeBinary(dir / "offsets.u32", set.offsets);
    writeBinary(dir / "points.f32", set.points);
    writeBinary(dir / "attributes.f32", set.attributes);
    // lines.json last: a reader that finds it finds the arrays too.
    std::ofstream out(dir / "lines.json");
    out << j.dump(1);
    if (!out)
        fail("{}: write failed", (dir / "lines.json").string());
}

PathlineSet loadPathlineSet(const fs::path& dataset, int step)
{
    const fs::path dir = pathlineDir(dataset, step);
    const fs::path jsonPath = dir / "lines.json";
    if (!fs::exists(jsonPath))
        fail("{}: no pathlines for step {} (the dataset was preprocessed with --no-pathlines, or the step "
             "does not exist)",
             dataset.string(), step);
    PathlineSet set;
    try {
        const json j = json::parse(readFile(jsonPath));
        if (j.at("format").get<std::string>() != "raypc-pathlines" || j.at("version").get<int>() != 1)
            fail("{}: not a version 1 raypc-pathlines file", jsonPath.string());
        set.injectionStep = j.at("injection_step").get<int>();
        set.injectionTimeMyr = j.at("injection_time_myr").get<double>();
        set.endStep = j.at("end_step").get<int>();
        set.seedField = j.at("seed_field").get<std::string>();
        set.threshold = j.at("threshold").get<double>();
        for (int k = 0; k < 5; ++k)
            set.criticalCounts[k] = j.at("critical_points").at(criticalKindName(static_cast<CriticalKind>(k)));
        for (const auto& c : j.at("columns")) {
            set.columns.push_back(c.at("name").get<std::string>());
            set.units.push_back(c.at("units").get<std::string>());
        }
        set.settingsJson = j.at("settings").is_null() ? std::string() : j.at("settings").dump();
        const size_t lines = j.at("line_count").get<size_t>(), points = j.at("point_count").get<size_t>();
        set.offsets = readBinary<uint32_t>(dir / "offsets.u32", lines + 1);
        set.points = readBinary<float>(dir / "points.f32", 4 * points);
        set.attributes = readBinary<float>(dir / "attributes.f32", lines * set.columns.size());
        if (set.offsets.front() != 0 || set.offsets.back() != points ||
            !std::is_sorted(set.offsets.begin(), set.offsets.end()))
            fail("{}: offsets are not ascending from 0 to {}", (dir / "offsets.u32").string(), points);
    } catch (const json::exception& e) {
        fail("{}: malformed: {}", jsonPath.string(), e.what());
    }
    return set;
}

std::vector<PathlineSet> loadPathlineWindow(const fs::path& dataset, int step, int window)
{
    std::vector<PathlineSet> sets;
    for (int s = std::max(0, step - window + 1); s <= step; ++s)
        sets.push_back(loadPathlineSet(dataset, s));
    return sets;
}

// --- Export ----------------------------------------------------------------------------------

std::string pathlinesCsv(const PathlineSet& set)
{
    std::string out = "line,point,x [km],y [km],z [km],lat [degrees_north],lon [degrees_east],radius [km],"
                      "time [Myr],age [Myr]";
    for (size_t c = 0; c < set.columns.size(); ++c)
        out += "," + header(set.columns[c], set.units[c]);
    out += '\n';
    auto it = std::back_inserter(out);
    for (size_t i = 0; i < set.lineCount(); ++i) {
        const auto [begin, end] = lineRange(set, i);
        for (size_t p = begin; p < end; ++p) {
            const float* q = &set.points[4 * p];
            const SphericalPoint s = cartesianToSpherical({q[0], q[1], q[2]});
            fmt::format_to(it, "{},{},{:.7g},{:.7g},{:.7g},{:.7g},{:.7g},{:.7g},{:.7g},{:.7g}", i, p - begin, q[0],
                           q[1], q[2], s.latDeg, s.lonDeg, s.rKm, q[3], q[3] - set.injectionTimeMyr);
            for (size_t c = 0; c < set.columns.size(); ++c)
                fmt::format_to(it, ",{:.7g}", set.attribute(i, c));
            out += '\n';
        }
    }
    return out;
}

std::string criticalPointsCsv(const PathlineSet& set)
{
    std::string out = "kind,x [km],y [km],z [km]";
    for (size_t c = 0; c < set.columns.size(); ++c)
        out += "," + header(set.columns[c], set.units[c]);
    out += '\n';
    auto it = std::back_inserter(out);
    for (size_t i = 0; i < set.lineCount(); ++i) {
        const float* q = &set.points[4 * set.offsets[i]];
        fmt::format_to(it, "{},{:.7g},{:.7g},{:.7g}", criticalKindName(static_cast<CriticalKind>(set.attribute(i, 0))),
                       q[0], q[1], q[2]);
        for (size_t c = 0; c < set.columns.size(); ++c)
            fmt::format_to(it, ",{:.7g}", set.attribute(i, c));
        out += '\n';
    }
    return out;
}

namespace {

template <typename F>
void xmlArray(std::string& out, const char* type, const std::string& name, int components, size_t count, F value)
{
    auto it = std::back_inserter(out);
    fmt::format_to(it, "        <DataArray type=\"{}\"", type);
    if (!name.empty())
        fmt::format_to(it, " Name=\"{}\"", xmlEscape(name));
    if (components > 1)
        fmt::format_to(it, " NumberOfComponents=\"{}\"", components);
    out += " format=\"ascii\">\n";
    for (size_t i = 0; i < count; ++i) {
        value(it, i);
        out += (i + 1) % 12 == 0 || i + 1 == count ? '\n' : ' ';
    }
    out += "        </DataArray>\n";
}

// The points of `set` selected by `index(i)` for i < n, and per-point data.
std::string vtpDocument(const PathlineSet& set, bool linesNotSeeds)
{
    const size_t nLines = set.lineCount();
    const size_t nPoints = linesNotSeeds ? set.pointCount() : nLines;
    auto pointIndex = [&](size_t i) { return linesNotSeeds ? i : static_cast<size_t>(set.offsets[i]); };
    std::string out = "<?xml version=\"1.0\"?>\n"
                      "<VTKFile type=\"PolyData\" version=\"1.0\" byte_order=\"LittleEndian\" header_type=\"UInt64\">\n"
                      "  <PolyData>\n";
    auto it = std::back_inserter(out);
    fmt::format_to(it,
                   "    <Piece NumberOfPoints=\"{}\" NumberOfVerts=\"{}\" NumberOfLines=\"{}\" NumberOfStrips=\"0\" "
                   "NumberOfPolys=\"0\">\n",
                   nPoints, linesNotSeeds ? 0 : nLines, linesNotSeeds ? nLines : 0);
    out += "      <PointData>\n";
    if (linesNotSeeds) {
        xmlArray(out, "Float32", "time", 1, nPoints, [&](auto o, size_t i) { fmt::format_to(o, "{:.7g}", set.points[4 * i + 3]); });
        xmlArray(out, "Float32", "age", 1, nPoints,
                 [&](auto o, size_t i) { fmt::format_to(o, "{:.7g}", set.points[4 * i + 3] - set.injectionTimeMyr); });
    } else {
        for (size_t c = 0; c < set.columns.size(); ++c)
            xmlArray(out, "Float32", set.columns[c], 1, nPoints,
                     [&](auto o, size_t i) { fmt::format_to(o, "{:.7g}", set.attribute(i, c)); });
    }
    out += "      </PointData>\n      <CellData>\n";
    if (linesNotSeeds)
        for (size_t c = 0; c < set.columns.size(); ++c)
            xmlArray(out, "Float32", set.columns[c], 1, nLines,
                     [&](auto o, size_t i) { fmt::format_to(o, "{:.7g}", set.attribute(i, c)); });
    out += "      </CellData>\n      <Points>\n";
    xmlArray(out, "Float32", "", 3, nPoints, [&](auto o, size_t i) {
        const float* q = &set.points[4 * pointIndex(i)];
        fmt::format_to(o, "{:.7g} {:.7g} {:.7g}", q[0], q[1], q[2]);
    });
    out += "      </Points>\n";
    const char* cells = linesNotSeeds ? "Lines" : "Verts";
    fmt::format_to(it, "      <{}>\n", cells);
    xmlArray(out, "Int64", "connectivity", 1, nPoints, [&](auto o, size_t i) { fmt::format_to(o, "{}", i); });
    xmlArray(out, "Int64", "offsets", 1, nLines,
             [&](auto o, size_t i) { fmt::format_to(o, "{}", linesNotSeeds ? set.offsets[i + 1] : i + 1); });
    fmt::format_to(it, "      </{}>\n", cells);
    out += "    </Piece>\n  </PolyData>\n</VTKFile>\n";
    return out;
}

std::string legacyDocument(const PathlineSet& set, bool linesNotSeeds)
{
    const size_t nLines = set.lineCount();
    const size_t nPoints = linesNotSeeds ? set.pointCount() : nLines;
    auto pointIndex = [&](size_t i) { return linesNotSeeds ? i : static_cast<size_t>(set.offsets[i]); };
    std::string out;
    auto it = std::back_inserter(out);
    fmt::format_to(it, "# vtk DataFile Version 3.0\nRayPC {} injected at step {} ({} Myr)\nASCII\nDATASET POLYDATA\n",
                   linesNotSeeds ? "pathlines" : "critical points (pathline seeds)", set.injectionStep,
                   set.injectionTimeMyr);
    fmt::format_to(it, "POINTS {} float\n", nPoints);
    for (size_t i = 0; i < nPoints; ++i) {
        const float* q = &set.points[4 * pointIndex(i)];
        fmt::format_to(it, "{:.7g} {:.7g} {:.7g}\n", q[0], q[1], q[2]);
    }
    // Legacy array names cannot hold spaces.
    auto fieldArrays = [&](size_t count, auto value) {
        fmt::format_to(it, "FIELD FieldData {}\n", set.columns.size());
        for (size_t c = 0; c < set.columns.size(); ++c) {
            fmt::format_to(it, "{} 1 {} float\n", fileSafeName(set.columns[c]), count);
            for (size_t i = 0; i < count; ++i)
                fmt::format_to(it, "{:.7g}{}", value(i, c), (i + 1) % 12 == 0 || i + 1 == count ? '\n' : ' ');
        }
    };
    auto attr = [&](size_t i, size_t c) { return set.attribute(i, c); };
    if (linesNotSeeds) {
        fmt::format_to(it, "LINES {} {}\n", nLines, nLines + nPoints);
        for (size_t i = 0; i < nLines; ++i) {
            const auto [begin, end] = lineRange(set, i);
            fmt::format_to(it, "{}", end - begin);
            for (size_t p = begin; p < end; ++p)
                fmt::format_to(it, " {}", p);
            out += '\n';
        }
        fmt::format_to(it, "CELL_DATA {}\n", nLines);
        fieldArrays(nLines, attr);
        fmt::format_to(it, "POINT_DATA {}\nFIELD FieldData 2\ntime 1 {} float\n", nPoints, nPoints);
        for (size_t i = 0; i < nPoints; ++i)
            fmt::format_to(it, "{:.7g}{}", set.points[4 * i + 3], (i + 1) % 12 == 0 || i + 1 == nPoints ? '\n' : ' ');
        fmt::format_to(it, "age 1 {} float\n", nPoints);
        for (size_t i = 0; i < nPoints; ++i)
            fmt::format_to(it, "{:.7g}{}", set.points[4 * i + 3] - set.injectionTimeMyr,
                           (i + 1) % 12 == 0 || i + 1 == nPoints ? '\n' : ' ');
    } else {
        fmt::format_to(it, "VERTICES {} {}\n", nLines, 2 * nLines);
        for (size_t i = 0; i < nLines; ++i)
            fmt::format_to(it, "1 {}\n", i);
        fmt::format_to(it, "POINT_DATA {}\n", nPoints);
        fieldArrays(nPoints, attr);
    }
    return out;
}

}  // namespace

std::string pathlinesVtp(const PathlineSet& set) { return vtpDocument(set, true); }
std::string criticalPointsVtp(const PathlineSet& set) { return vtpDocument(set, false); }
std::string pathlinesLegacyVtk(const PathlineSet& set) { return legacyDocument(set, true); }
std::string criticalPointsLegacyVtk(const PathlineSet& set) { return legacyDocument(set, false); }

}  // namespace raypc
