#include "data/preprocess.h"

#include "core/atomic_file.h"
#include "core/error.h"
#include "core/mapped_file.h"
#include "core/progress.h"
#include "core/spherical.h"
#include "core/system_memory.h"
#include "core/strings.h"
#include "data/bricks.h"
#include "data/dataset_format.h"

#include <spdlog/spdlog.h>
#include <tbb/parallel_for.h>
#include <tbb/parallel_reduce.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <exception>
#include <fstream>
#include <functional>
#include <map>
#include <random>

namespace raypc {
namespace {

namespace fs = std::filesystem;
using nlohmann::json;

// Runs an action when the scope is left by an exception, unless dismissed first.
class ScopeCleanup {
public:
    explicit ScopeCleanup(std::function<void()> action) : m_action(std::move(action)) {}
    ~ScopeCleanup()
    {
        if (m_action && std::uncaught_exceptions() > m_exceptions)
            m_action();
    }
    ScopeCleanup(const ScopeCleanup&) = delete;
    ScopeCleanup& operator=(const ScopeCleanup&) = delete;
    void dismiss() { m_action = nullptr; }

private:
    std::function<void()> m_action;
    int m_exceptions = std::uncaught_exceptions();
};

void writeArray(const fs::path& path, std::span<const float> values)
{
    std::FILE* f = std::fopen(path.c_str(), "wb");
    if (!f)
        fail("{}: cannot create", path.string());
    const size_t written = std::fwrite(values.data(), sizeof(float), values.size(), f);
    const bool ok = written == values.size() && std::fclose(f) == 0;
    if (!ok)
        fail("{}: write failed (disk full?)", path.string());
}

struct VariableSpec {
    std::string name, units;
    bool derived;
};

// The variables of the dataset, in order: the stored ones as the reader returns them, then
// the derived ones. Units of derived variables are fixed by addDerivedVariables.
std::vector<VariableSpec> variableSpecs(const FileHeader& header)
{
    std::vector<VariableSpec> specs;
    for (const auto& v : header.variables)
        specs.push_back({v.name, v.units, false});
    specs.push_back({"radial velocity", "cm/yr", true});
    specs.push_back({"velocity magnitude", "cm/yr", true});
    for (const auto& v : header.variables)
        if (v.name == "thermal expansivity")
            specs.push_back({"thermal expansivity anomaly", v.units, true});
    return specs;
}

json manifest(const std::vector<SphericalGrid>& levels, const std::vector<VariableSpec>& specs,
              const std::vector<fs::path>& inputs, const PreprocessOptions& options, size_t sampleRows)
{
    json j;
    j["format"] = format::kFormatName;
    j["version"] = format::kVersion;
    j["status"] = "incomplete";
    j["dt_myr"] = options.dtMyr;
    j["brick_size"] = options.brickSize;
    j["levels"] = json::array();
    for (const auto& g : levels)
        j["levels"].push_back(format::toJson(g));
    j["variables"] = json::array();
    for (const auto& v : specs)
        j["variables"].push_back(
            {{"name", v.name}, {"units", v.units}, {"derived", v.derived}, {"file_stem", fileSafeName(v.name)}});
    j["inputs"] = json::array();
    for (const auto& p : inputs)
        j["inputs"].push_back(p.filename().string());
    j["sample"] = {{"rows", sampleRows}, {"seed", options.seed}};
    return j;
}

// Writes the sample's coordinate columns (coordinateInfos() order) for every sampled point.
std::vector<float> sampleCoordinates(const SphericalGrid& grid, std::span<const uint32_t> cells)
{
    const size_t nc = coordinateInfos().size();
    std::vector<float> out(cells.size() * nc);
    for (size_t i = 0; i < cells.size(); ++i) {
        const size_t c = cells[i];
        const size_t iLon = c % grid.nLon(), iR = (c / grid.nLon()) % grid.nR(), iLat = c / (grid.nLon() * grid.nR());
        const double lat = grid.latDeg[iLat], lon = grid.lonDeg[iLon], r = grid.rKm[iR];
        const Vec3d p = sphericalToCartesianKm(lat, lon, r);
        const double row[] = {p.x, p.y, p.z, lat, lon, r, kSurfaceRadiusKm - r};
        for (size_t k = 0; k < nc; ++k)
            out[i * nc + k] = static_cast<float>(row[k]);
    }
    return out;
}

json pathlineSettings(const PathlineOptions& o)
{
    return {{"field", o.field},
            {"steps", o.steps},
            {"filter",
             {{"min_abs_value", o.filter.minAbsValue},
              {"min_fraction_of_max_abs", o.filter.minFractionOfMaxAbs},
              {"max_count", o.filter.maxCount},
              {"saddles", o.filter.saddles}}},
            {"tracer",
             {{"tolerance_km", o.tracer.toleranceKm},
              {"max_step_myr", o.tracer.maxStepMyr},
              {"max_segment_km", o.tracer.maxSegmentKm},
              {"max_points", o.tracer.maxPoints}}}};
}

void checkPathlineOptions(const PathlineOptions& o, const std::vector<VariableSpec>& specs)
{
    if (!o.enabled)
        return;
    if (o.steps < 1)
        fail("--pathline-steps: {} is not a positive number of steps", o.steps);
    if (std::none_of(specs.begin(), specs.end(), [&](const VariableSpec& v) { return v.name == o.field; })) {
        std::vector<std::string> names;
        for (const auto& v : specs)
            names.push_back(v.name);
        fail("--pathline-field: no variable '{}' in the input; variables are {}", o.field, fmt::join(names, ", "));
    }
    if (!(o.filter.minAbsValue >= 0) || !(o.filter.minFractionOfMaxAbs >= 0 && o.filter.minFractionOfMaxAbs <= 1))
        fail("critical-point threshold: need --cp-min-abs >= 0 and --cp-min-fraction within [0, 1], got {} and {}",
             o.filter.minAbsValue, o.filter.minFractionOfMaxAbs);
    if (o.filter.maxCount == 0)
        fail("--cp-max-count: must be at least 1");
}

// The level-0 arrays of written steps, mapped on demand and released when no longer needed.
class StepArrays {
public:
    StepArrays(fs::path dataset, std::vector<VariableSpec> specs) : m_dir(std::move(dataset)), m_specs(std::move(specs)) {}

    const std::vector<const float*>& fields(int step, size_t cellCount)
    {
        auto it = m_steps.find(step);
        if (it != m_steps.end())
            return it->second.pointers;
        Mapped& m = m_steps[step];
        const fs::path dir = format::levelDir(format::stepDir(m_dir, step), 0);
        for (const auto& v : m_specs) {
            const fs::path path = format::valuesFile(dir, fileSafeName(v.name));
            auto& file = m.files.emplace_back(path);
            if (file.size() != cellCount * sizeof(float))
                fail("{}: {} bytes, expected {}", path.string(), file.size(), cellCount * sizeof(float));
            m.pointers.push_back(reinterpret_cast<const float*>(file.bytes().data()));
        }
        return m.pointers;
    }
    // Unmaps the steps before `step`.
    void releaseBefore(int step) { m_steps.erase(m_steps.begin(), m_steps.lower_bound(step)); }

private:
    struct Mapped {
        std::vector<MappedFile> files;
        std::vector<const float*> pointers;
    };
    fs::path m_dir;
    std::vector<VariableSpec> m_specs;
    std::map<int, Mapped> m_steps;
};

// Phase 2: critical points and pathlines of every step, each step's set written atomically and
// skipped on a rerun when it was made with the same settings and reaches the same last step.
void writePathlines(const fs::path& outDir, const SphericalGrid& grid, const std::vector<VariableSpec>& specs,
                    const std::vector<json>& stepJsons, const PreprocessOptions& options, PreprocessSummary& summary)
{
    const PathlineOptions& po = options.pathlines;
    const fs::path root = outDir / "pathlines";
    if (!po.enabled) {
        fs::remove_all(root);
        return;
    }
    fs::create_directories(root);
    for (const auto& entry : fs::directory_iterator(root))
        if (entry.path().filename().string().starts_with("."))
            fs::remove_all(entry.path());
    const json settings = pathlineSettings(po);
    const int nSteps = static_cast<int>(stepJsons.size());
    std::vector<std::string> names, units;
    size_t field = 0, vx = 0, vy = 0, vz = 0;
    for (size_t v = 0; v < specs.size(); ++v) {
        names.push_back(specs[v].name);
        units.push_back(specs[v].units);
        field = specs[v].name == po.field ? v : field;
        vx = specs[v].name == "vx" ? v : vx;
        vy = specs[v].name == "vy" ? v : vy;
        vz = specs[v].name == "vz" ? v : vz;
    }

    std::vector<int> todo;
    for (int s = 0; s < nSteps; ++s) {
        const int endStep = std::min(s + po.steps, nSteps - 1);
        const fs::path dir = pathlineDir(outDir, s);
        if (fs::exists(dir / "lines.json")) {
            try {
                const json old = json::parse(readFile(dir / "lines.json"));
                if (old.at("settings") == settings && old.at("end_step").get<int>() == endStep) {
                    ++summary.pathlineSetsSkipped;
                    continue;
                }
            } catch (const json::exception&) {
                // An unreadable set is redone below.
            }
        }
        todo.push_back(s);
    }
    std::optional<Progress> progress;
    if (!options.quiet && !todo.empty())
        progress.emplace("pathlines", static_cast<int64_t>(todo.size()), "steps");
    StepArrays arrays(outDir, specs);
    for (const int s : todo) {
        const int endStep = std::min(s + po.steps, nSteps - 1);
        arrays.releaseBefore(s);
        FieldSeries series;
        series.grid = grid;
        for (int k = s; k <= endStep; ++k) {
            series.timesMyr.push_back(stepJsons[k].at("time_myr").get<double>());
            series.fields.push_back(arrays.fields(k, grid.cellCount()));
        }
        const std::span<const float> values(series.fields.front()[field], grid.cellCount());
        const auto all = findCriticalPoints(grid, values);
        const VariableStats stats = format::statsFromJson(stepJsons[s].at("stats").at(field));
        const double maxAbs = std::max(std::abs(double(stats.range.min)), std::abs(double(stats.range.max)));
        const auto seeds = selectSignificant(all, maxAbs, po.filter);
        const PathlineTracer tracer(series, vx, vy, vz, po.tracer);
        PathlineSet set = tracePathlines(series, tracer, seeds, 0, endStep - s, names, units);
        set.injectionStep = s;
        set.endStep = endStep;
        set.seedField = po.field;
        set.threshold = significanceThreshold(po.filter, maxAbs);
        for (const auto& p : all)
            ++set.criticalCounts[static_cast<size_t>(p.kind)];
        set.settingsJson = settings.dump();

        const fs::path finalDir = pathlineDir(outDir, s);
        const fs::path tmpDir = temporarySibling(finalDir);
        writePathlineSet(tmpDir, set);
        if (fs::exists(finalDir))
            fs::remove_all(finalDir);
        renameAtomic(tmpDir, finalDir);
        spdlog::debug("step {}: {} critical points, {} seeds above {:.4g}, {} pathline points", s, all.size(),
                      seeds.size(), set.threshold, set.pointCount());
        ++summary.pathlineSetsWritten;
        summary.pathlineCount += set.lineCount();
        if (progress)
            progress->advance();
    }
    if (progress)
        progress->finish();
    // Sets of steps beyond the inputs (a rerun with fewer inputs is refused earlier) never stay.
    for (const auto& entry : fs::directory_iterator(root)) {
        const std::string name = entry.path().filename().string();
        if (name.size() == 4 && std::all_of(name.begin(), name.end(), ::isdigit) && std::stoi(name) >= nSteps)
            fs::remove_all(entry.path());
    }
}

}  // namespace

uint64_t preprocessMemoryBytes(const SphericalGrid& grid, size_t variableCount)
{
    return (variableCount + 1) * uint64_t(grid.nLat()) * grid.nR() * grid.nLon() * sizeof(float);
}

float toFloat32(double value)
{
    if (std::abs(value) > std::numeric_limits<float>::max())
        return std::copysign(std::numeric_limits<float>::infinity(), value);
    return static_cast<float>(value);
}

void addDerivedVariables(Snapshot& snapshot)
{
    const Field* vx = snapshot.find("vx");
    const Field* vy = snapshot.find("vy");
    const Field* vz = snapshot.find("vz");
    if (!vx || !vy || !vz)
        fail("derived variables need vx, vy and vz, which are not all present");
    const auto& g = snapshot.grid;
    Field radial{"radial velocity", "cm/yr", std::vector<float>(g.cellCount()), {"vx", "vy", "vz"}};
    Field magnitude{"velocity magnitude", "cm/yr", std::vector<float>(g.cellCount()), {"vx", "vy", "vz"}};
    tbb::parallel_for(size_t(0), g.nLat(), [&](size_t iLat) {
        const double lat = degToRad(g.latDeg[iLat]);
        for (size_t iLon = 0; iLon < g.nLon(); ++iLon) {
            const double lon = degToRad(g.lonDeg[iLon]);
            // The outward unit vector is the same on every shell of this column.
            const double ux = std::cos(lat) * std::cos(lon), uy = std::cos(lat) * std::sin(lon), uz = std::sin(lat);
            for (size_t iR = 0; iR < g.nR(); ++iR) {
                const size_t i = g.index(iLat, iR, iLon);
                const double x = vx->values[i], y = vy->values[i], z = vz->values[i];
                radial.values[i] = toFloat32((x * ux + y * uy + z * uz) * kMpsToCmPerYr);
                magnitude.values[i] = toFloat32(std::sqrt(x * x + y * y + z * z) * kMpsToCmPerYr);
            }
        }
    });
    snapshot.fields.push_back(std::move(radial));
    snapshot.fields.push_back(std::move(magnitude));
    // The contest's correlation task asks for the sign of the expansivity *anomaly*: its
    // deviation from the area-weighted lateral mean of each shell, like the temperature anomaly.
    if (const Field* alpha = snapshot.find("thermal expansivity"))
        snapshot.fields.push_back(lateralAnomaly(g, *alpha, "thermal expansivity anomaly"));
}

Field lateralAnomaly(const SphericalGrid& g, const Field& field, const std::string& name)
{
    const auto w = g.volumeFactors();
    double area = 0;
    for (size_t iLat = 0; iLat < g.nLat(); ++iLat)
        for (size_t iLon = 0; iLon < g.nLon(); ++iLon)
            area += w.lat[iLat] * w.lon[iLon];
    Field out{name, field.units, std::vector<float>(g.cellCount()), {field.name}};
    tbb::parallel_for(size_t(0), g.nR(), [&](size_t iR) {
        double sum = 0;
        for (size_t iLat = 0; iLat < g.nLat(); ++iLat)
            for (size_t iLon = 0; iLon < g.nLon(); ++iLon)
                sum += w.lat[iLat] * w.lon[iLon] * field.values[g.index(iLat, iR, iLon)];
        const double mean = sum / area;
        for (size_t iLat = 0; iLat < g.nLat(); ++iLat)
            for (size_t iLon = 0; iLon < g.nLon(); ++iLon) {
                const size_t i = g.index(iLat, iR, iLon);
                out.values[i] = toFloat32(field.values[i] - mean);
            }
    });
    return out;
}

std::vector<float> coarsenField(const SphericalGrid& fine, std::span<const float> values)
{
    RAYPC_CHECK_EQ(values.size(), fine.cellCount());
    const SphericalGrid coarse = fine.coarsened();
    const auto w = fine.volumeFactors();
    std::vector<float> out(coarse.cellCount());
    tbb::parallel_for(size_t(0), coarse.nLat(), [&](size_t cLat) {
        const size_t lat0 = 2 * cLat, lat1 = std::min(lat0 + 2, fine.nLat());
        for (size_t cR = 0; cR < coarse.nR(); ++cR) {
            const size_t r0 = 2 * cR, r1 = std::min(r0 + 2, fine.nR());
            for (size_t cLon = 0; cLon < coarse.nLon(); ++cLon) {
                const size_t lon0 = 2 * cLon, lon1 = std::min(lon0 + 2, fine.nLon());
                double sum = 0, weight = 0;
                for (size_t iLat = lat0; iLat < lat1; ++iLat)
                    for (size_t iR = r0; iR < r1; ++iR)
                        for (size_t iLon = lon0; iLon < lon1; ++iLon) {
                            const double wi = w.at(iLat, iR, iLon);
                            sum += wi * values[fine.index(iLat, iR, iLon)];
                            weight += wi;
                        }
                out[coarse.index(cLat, cR, cLon)] = static_cast<float>(sum / weight);
            }
        }
    });
    return out;
}

VariableStats computeStats(const SphericalGrid& grid, std::span<const float> values)
{
    RAYPC_CHECK_EQ(values.size(), grid.cellCount());
    const auto w = grid.volumeFactors();
    const size_t rowSize = grid.nR() * grid.nLon();
    const auto [lo, hi] = tbb::parallel_reduce(
        tbb::blocked_range<size_t>(0, values.size(), 1 << 16), std::pair<float, float>(INFINITY, -INFINITY),
        [&](const auto& range, std::pair<float, float> acc) {
            for (size_t i = range.begin(); i != range.end(); ++i) {
                acc.first = std::min(acc.first, values[i]);
                acc.second = std::max(acc.second, values[i]);
            }
            return acc;
        },
        [](auto a, auto b) { return std::pair(std::min(a.first, b.first), std::max(a.second, b.second)); });

    // Callers check that values are finite (checkFinite): an infinite range has no bins.
    RAYPC_CHECK(std::isfinite(lo) && std::isfinite(hi));
    VariableStats stats;
    stats.range = {lo, hi};
    const double span = static_cast<double>(hi) - lo;
    const double scale = span > 0 ? kHistogramBins / span : 0.0;
    // One partial sum per lat row, added in row order: the sums do not depend on how rows were
    // spread over threads, so a rerun writes the same bytes (dataset.json is reproducible).
    struct Partial {
        double weighted = 0, weight = 0;
    };
    std::vector<Partial> rows(grid.nLat());
    std::vector<double> rowHistograms(grid.nLat() * kHistogramBins, 0.0);
    tbb::parallel_for(size_t(0), grid.nLat(), [&](size_t iLat) {
        Partial& p = rows[iLat];
        double* histogram = rowHistograms.data() + iLat * kHistogramBins;
        for (size_t iR = 0; iR < grid.nR(); ++iR) {
            const double wRow = w.lat[iLat] * w.r[iR];
            const float* row = values.data() + iLat * rowSize + iR * grid.nLon();
            for (size_t iLon = 0; iLon < grid.nLon(); ++iLon) {
                const double wi = wRow * w.lon[iLon];
                // In double: the difference of two finite floats may overflow float.
                const int bin = std::min(kHistogramBins - 1, static_cast<int>((double(row[iLon]) - lo) * scale));
                histogram[bin] += wi;
                p.weighted += wi * row[iLon];
                p.weight += wi;
            }
        }
    });
    stats.histogram.assign(kHistogramBins, 0.0);
    double weighted = 0, weight = 0;
    for (size_t iLat = 0; iLat < grid.nLat(); ++iLat) {
        for (int b = 0; b < kHistogramBins; ++b)
            stats.histogram[b] += rowHistograms[iLat * kHistogramBins + b];
        weighted += rows[iLat].weighted;
        weight += rows[iLat].weight;
    }
    for (double& h : stats.histogram)
        h /= weight;
    stats.mean = weighted / weight;
    return stats;
}

std::vector<uint32_t> drawVolumeWeightedSample(const SphericalGrid& grid, size_t rows, uint64_t seed)
{
    // Dual-cell volumes factor into lat, r and lon parts, so drawing each index independently
    // from its own factor draws grid points with probability proportional to volume.
    const auto w = grid.volumeFactors();
    std::mt19937_64 rng(seed);
    std::discrete_distribution<size_t> lat(w.lat.begin(), w.lat.end());
    std::discrete_distribution<size_t> r(w.r.begin(), w.r.end());
    std::discrete_distribution<size_t> lon(w.lon.begin(), w.lon.end());
    std::vector<uint32_t> cells(rows);
    for (auto& c : cells) {
        const size_t iLat = lat(rng), iR = r(rng), iLon = lon(rng);
        c = static_cast<uint32_t>(grid.index(iLat, iR, iLon));
    }
    std::sort(cells.begin(), cells.end());
    return cells;
}

void rebinHistogram(const VariableStats& stats, ValueRange range, std::span<double> histogram)
{
    const size_t nOut = histogram.size();
    const size_t nIn = stats.histogram.size();
    const double outLo = range.min, outSpan = static_cast<double>(range.max) - range.min;
    const double inLo = stats.range.min, inSpan = static_cast<double>(stats.range.max) - stats.range.min;
    auto outBin = [&](double v) {
        if (outSpan <= 0)
            return size_t(0);
        return std::min(nOut - 1, static_cast<size_t>(std::max(0.0, (v - outLo) / outSpan * nOut)));
    };
    for (size_t b = 0; b < nIn; ++b) {
        const double mass = stats.histogram[b];
        if (mass == 0)
            continue;
        if (inSpan <= 0 || outSpan <= 0) {
            histogram[outBin(inLo)] += mass;
            continue;
        }
        const double a = inLo + inSpan * b / nIn, c = inLo + inSpan * (b + 1) / nIn;
        const size_t first = outBin(a), last = outBin(c);
        for (size_t o = first; o <= last; ++o) {
            const double oLo = outLo + outSpan * o / nOut, oHi = outLo + outSpan * (o + 1) / nOut;
            const double overlap = std::min(c, oHi) - std::max(a, oLo);
            if (overlap > 0)
                histogram[o] += mass * overlap / (c - a);
        }
    }
}

PreprocessSummary preprocess(const std::vector<fs::path>& inputs, const fs::path& outDir,
                             const PreprocessOptions& options)
{
    const auto start = std::chrono::steady_clock::now();
    if (inputs.empty())
        fail("preprocess: no input files");
    if (!(options.dtMyr > 0))
        fail("--dt-myr: {} is not a positive time step", options.dtMyr);
    if (options.sampleRows == 0)
        fail("--sample-rows: must be at least 1");

    // The first file fixes the grid and the variables; every other step must match them.
    const FileHeader header = readHeader(inputs.front(), options.reader);
    std::vector<SphericalGrid> levels = {header.grid};
    for (int l = 1; l < kLevelCount; ++l)
        levels.push_back(levels.back().coarsened());
    // Check every input's header before writing anything, so that a bad file, a missing variable
    // or a different grid stops the run before it starts.
    for (size_t s = 1; s < inputs.size(); ++s) {
        const FileHeader other = readHeader(inputs[s], options.reader);
        if (!other.grid.sameAs(header.grid))
            fail("{}: grid {}x{}x{} (lat x r x lon) or its coordinates differ from the first step's {}x{}x{} in {}",
                 inputs[s].string(), other.grid.nLat(), other.grid.nR(), other.grid.nLon(), header.grid.nLat(),
                 header.grid.nR(), header.grid.nLon(), inputs.front().filename().string());
    }
    const auto specs = variableSpecs(header);
    checkPathlineOptions(options.pathlines, specs);
    checkGridFitsMemory(header.grid, preprocessMemoryBytes(header.grid, specs.size()), inputs.front().string(),
                        "preprocess", availableMemory());
    const size_t sampleRows = options.sampleRows;
    json j = manifest(levels, specs, inputs, options, sampleRows);

    // From here on the run writes; one run at a time per directory.
    const bool dirExisted = fs::exists(outDir);
    DatasetWriteLock lock(outDir);
    const fs::path manifestPath = outDir / format::kManifest;
    const bool fresh = !fs::exists(manifestPath);
    // A fresh run that fails before it finishes a step leaves nothing (what it created goes);
    // later, the finished steps stay for a rerun to resume from (docs/format.md).
    std::vector<fs::path> created;
    for (const fs::path name : {format::kSampleCoords, "steps", "pathlines"})
        if (!fs::exists(outDir / name))
            created.push_back(outDir / name);
    ScopeCleanup leaveNothing([&] {
        std::error_code ec;
        lock.removeFile();
        if (!dirExisted) {
            fs::remove_all(outDir, ec);
            return;
        }
        fs::remove(manifestPath, ec);
        for (const auto& path : created)
            fs::remove_all(path, ec);
    });
    if (!fresh)
        leaveNothing.dismiss();
    fs::create_directories(outDir / "steps");
    if (!fresh) {
        json old;
        try {
            old = json::parse(readFile(manifestPath));
        } catch (const json::exception& e) {
            fail("{}: exists but is not valid JSON ({}); remove the directory to start over",
                 manifestPath.string(), e.what());
        }
        // Resuming is only safe into a dataset made from the same inputs with the same settings.
        // A finished manifest adds global statistics to the variables: not a setting.
        if (old.contains("variables") && old["variables"].is_array())
            for (auto& v : old["variables"])
                if (v.is_object())
                    v.erase("global");
        for (const char* key : {"format", "version", "levels", "variables", "dt_myr", "brick_size", "sample"})
            if (old.value(key, json()) != j[key])
                fail("{}: holds a dataset made with a different '{}' (other inputs or options); "
                     "use another output directory or remove it",
                     outDir.string(), key);
        const auto oldInputs = old.value("inputs", json::array());
        for (size_t i = 0; i < std::min(oldInputs.size(), j["inputs"].size()); ++i)
            if (oldInputs[i] != j["inputs"][i] && fs::exists(format::stepDir(outDir, static_cast<int>(i))))
                fail("{}: step {} was made from {}, now the input is {}; use another output directory",
                     outDir.string(), i, oldInputs[i].get<std::string>(), j["inputs"][i].get<std::string>());
    }
    // Leftovers of a killed run: temporary step directories are never valid.
    for (const auto& entry : fs::directory_iterator(outDir / "steps"))
        if (entry.path().filename().string().starts_with("."))
            fs::remove_all(entry.path());
    for (const auto& entry : fs::directory_iterator(outDir))
        if (entry.path().filename().string().starts_with(".") &&
            entry.path().filename().string().find(".tmp-") != std::string::npos)
            fs::remove_all(entry.path());
    writeFileAtomic(manifestPath, j.dump(1));

    // The sample's grid points are the same for every step, so lines are comparable over time.
    const auto cells = drawVolumeWeightedSample(header.grid, sampleRows, options.seed);
    if (!fs::exists(outDir / format::kSampleCoords)) {
        const auto coords = sampleCoordinates(header.grid, cells);
        writeFileAtomic(outDir / format::kSampleCoords, std::as_bytes(std::span(coords)));
    }

    PreprocessSummary summary;
    std::vector<json> stepJsons(inputs.size());
    std::vector<int> todo;
    for (size_t s = 0; s < inputs.size(); ++s) {
        const fs::path stepPath = format::stepDir(outDir, static_cast<int>(s));
        if (fs::exists(stepPath / format::kStepManifest)) {
            stepJsons[s] = json::parse(readFile(stepPath / format::kStepManifest));
            ++summary.stepsSkipped;
        } else {
            if (fs::exists(stepPath))
                fs::remove_all(stepPath);
            todo.push_back(static_cast<int>(s));
        }
    }
    if (summary.stepsSkipped > 0 && !options.quiet)
        spdlog::info("{}: {} of {} steps already done by an earlier run, skipping them", outDir.string(),
                     summary.stepsSkipped, inputs.size());

    std::optional<Progress> progress;
    if (!options.quiet && !todo.empty())
        progress.emplace("preprocess", static_cast<int64_t>(todo.size()), "steps");
    try {
        for (const int s : todo) {
            const fs::path& input = inputs[s];
            const auto stepStart = std::chrono::steady_clock::now();
            auto elapsed = [&] { return std::chrono::duration<double>(std::chrono::steady_clock::now() - stepStart).count(); };
            Snapshot snap = readSnapshot(input, options.reader);
            spdlog::debug("{}: read in {:.2f} s", input.filename().string(), elapsed());
            if (!snap.grid.sameAs(header.grid))
                fail("{}: grid {}x{}x{} (lat x r x lon) or its coordinates differ from the first step's {}x{}x{} in {}",
                     input.string(), snap.grid.nLat(), snap.grid.nR(), snap.grid.nLon(), header.grid.nLat(),
                     header.grid.nR(), header.grid.nLon(), inputs.front().filename().string());
            addDerivedVariables(snap);
            RAYPC_CHECK_EQ(snap.fields.size(), specs.size());
            // The reader refused non-finite inputs; a finite input can still derive an infinity.
            for (const auto& field : snap.fields)
                checkFinite(snap, field, input.string());

            const fs::path finalDir = format::stepDir(outDir, s);
            const fs::path tmpDir = temporarySibling(finalDir);
            ScopeCleanup removeTmp([&] {
                std::error_code ec;
                fs::remove_all(tmpDir, ec);
            });
            json stepJson = {{"index", s}, {"time_myr", s * options.dtMyr}, {"source", input.filename().string()}};
            stepJson["stats"] = json::array();
            // Level by level: values and brick bounds of every variable; stats at full resolution.
            std::vector<std::vector<float>> current(snap.fields.size());
            for (size_t v = 0; v < snap.fields.size(); ++v)
                current[v] = std::move(snap.fields[v].values);
            // The sample reads full-resolution values.
            std::vector<float> sample(cells.size() * specs.size());
            std::vector<VariableStats> stats(specs.size());
            tbb::parallel_for(size_t(0), specs.size(), [&](size_t v) {
                stats[v] = computeStats(header.grid, current[v]);
                for (size_t i = 0; i < cells.size(); ++i)
                    sample[i * specs.size() + v] = current[v][cells[i]];
            });
            for (const auto& st : stats)
                stepJson["stats"].push_back(format::toJson(st));
            spdlog::debug("{}: derived, stats and sample done at {:.2f} s", input.filename().string(), elapsed());
            for (int level = 0; level < kLevelCount; ++level)
                fs::create_directories(format::levelDir(tmpDir, level));
            // Variables in parallel: writing into the page cache costs as much CPU as computing,
            // so both cores write while they compute bounds and coarser levels.
            tbb::parallel_for(size_t(0), specs.size(), [&](size_t v) {
                const auto stem = fileSafeName(specs[v].name);
                for (int level = 0; level < kLevelCount; ++level) {
                    const SphericalGrid& grid = levels[level];
                    const BrickLayout layout = BrickLayout::forGrid(grid, options.brickSize);
                    const fs::path dir = format::levelDir(tmpDir, level);
                    std::vector<float> bounds(2 * layout.brickCount());
                    computeBrickBounds(grid, layout, current[v], bounds);
                    writeArray(format::valuesFile(dir, stem), current[v]);
                    writeArray(format::boundsFile(dir, stem), bounds);
                    if (level + 1 < kLevelCount)
                        current[v] = coarsenField(grid, current[v]);
                }
            });
            writeArray(tmpDir / format::kStepSample, sample);
            {
                std::ofstream out(tmpDir / format::kStepManifest);
                out << stepJson.dump(1);
                if (!out)
                    fail("{}: write failed", (tmpDir / format::kStepManifest).string());
            }
            renameAtomic(tmpDir, finalDir);
            removeTmp.dismiss();
            leaveNothing.dismiss();
            spdlog::debug("{}: levels, bricks and files done at {:.2f} s", input.filename().string(), elapsed());
            stepJsons[s] = std::move(stepJson);
            ++summary.stepsWritten;
            if (progress)
                progress->advance();
        }
    } catch (const Error& e) {
        // What the run finished stays (the failed step's temporary directory does not).
        const int kept = summary.stepsWritten + summary.stepsSkipped;
        if (kept == 0)
            throw;
        throw Error(fmt::format("{} ({} finished steps stay in {}: a rerun resumes from them)", e.what(), kept,
                                outDir.string()));
    }
    if (progress)
        progress->finish();

    // Finalize: every step's stats and the global ranges and histograms in one manifest.
    j["steps"] = json::array();
    for (const auto& sj : stepJsons)
        j["steps"].push_back(sj);
    for (size_t v = 0; v < specs.size(); ++v) {
        std::vector<VariableStats> perStep;
        for (const auto& sj : stepJsons)
            perStep.push_back(format::statsFromJson(sj.at("stats").at(v)));
        VariableStats global;
        global.range = perStep.front().range;
        double mean = 0;
        for (const auto& st : perStep) {
            global.range.min = std::min(global.range.min, st.range.min);
            global.range.max = std::max(global.range.max, st.range.max);
            mean += st.mean / perStep.size();
        }
        global.mean = mean;
        global.histogram.assign(kHistogramBins, 0.0);
        for (const auto& st : perStep)
            rebinHistogram(st, global.range, global.histogram);
        for (double& h : global.histogram)
            h /= perStep.size();
        j["variables"][v]["global"] = format::toJson(global);
    }
    // Phase 2 reads the finished steps back: the manifest says "complete" only after it.
    writeFileAtomic(manifestPath, j.dump(1));
    writePathlines(outDir, header.grid, specs, stepJsons, options, summary);
    j["pathlines"] = options.pathlines.enabled ? pathlineSettings(options.pathlines) : json();
    j["status"] = "complete";
    writeFileAtomic(manifestPath, j.dump(1));
    summary.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    return summary;
}

}  // namespace raypc
