#include "dataset/dataset.h"

#include "core/atomic_file.h"
#include "core/clock.h"
#include "core/error.h"
#include "core/error_kinds.h"
#include "core/json_input.h"
#include "core/strings.h"
#include "dataset/bricks.h"
#include "dataset/dataset_format.h"

#include <fcntl.h>
#include <fmt/format.h>
#include <spdlog/spdlog.h>
#include <sys/file.h>
#include <sys/stat.h>
#include <unistd.h>

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>
#include <tbb/task_arena.h>

#include <cerrno>
#include <algorithm>
#include <cmath>
#include <cstring>
#include <limits>

namespace raypc::dataset {

namespace format {

std::filesystem::path stepDir(const std::filesystem::path& dataset, int step)
{
    return dataset / "steps" / fmt::format("{:04d}", step);
}

std::filesystem::path levelDir(const std::filesystem::path& stepDir, int level)
{
    return stepDir / fmt::format("L{}", level);
}

std::filesystem::path valuesFile(const std::filesystem::path& levelDir, const std::string& stem)
{
    return levelDir / (stem + ".f32");
}

std::filesystem::path encodedValuesFile(const std::filesystem::path& levelDir, const std::string& stem)
{
    return levelDir / (stem + ".u16");
}

std::filesystem::path boundsFile(const std::filesystem::path& levelDir, const std::string& stem)
{
    return levelDir / (stem + ".bricks.f32");
}

nlohmann::json toJson(const grid::SphericalGrid& grid)
{
    nlohmann::json j = {{"lat_deg", grid.latDeg}, {"r_km", grid.rKm}, {"lon_deg", grid.lonDeg}};
    if (grid.dataLatDeg)
        j["data_lat_deg"] = *grid.dataLatDeg;
    if (grid.dataLonDeg)
        j["data_lon_deg"] = *grid.dataLonDeg;
    return j;
}

grid::SphericalGrid gridFromJson(const nlohmann::json& j)
{
    grid::SphericalGrid g;
    g.latDeg = j.at("lat_deg").get<std::vector<double>>();
    g.rKm = j.at("r_km").get<std::vector<double>>();
    g.lonDeg = j.at("lon_deg").get<std::vector<double>>();
    if (j.contains("data_lat_deg"))
        g.dataLatDeg = j.at("data_lat_deg").get<std::array<double, 2>>();
    if (j.contains("data_lon_deg"))
        g.dataLonDeg = j.at("data_lon_deg").get<std::array<double, 2>>();
    return g;
}

nlohmann::json toJson(const VariableStats& stats)
{
    nlohmann::json j = {{"min", stats.range.min}, {"max", stats.range.max}, {"mean", stats.mean},
                        {"histogram", stats.histogram}};
    if (stats.missingPoints > 0) {
        j["missing_fraction"] = stats.missingFraction;
        j["missing_points"] = stats.missingPoints;
    }
    return j;
}

VariableStats statsFromJson(const nlohmann::json& j)
{
    VariableStats s;
    s.range = {j.at("min").get<float>(), j.at("max").get<float>()};
    s.mean = j.at("mean").get<double>();
    s.histogram = j.at("histogram").get<std::vector<double>>();
    s.missingFraction = j.value("missing_fraction", 0.0);
    s.missingPoints = j.value("missing_points", size_t(0));
    if (!(s.missingFraction >= 0 && s.missingFraction < 1))
        fail("missing_fraction {} is not within [0, 1)", s.missingFraction);
    return s;
}

}  // namespace format

std::shared_ptr<StepVolume> StepVolume::fromSnapshot(const grid::Snapshot& snapshot, uint32_t brickSize)
{
    auto volume = std::make_shared<StepVolume>();
    volume->m_grid = snapshot.grid;
    volume->m_bricks = grid::BrickLayout::forGrid(snapshot.grid, brickSize);
    const size_t n = snapshot.grid.cellCount();
    volume->m_owned.reserve(2 * snapshot.fields.size());  // references below must stay valid
    for (const auto& field : snapshot.fields) {
        if (field.values.size() != n)
            fail("{}: {} values, expected {} for the grid", field.name, field.values.size(), n);
        auto& values = volume->m_owned.emplace_back(field.values);
        auto& bounds = volume->m_owned.emplace_back(2 * volume->m_bricks.brickCount());
        computeBrickBounds(volume->m_grid, volume->m_bricks, values, bounds);
    }
    const size_t count = snapshot.fields.size();
    volume->m_valuesStorage = std::make_unique<std::atomic<const float*>[]>(count);
    volume->m_values = {volume->m_valuesStorage.get(), count};
    for (size_t i = 0; i < count; ++i) {
        volume->m_values[i].store(volume->m_owned[2 * i].data());
        volume->m_bounds.push_back(volume->m_owned[2 * i + 1].data());
    }
    volume->m_storedCount = count;
    return volume;
}

std::shared_ptr<StepVolume> StepVolume::withVariable(std::shared_ptr<const StepVolume> base, std::vector<float> values)
{
    RAYPC_CHECK(base);
    if (values.size() != base->grid().cellCount())
        fail("derived variable: {} values, expected {} for the grid", values.size(), base->grid().cellCount());
    auto volume = std::make_shared<StepVolume>();
    volume->m_grid = base->grid();
    volume->m_bricks = base->bricks();
    const size_t count = base->variableCount() + 1;
    volume->m_valuesStorage = std::make_unique<std::atomic<const float*>[]>(count);
    volume->m_values = {volume->m_valuesStorage.get(), count};
    for (size_t i = 0; i + 1 < count; ++i) {
        // Not decoded by the base yet: decode() asks the base on first use.
        volume->m_values[i].store(base->valuesReady(i) ? base->values(i) : nullptr);
        volume->m_bounds.push_back(nullptr);  // brickBounds asks the base (a computed variable's are made on use)
    }
    volume->m_storedCount = count;
    volume->m_owned.reserve(2);  // references below must stay valid
    auto& own = volume->m_owned.emplace_back(std::move(values));
    auto& bounds = volume->m_owned.emplace_back(2 * volume->m_bricks.brickCount());
    computeBrickBounds(volume->m_grid, volume->m_bricks, own, bounds);
    volume->m_values[count - 1].store(own.data());
    volume->m_bounds.push_back(bounds.data());
    volume->m_base = std::move(base);
    return volume;
}

std::shared_ptr<StepVolume> StepVolume::open(const std::filesystem::path& dir, const LevelInfo& level,
                                             const std::vector<std::string>& fileStems, ValueEncoding encoding,
                                             std::span<const ValueRange> ranges, std::span<const char> missing,
                                             std::span<const ShellAnomalyOf> computed,
                                             std::span<const std::vector<double>> shellMeans)
{
    RAYPC_CHECK(ranges.empty() || ranges.size() == fileStems.size());
    RAYPC_CHECK(missing.empty() || missing.size() == fileStems.size());
    for (const ShellAnomalyOf& c : computed)
        RAYPC_CHECK(c.base < fileStems.size());
    RAYPC_CHECK(shellMeans.empty() || shellMeans.size() == fileStems.size());
    auto volume = std::make_shared<StepVolume>();
    volume->m_grid = level.grid;
    volume->m_bricks = level.bricks;
    volume->m_encoding = encoding;
    const size_t n = volume->m_grid.cellCount(), brickCount = volume->m_bricks.brickCount();
    const bool encoded = encoding == ValueEncoding::Uint16;
    const size_t valueBytes = n * (encoded ? sizeof(uint16_t) : sizeof(float));
    const size_t boundBytes = 2 * brickCount * sizeof(float);
    const size_t count = fileStems.size(), total = count + computed.size();
    volume->m_valuesStorage = std::make_unique<std::atomic<const float*>[]>(total);
    volume->m_values = {volume->m_valuesStorage.get(), total};
    volume->m_decoded.resize(total);
    volume->m_storedCount = count;
    volume->m_computed.assign(computed.begin(), computed.end());
    volume->m_computedBounds.resize(computed.size());
    for (size_t i = 0; i < shellMeans.size(); ++i)
        if (!shellMeans[i].empty()) {
            RAYPC_CHECK_EQ(shellMeans[i].size(), level.grid.nR());
            volume->m_shellMeans.emplace(i, shellMeans[i]);
        }
    if (encoding == ValueEncoding::Uint16)
        volume->m_pointDecoder.emplace(level.grid, level.bricks);
    volume->m_mapped.reserve(count);  // references below must stay valid
    volume->m_owned.reserve(count);
    volume->m_ranges.assign(count, ValueRange{-std::numeric_limits<float>::max(), std::numeric_limits<float>::max()});
    volume->m_missing.assign(count, 0);
    for (size_t i = 0; i < count; ++i) {
        if (!ranges.empty())
            volume->m_ranges[i] = ranges[i];
        if (!missing.empty())
            volume->m_missing[i] = missing[i];
        const ValueRange range = volume->m_ranges[i];
        const auto valuesPath = encoded ? format::encodedValuesFile(dir, fileStems[i]) : format::valuesFile(dir, fileStems[i]);
        const auto boundsPath = format::boundsFile(dir, fileStems[i]);
        const MappedFile& values = volume->m_mapped.emplace_back(valuesPath);
        if (values.size() != valueBytes)
            fail("{}: {} bytes, expected {} ({} points of {})", valuesPath.string(), values.size(), valueBytes, n,
                 encodingName(encoding));
        // The bounds are small (two floats per brick) and read by every pass: copied, so that a file cut
        // short later cannot take them away under a renderer (only the values stay mapped).
        const MappedFile boundsFile(boundsPath);
        if (boundsFile.size() != boundBytes)
            fail("{}: {} bytes, expected {}", boundsPath.string(), boundsFile.size(), boundBytes);
        const auto* stored = reinterpret_cast<const float*>(boundsFile.bytes().data());
        auto& bounds = volume->m_owned.emplace_back(stored, stored + 2 * brickCount);
        volume->m_bounds.push_back(bounds.data());
        // Decoding (u16) and brick skipping trust the bounds; checked here, where a bad file is an
        // error. Within the step's range (the manifest's exact statistics), so that a finite but
        // absurd bound (3.4e38) is refused too.
        // A variable with missing values may have bricks of nothing but them: (+inf, -inf).
        const bool mayBeEmpty = volume->m_missing[i];
        for (size_t b = 0; b < brickCount; ++b)
            if (!(bounds[2 * b] >= range.min && bounds[2 * b] <= bounds[2 * b + 1] && bounds[2 * b + 1] <= range.max) &&
                !(mayBeEmpty && bounds[2 * b] == INFINITY && bounds[2 * b + 1] == -INFINITY))
                fail("{}: brick {} has bounds ({}, {}), expected finite values with min <= max within the step's "
                     "range [{}, {}] (a damaged file; preprocess the step again)",
                     boundsPath.string(), b, bounds[2 * b], bounds[2 * b + 1], range.min, range.max);
        volume->m_valueFiles.push_back(values.bytes().data());
    }
    return volume;
}

namespace {

// The first index in `values` outside [min, max] (NaN included), or values.size().
size_t firstOutsideRange(std::span<const float> values, ValueRange range, bool missing)
{
    std::atomic<size_t> first{values.size()};
    tbb::parallel_for(tbb::blocked_range<size_t>(0, values.size(), size_t(1) << 16), [&](const auto& r) {
        if (r.begin() >= first.load(std::memory_order_relaxed))
            return;
        for (size_t i = r.begin(); i < r.end(); ++i)
            if (!(values[i] >= range.min && values[i] <= range.max) && !(missing && std::isnan(values[i]))) {
                size_t seen = first.load(std::memory_order_relaxed);
                while (i < seen && !first.compare_exchange_weak(seen, i, std::memory_order_relaxed)) {
                }
                return;
            }
    });
    return first.load();
}

}  // namespace

[[noreturn]] void StepVolume::failValue(size_t var, size_t index, float value) const
{
    const size_t iLon = index % m_grid.nLon(), iR = (index / m_grid.nLon()) % m_grid.nR(),
                 iLat = index / (m_grid.nLon() * m_grid.nR());
    fail("{}: point {} (lat {:.4g} deg, r {:.6g} km, lon {:.4g} deg) holds {}, expected a finite value within the "
         "step's range [{}, {}] (a damaged file; preprocess the step again)",
         m_mapped[var].path().string(), index, m_grid.latDeg[iLat], m_grid.rKm[iR], m_grid.lonDeg[iLon], value,
         m_ranges[var].min, m_ranges[var].max);
}

const ShellAnomalyOf* StepVolume::computedFrom(size_t var) const
{
    RAYPC_CHECK(var < variableCount());
    if (m_base && var < m_base->variableCount())
        return m_base->computedFrom(var);
    return var >= m_storedCount && var - m_storedCount < m_computed.size() ? &m_computed[var - m_storedCount] : nullptr;
}

const float* StepVolume::brickBounds(size_t var) const
{
    RAYPC_CHECK(var < variableCount());
    if (m_base && var < m_base->variableCount())
        return m_base->brickBounds(var);
    if (var >= m_storedCount) {
        values(var);  // computes the bounds with the values; both are ready once it returns
        return m_computedBounds[var - m_storedCount].data();
    }
    return m_bounds[var];
}

// A shell anomaly of this level: from the level's own values of its base and their shell means, so
// that every level of detail has anomalies about zero on each of its shells.
const float* StepVolume::compute(size_t var) const
{
    const ShellAnomalyOf& of = m_computed[var - m_storedCount];
    const size_t n = m_grid.cellCount();
    const std::span<const float> base(values(of.base), n);  // before the lock: it may decode
    std::lock_guard lock(m_computeMutex);
    if (const float* p = m_values[var].load(std::memory_order_acquire))
        return p;  // another thread computed it while this one waited
    auto out = makeSpareArray<float>(n);
    std::vector<float>& bounds = m_computedBounds[var - m_storedCount];
    bounds.resize(2 * m_bricks.brickCount());
    // Isolated: while this thread waits inside a parallel loop it must not pick up another task that
    // asks this volume for a computed variable and blocks on the lock it holds.
    tbb::this_task_arena::isolate([&] {
        auto means = m_shellMeans.find(of.base);
        if (means == m_shellMeans.end())
            means = m_shellMeans.emplace(of.base, shellMeans(m_grid, base)).first;
        computeShellAnomaly(m_grid, base, means->second, of.kind, {out.get(), n});
        computeBrickBounds(m_grid, m_bricks, {out.get(), n}, bounds);
    });
    const float* p = out.get();
    m_decoded[var] = std::move(out);
    m_decodedBytes.fetch_add(n * sizeof(float) + bounds.size() * sizeof(float), std::memory_order_relaxed);
    m_values[var].store(p, std::memory_order_release);
    return p;
}

StepVolume::PointValues StepVolume::pointValues(size_t var) const
{
    RAYPC_CHECK(var < variableCount());
    PointValues p;
    if (const float* v = m_values[var].load(std::memory_order_acquire)) {
        p.m_values = v;
        return p;
    }
    if (m_base && var < m_base->variableCount())
        return m_base->pointValues(var);
    if (var >= m_storedCount) {
        const ShellAnomalyOf& of = m_computed[var - m_storedCount];
        // The base read as its points are when its means need no decoding (kept, or its values ready);
        // else decoded first: the means then come from these values.
        if (shellMeansReady(of.base))
            p = pointValues(of.base);
        else
            p.m_values = values(of.base);
        p.m_means = shellMeansOf(of.base).data();
        p.m_kind = of.kind;
        return p;
    }
    if (m_encoding == ValueEncoding::Float32) {
        p.m_values = values(var);  // mapped: checked once as a whole
        return p;
    }
    m_mapped[var].checkNotCutShort();
    p.m_decoder = &*m_pointDecoder;
    p.m_encoded = static_cast<const uint16_t*>(m_valueFiles[var]);
    p.m_bounds = m_bounds[var];
    p.m_missing = hasMissing(var);
    return p;
}

bool StepVolume::pointValuesDirect(size_t var) const
{
    RAYPC_CHECK(var < variableCount());
    if (valuesReady(var))
        return true;
    if (m_base && var < m_base->variableCount())
        return m_base->pointValuesDirect(var);
    if (const ShellAnomalyOf* of = computedFrom(var))
        return !shellMeansReady(of->base) || pointValuesDirect(of->base);
    return m_encoding == ValueEncoding::Float32;
}

BrickCachedValues::BrickCachedValues(const StepVolume& volume, size_t var)
    : m_grid(&volume.grid()), m_bricks(volume.bricks()), m_points(volume.pointValues(var)),
      m_direct(volume.pointValuesDirect(var))
{
    if (m_direct)
        return;
    m_slot.assign(m_bricks.brickCount(), -1);
    const size_t s = m_bricks.size;
    m_brickPoints = s * s * s;
    const std::array<size_t, 3> n{m_grid->nLat(), m_grid->nR(), m_grid->nLon()};
    const std::array<size_t, 3> brickStride{size_t(m_bricks.count[1]) * m_bricks.count[2], m_bricks.count[2], 1};
    const std::array<size_t, 3> offsetStride{s * s, s, 1};
    for (size_t a = 0; a < 3; ++a)
        for (size_t i = 0; i < n[a]; ++i) {
            m_brickOf[a].push_back(uint32_t(i / s * brickStride[a]));
            m_offsetOf[a].push_back(uint32_t(i % s * offsetStride[a]));
        }
}

void BrickCachedValues::fill(size_t brick)
{
    const size_t s = m_bricks.size, slot = m_decoded.size() / (s * s * s);
    RAYPC_CHECK(slot < size_t(std::numeric_limits<int32_t>::max()));
    m_decoded.resize(m_decoded.size() + s * s * s, NAN);
    float* out = m_decoded.data() + slot * s * s * s;
    const size_t bLon = brick % m_bricks.count[2], bR = (brick / m_bricks.count[2]) % m_bricks.count[1],
                 bLat = brick / (size_t(m_bricks.count[2]) * m_bricks.count[1]);
    // The points the brick owns: [b·s, (b+1)·s) along each axis, cut at the grid's end.
    for (size_t iLat = bLat * s; iLat < std::min((bLat + 1) * s, m_grid->nLat()); ++iLat)
        for (size_t iR = bR * s; iR < std::min((bR + 1) * s, m_grid->nR()); ++iR)
            for (size_t iLon = bLon * s; iLon < std::min((bLon + 1) * s, m_grid->nLon()); ++iLon)
                out[m_offsetOf[0][iLat] + m_offsetOf[1][iR] + m_offsetOf[2][iLon]] =
                    m_points.at(m_grid->index(iLat, iR, iLon), iLat, iR, iLon);
    m_slot[brick] = int32_t(slot);
}

const float* StepVolume::decode(size_t var) const
{
    RAYPC_CHECK(var < variableCount());
    if (m_base && var < m_base->variableCount()) {
        const float* p = m_base->values(var);
        m_values[var].store(p, std::memory_order_release);
        return p;
    }
    if (var >= m_storedCount)
        return compute(var);
    std::lock_guard lock(m_decodeMutex);
    if (const float* p = m_values[var].load(std::memory_order_acquire))
        return p;  // another thread decoded it while this one waited
    RAYPC_CHECK(var < m_mapped.size());
    // The first read of a mapped array since it was opened: a file cut short meanwhile (a server
    // keeps steps for minutes) is an error here instead of SIGBUS in the loop below.
    m_mapped[var].checkNotCutShort();
    const size_t n = m_grid.cellCount();
    if (m_encoding == ValueEncoding::Float32) {
        // Mapped as they are; preprocessing never writes a value outside the step's range, so one that
        // is (NaN, Inf, 3.4e38 in a damaged file) is refused before anything computes with it. One
        // read of the array on first use, as a u16 variable's decoding is.
        const auto* values = static_cast<const float*>(m_valueFiles[var]);
        size_t bad = 0;
        tbb::this_task_arena::isolate([&] { bad = firstOutsideRange({values, n}, m_ranges[var], hasMissing(var)); });
        if (bad < n)
            failValue(var, bad, values[bad]);
        m_values[var].store(values, std::memory_order_release);
        return values;
    }
    const auto start = std::chrono::steady_clock::now();
    auto values = makeSpareArray<float>(n);
    // Isolated: while this thread waits inside the parallel loop it must not pick up another task
    // that asks this volume for values and blocks on the lock it holds.
    tbb::this_task_arena::isolate([&] {
        decodeUint16(m_grid, m_bricks, {static_cast<const uint16_t*>(m_valueFiles[var]), n},
                     {m_bounds[var], 2 * m_bricks.brickCount()}, {values.get(), n}, hasMissing(var));
    });
    spdlog::debug("decoded {} ({} points) in {:.1f} ms", m_mapped[var].path().string(), n, millisecondsSince(start));
    const float* p = values.get();
    m_decoded[var] = std::move(values);
    m_decodedBytes.fetch_add(n * sizeof(float), std::memory_order_relaxed);
    m_values[var].store(p, std::memory_order_release);
    return p;
}

float StepVolume::value(size_t var, size_t iLat, size_t iR, size_t iLon) const
{
    if (const float* p = m_values[var].load(std::memory_order_acquire))
        return p[m_grid.index(iLat, iR, iLon)];
    if (m_base && var < m_base->variableCount())
        return m_base->value(var, iLat, iR, iLon);
    if (const ShellAnomalyOf* of = computedFrom(var))
        return shellAnomalyValue(value(of->base, iLat, iR, iLon), shellMeansOf(of->base)[iR], of->kind);
    if (var >= m_storedCount)
        return values(var)[m_grid.index(iLat, iR, iLon)];
    m_mapped[var].checkNotCutShort();
    return mappedValue(var, iLat, iR, iLon);
}

bool StepVolume::shellMeansReady(size_t var) const
{
    RAYPC_CHECK(var < variableCount());
    {
        std::lock_guard lock(m_computeMutex);
        if (m_shellMeans.count(var))
            return true;
    }
    return valuesReady(var) || (m_encoding == ValueEncoding::Float32 && !m_base);
}

const std::vector<double>& StepVolume::shellMeansOf(size_t base) const
{
    RAYPC_CHECK(base < variableCount());
    {
        std::lock_guard lock(m_computeMutex);
        if (const auto all = m_shellMeans.find(base); all != m_shellMeans.end())
            return all->second;
    }
    // Every shell's mean at once (shellMeans, as compute() gets them): from the values when they are
    // at hand (decoded, or mapped float32), else from a decoded copy dropped at once, so that a few
    // point reads keep no array of the grid. Outside the lock (parallel loops); two threads may
    // compute them: the same bits. std::map: a reference handed out stays valid as others are added.
    const size_t n = m_grid.cellCount();
    std::vector<double> means;
    if (m_encoding == ValueEncoding::Uint16 && !valuesReady(base) && !(m_base && base < m_base->variableCount()) &&
        base < m_storedCount) {
        m_mapped[base].checkNotCutShort();
        std::vector<float> decoded(n);
        tbb::this_task_arena::isolate([&] {
            decodeUint16(m_grid, m_bricks, {static_cast<const uint16_t*>(m_valueFiles[base]), n},
                         {m_bounds[base], 2 * m_bricks.brickCount()}, decoded, hasMissing(base));
            means = shellMeans(m_grid, decoded);
        });
    } else {
        const std::span<const float> values(this->values(base), n);
        tbb::this_task_arena::isolate([&] { means = shellMeans(m_grid, values); });
    }
    std::lock_guard lock(m_computeMutex);
    return m_shellMeans.try_emplace(base, std::move(means)).first->second;
}

float StepVolume::mappedValue(size_t var, size_t iLat, size_t iR, size_t iLon) const
{
    if (m_encoding == ValueEncoding::Float32) {
        // Not yet checked as a whole (decode): this one value is.
        const size_t index = m_grid.index(iLat, iR, iLon);
        const float v = static_cast<const float*>(m_valueFiles[var])[index];
        if (!(v >= m_ranges[var].min && v <= m_ranges[var].max) && !(hasMissing(var) && std::isnan(v)))
            failValue(var, index, v);
        return v;
    }
    return decodeUint16Point(m_grid, m_bricks, static_cast<const uint16_t*>(m_valueFiles[var]), m_bounds[var], iLat,
                             iR, iLon, hasMissing(var));
}

void StepVolume::valuesInBox(size_t var, const std::array<size_t, 3>& begin, const std::array<size_t, 3>& end,
                             float* out) const
{
    RAYPC_CHECK(var < variableCount());
    const std::array<size_t, 3> n{m_grid.nLat(), m_grid.nR(), m_grid.nLon()};
    for (size_t a = 0; a < 3; ++a)
        RAYPC_CHECK(begin[a] <= end[a] && end[a] <= n[a]);
    const size_t nR = end[1] - begin[1], nLon = end[2] - begin[2];
    // A shell anomaly not computed yet: from its base's values on the box's whole shells, which their
    // means need (shellMean: the bits compute() gets from the whole step), not from the whole step.
    if (const ShellAnomalyOf* of = computedFrom(var); of && !valuesReady(var)) {
        const size_t nLatAll = m_grid.nLat(), nLonAll = m_grid.nLon();
        const auto w = m_grid.volumeFactors();
        std::vector<float> shell(nLatAll * nLonAll);
        for (size_t iR = begin[1]; iR < end[1]; ++iR) {
            valuesInBox(of->base, {0, iR, 0}, {nLatAll, iR + 1, nLonAll}, shell.data());
            const double mean = shellMean(w, shell.data(), nLonAll);
            for (size_t iLat = begin[0]; iLat < end[0]; ++iLat) {
                float* row = out + ((iLat - begin[0]) * nR + (iR - begin[1])) * nLon;
                for (size_t iLon = begin[2]; iLon < end[2]; ++iLon)
                    row[iLon - begin[2]] = shellAnomalyValue(shell[iLat * nLonAll + iLon], mean, of->kind);
            }
        }
        return;
    }
    // Decoded already, another volume's or computed: value() is a load, or computes the whole once.
    const bool mapped = !valuesReady(var) && !(m_base && var < m_base->variableCount()) && var < m_storedCount;
    if (mapped)
        m_mapped[var].checkNotCutShort();
    tbb::parallel_for(begin[0], end[0], [&](size_t iLat) {
        float* row = out + (iLat - begin[0]) * nR * nLon;
        for (size_t iR = begin[1]; iR < end[1]; ++iR, row += nLon)
            for (size_t iLon = begin[2]; iLon < end[2]; ++iLon)
                row[iLon - begin[2]] = mapped ? mappedValue(var, iLat, iR, iLon) : value(var, iLat, iR, iLon);
    });
}

double StepVolume::errorBound(size_t var, size_t iLat, size_t iR, size_t iLon) const
{
    RAYPC_CHECK(var < variableCount());
    if (m_base && var < m_base->variableCount())
        return m_base->errorBound(var, iLat, iR, iLon);
    if (m_encoding != ValueEncoding::Uint16)
        return 0;
    if (var >= m_storedCount) {
        // x - m: the point's error and the mean's (at most the largest on its shell); the percentage
        // 100 (x/m - 1) to first order 100 (ex/|m| + |x| em/m^2).
        const ShellAnomalyOf& of = m_computed[var - m_storedCount];
        const double ex = errorBound(of.base, iLat, iR, iLon), em = shellErrorBound(of.base, iR);
        if (of.kind == ShellAnomalyKind::Difference)
            return ex + em;
        values(var);  // the shell means
        double m = 0;
        {
            std::lock_guard lock(m_computeMutex);
            m = std::abs(m_shellMeans.at(of.base)[iR]);
        }
        const double x = std::abs(double(value(of.base, iLat, iR, iLon)));
        return 100.0 * (ex / m + x * em / (m * m));
    }
    const uint32_t s = m_bricks.size;
    const size_t brick = m_bricks.index(uint32_t(iLat / s), uint32_t(iR / s), uint32_t(iLon / s));
    return uint16ErrorBound(m_bounds[var][2 * brick], m_bounds[var][2 * brick + 1], hasMissing(var));
}

double StepVolume::shellErrorBound(size_t var, size_t iR) const
{
    const uint32_t s = m_bricks.size;
    double bound = 0;
    for (uint32_t bLat = 0; bLat < m_bricks.count[0]; ++bLat)
        for (uint32_t bLon = 0; bLon < m_bricks.count[2]; ++bLon) {
            const size_t brick = m_bricks.index(bLat, uint32_t(iR / s), bLon);
            bound = std::max(bound, uint16ErrorBound(m_bounds[var][2 * brick], m_bounds[var][2 * brick + 1], hasMissing(var)));
        }
    return bound;
}

size_t StepVolume::memoryBytes() const
{
    size_t bytes = decodedBytes();
    for (const auto& file : m_mapped)
        bytes += file.size();
    for (const auto& array : m_owned)
        bytes += array.size() * sizeof(float);
    if (m_base)
        bytes += m_base->memoryBytes();
    return bytes;
}

bool StepVolume::filesCutShort() const noexcept
{
    if (m_base && m_base->filesCutShort())
        return true;
    for (const auto& file : m_mapped)
        if (file.cutShort())
            return true;
    return false;
}

void StepVolume::adviseWillNeed() const noexcept
{
    if (m_base)
        m_base->adviseWillNeed();
    for (const auto& file : m_mapped)
        file.adviseWillNeed();
}

void StepVolume::dropResidentPages() const noexcept
{
    if (m_base)
        m_base->dropResidentPages();
    for (const auto& file : m_mapped)
        file.dropResidentPages();
}

void StepVolume::touchPages() const
{
    if (m_base)
        m_base->touchPages();
    volatile uint8_t sink = 0;
    for (const auto& file : m_mapped) {
        file.checkNotCutShort();
        const auto bytes = file.bytes();
        for (size_t i = 0; i < bytes.size(); i += 4096)
            sink = sink + uint8_t(bytes[i]);
    }
}

const float* StepVolume::brickBounds(size_t var, uint32_t brickSize) const
{
    RAYPC_CHECK(var < variableCount());
    if (brickSize == m_bricks.size)
        return brickBounds(var);
    std::lock_guard lock(m_derivedMutex);
    std::vector<float>& bounds = m_derivedBounds[{var, brickSize}];
    if (bounds.empty()) {
        const grid::BrickLayout layout = grid::BrickLayout::forGrid(m_grid, brickSize);
        bounds.resize(2 * layout.brickCount());
        const auto start = std::chrono::steady_clock::now();
        // Isolated: while this thread waits inside the parallel loop it must not pick up another
        // task that asks this volume for derived data and blocks on the lock it holds.
        tbb::this_task_arena::isolate(
            [&] { computeBrickBounds(m_grid, layout, {values(var), m_grid.cellCount()}, bounds); });
        spdlog::debug("brick bounds of variable {} at brick size {} in {:.1f} ms (decoding included)", var, brickSize,
                      millisecondsSince(start));
    }
    return bounds.data();
}

const grid::NodeGradient& StepVolume::nodeGradient(size_t var) const
{
    RAYPC_CHECK(var < variableCount());
    std::lock_guard lock(m_derivedMutex);
    auto it = m_gradients.find(var);
    if (it == m_gradients.end()) {
        const float* v = values(var);
        const auto start = std::chrono::steady_clock::now();
        it = m_gradients.emplace(var, tbb::this_task_arena::isolate([&] { return raypc::grid::nodeGradient(m_grid, v); }))
                 .first;  // isolated as above
        spdlog::debug("shading gradient of variable {} ({} points) in {:.1f} ms", var, m_grid.cellCount(),
                      millisecondsSince(start));
    }
    return it->second;
}

size_t StepVolume::dropGradients() const
{
    std::map<size_t, grid::NodeGradient> dropped;
    {
        std::lock_guard lock(m_derivedMutex);
        dropped.swap(m_gradients);
    }
    size_t bytes = 0;
    for (const auto& [var, g] : dropped)
        bytes += 3 * g.count * sizeof(float);
    return bytes;  // given back as `dropped` goes
}

namespace {

using nlohmann::json;

inline constexpr uint32_t kMaxBrickSize = 64;
inline constexpr size_t kMaxVariables = 1024;

// A short excerpt of a JSON value for a message (an outside file may hold anything). Containers are
// described, not printed: dump() recurses, and a manifest may nest deeply.
std::string excerpt(const json& value)
{
    if (value.is_array())
        return value.empty() ? "[]" : fmt::format("an array of {} entries", value.size());
    if (value.is_object())
        return value.empty() ? "{}" : fmt::format("an object of {} members", value.size());
    std::string text = value.dump();
    if (text.size() > 40)
        text = text.substr(0, 37) + "...";
    return text;
}

// Reads the manifest field by field; every problem is one raypc::Error
// "<manifest>: <field>: <found>, expected <what>", the field as a path (`levels[0].lat_deg[3]`).
class ManifestReader {
public:
    explicit ManifestReader(std::string file) : m_file(std::move(file)) {}

    template <typename... Args>
    [[noreturn]] void bad(const std::string& field, const std::string& found, fmt::format_string<Args...> expected,
                          Args&&... args) const
    {
        fail("{}: {}: {}, expected {}", m_file, field, found, fmt::format(expected, std::forward<Args>(args)...));
    }

    const json& member(const json& object, const std::string& objectField, const char* key) const
    {
        const std::string field = objectField.empty() ? key : objectField + "." + key;
        if (!object.is_object())
            bad(objectField.empty() ? "the manifest" : objectField, excerpt(object), "an object");
        const auto it = object.find(key);
        if (it == object.end())
            bad(field, "missing", "a value");
        return *it;
    }
    static std::string path(const std::string& objectField, const char* key)
    {
        return objectField.empty() ? key : objectField + "." + key;
    }
    static std::string path(const std::string& arrayField, size_t index)
    {
        return fmt::format("{}[{}]", arrayField, index);
    }

    std::string string(const json& object, const std::string& objectField, const char* key) const
    {
        const json& v = member(object, objectField, key);
        if (!v.is_string())
            bad(path(objectField, key), excerpt(v), "a string");
        return v.get<std::string>();
    }
    bool boolean(const json& object, const std::string& objectField, const char* key) const
    {
        const json& v = member(object, objectField, key);
        if (!v.is_boolean())
            bad(path(objectField, key), excerpt(v), "true or false");
        return v.get<bool>();
    }
    // An integer within [lo, hi].
    uint64_t integer(const json& v, const std::string& field, uint64_t lo, uint64_t hi) const
    {
        if (v.is_number_unsigned() && v.get<uint64_t>() >= lo && v.get<uint64_t>() <= hi)
            return v.get<uint64_t>();
        if (v.is_number_integer() && v.get<int64_t>() >= 0 && uint64_t(v.get<int64_t>()) >= lo &&
            uint64_t(v.get<int64_t>()) <= hi)
            return uint64_t(v.get<int64_t>());
        bad(field, excerpt(v), "an integer {}..{}", lo, hi);
    }
    uint64_t integer(const json& object, const std::string& objectField, const char* key, uint64_t lo,
                     uint64_t hi) const
    {
        return integer(member(object, objectField, key), path(objectField, key), lo, hi);
    }
    // A finite number.
    double number(const json& v, const std::string& field) const
    {
        if (!v.is_number() || !std::isfinite(v.get<double>()))
            bad(field, excerpt(v), "a finite number");
        return v.get<double>();
    }
    double number(const json& object, const std::string& objectField, const char* key) const
    {
        return number(member(object, objectField, key), path(objectField, key));
    }
    // A finite number that float32 holds.
    float float32(const json& object, const std::string& objectField, const char* key) const
    {
        const double v = number(object, objectField, key);
        if (std::abs(v) > double(std::numeric_limits<float>::max()))
            bad(path(objectField, key), excerpt(object.at(key)), "a finite float32 value");
        return static_cast<float>(v);
    }
    const json& array(const json& object, const std::string& objectField, const char* key, size_t minSize,
                      size_t maxSize) const
    {
        const json& v = member(object, objectField, key);
        if (!v.is_array())
            bad(path(objectField, key), excerpt(v), "an array");
        if (v.size() < minSize || v.size() > maxSize)
            bad(path(objectField, key), fmt::format("{} entries", v.size()), "{}..{}", minSize, maxSize);
        return v;
    }

    // One coordinate axis: finite numbers, strictly ascending, within [lo, hi] (`loOpen`: (lo, ...,
    // `hiOpen`: ..., hi)); `expected` says that in a message.
    std::vector<double> axis(const json& level, const std::string& levelField, const char* key, size_t minSize,
                             double lo, double hi, bool loOpen, bool hiOpen, const char* expected) const
    {
        const json& a = array(level, levelField, key, minSize, std::numeric_limits<size_t>::max());
        std::vector<double> values;
        values.reserve(a.size());
        for (size_t i = 0; i < a.size(); ++i) {
            const std::string field = path(path(levelField, key), i);
            const double v = number(a[i], field);
            if ((loOpen ? v <= lo : v < lo) || (hiOpen ? v >= hi : v > hi))
                bad(field, excerpt(a[i]), "{}", expected);
            if (i > 0 && v <= values.back())
                bad(field, fmt::format("{} after {}", excerpt(a[i]), values.back()), "strictly ascending values");
            values.push_back(v);
        }
        return values;
    }

    grid::SphericalGrid grid(const json& level, const std::string& field) const
    {
        grid::SphericalGrid g;
        g.latDeg = axis(level, field, "lat_deg", 1, -90, 90, false, false, "a value within [-90, 90] degrees");
        g.rKm = axis(level, field, "r_km", 1, 0, std::numeric_limits<double>::infinity(), true, false,
                     "a positive radius in km");
        g.lonDeg = axis(level, field, "lon_deg", 1, 0, 360, false, true, "a value within [0, 360) degrees");
        // A regional grid's extent of data (grid.h): south <= north within [-90, 90]; west, east in [0, 360).
        auto extent = [&](const char* key, double lo, double hi, bool ordered) -> std::optional<std::array<double, 2>> {
            if (!level.is_object() || !level.contains(key))
                return std::nullopt;
            const json& e = array(level, field, key, 2, 2);
            const std::array<double, 2> v{number(e[0], path(path(field, key), size_t(0))), number(e[1], path(path(field, key), size_t(1)))};
            if (!(v[0] >= lo && v[0] <= hi && v[1] >= lo && v[1] <= hi) || (ordered && v[0] > v[1]))
                bad(path(field, key), excerpt(e), "two values within [{}, {}]{}", lo, hi, ordered ? ", the first not larger" : "");
            return v;
        };
        g.dataLatDeg = extent("data_lat_deg", -90, 90, true);
        g.dataLonDeg = extent("data_lon_deg", 0, 360, false);
        return g;
    }

    VariableStats stats(const json& j, const std::string& field) const
    {
        VariableStats s;
        s.range = {float32(j, field, "min"), float32(j, field, "max")};
        if (!(s.range.min <= s.range.max))
            bad(path(field, "max"), excerpt(j.at("max")), "a value >= min ({})", s.range.min);
        s.mean = number(j, field, "mean");
        const json& h = array(j, field, "histogram", kHistogramBins, kHistogramBins);
        for (size_t i = 0; i < h.size(); ++i) {
            const double v = number(h[i], path(path(field, "histogram"), i));
            if (!(v >= 0 && v <= 1.0 + 1e-6))
                bad(path(path(field, "histogram"), i), excerpt(h[i]), "a volume fraction within [0, 1]");
            s.histogram.push_back(v);
        }
        if (j.is_object() && j.contains("missing_fraction")) {
            s.missingFraction = number(j, field, "missing_fraction");
            if (!(s.missingFraction >= 0 && s.missingFraction < 1))
                bad(path(field, "missing_fraction"), excerpt(j.at("missing_fraction")), "a volume fraction within [0, 1)");
            const json& points = member(j, field, "missing_points");
            if (!points.is_number_unsigned() || points.get<uint64_t>() == 0)
                bad(path(field, "missing_points"), excerpt(points), "a positive count of grid points");
            s.missingPoints = points.get<size_t>();
        }
        return s;
    }

    const std::string& file() const { return m_file; }

private:
    std::string m_file;
};

// Whether `stem` names a file inside a level directory: letters, digits, '-', '.', '_', not "." or "..".
bool plainFileStem(const std::string& stem)
{
    if (stem.empty() || stem == "." || stem == ".." || stem.size() > 200)
        return false;
    return std::all_of(stem.begin(), stem.end(), [](char c) {
        return (c >= 'a' && c <= 'z') || (c >= 'A' && c <= 'Z') || (c >= '0' && c <= '9') || c == '-' || c == '.' ||
               c == '_';
    });
}

// The size of `file` must be `expected` bytes (`what` says where that comes from).
void checkFileSize(const std::filesystem::path& file, uint64_t expected, const std::string& what)
{
    std::error_code ec;
    const uintmax_t size = std::filesystem::file_size(file, ec);
    if (ec)
        fail("{}: {}, expected {} bytes ({})", file.string(), ec.message(), expected, what);
    if (size != expected)
        fail("{}: {} bytes, expected {} ({}; a damaged dataset: preprocess it again)", file.string(), size, expected,
             what);
}

// The manifest's format and version (one this raypc reads), and so the encoding of its arrays.
ValueEncoding readFormat(const ManifestReader& r, const json& j, const std::filesystem::path& manifestPath)
{
    const std::string formatName = r.string(j, "", "format");
    if (formatName != format::kFormatName)
        r.bad("format", excerpt(j.at("format")), "'{}'", format::kFormatName);
    const json& versionField = r.member(j, "", "version");
    if (!versionField.is_number_integer())
        r.bad("version", excerpt(versionField), "an integer");
    const int64_t version = versionField.get<int64_t>();
    if (version < format::kOldestReadableVersion || version > format::kVersion)
        fail("{}: format version {}, this raypc reads versions {} to {}", manifestPath.string(), version,
             format::kOldestReadableVersion, format::kVersion);
    // Version 1 stored float32 only; version 2 names its encoding.
    return version == 1 ? ValueEncoding::Float32 : parseEncoding(r.string(j, "", "encoding"), manifestPath.string());
}

// Levels: level 0 a valid global grid; each coarser one level 0 merged in pairs (docs/format.md).
std::vector<LevelInfo> readLevels(const ManifestReader& r, const json& j, const std::filesystem::path& manifestPath,
                                  uint32_t brickSize)
{
    std::vector<LevelInfo> out;
    const json& levels = r.array(j, "", "levels", 1, kLevelCount);
    for (size_t l = 0; l < levels.size(); ++l) {
        const std::string field = ManifestReader::path("levels", l);
        LevelInfo info;
        info.grid = r.grid(levels[l], field);
        if (l == 0) {
            info.grid.validate(fmt::format("{}: {}", manifestPath.string(), field));
            const double points = double(info.grid.nLat()) * double(info.grid.nR()) * double(info.grid.nLon());
            if (points > double(grid::kMaxGridPoints))
                r.bad(field, fmt::format("{}x{}x{} points", info.grid.nLat(), info.grid.nR(), info.grid.nLon()),
                      "at most {} points", grid::kMaxGridPoints);
        } else {
            const grid::SphericalGrid expected = out.back().grid.coarsened();
            const std::pair<const char*, std::pair<const std::vector<double>*, const std::vector<double>*>> axes[] = {
                {"lat_deg", {&info.grid.latDeg, &expected.latDeg}},
                {"r_km", {&info.grid.rKm, &expected.rKm}},
                {"lon_deg", {&info.grid.lonDeg, &expected.lonDeg}}};
            for (const auto& [key, arrays] : axes) {
                const auto& [got, want] = arrays;
                const std::string axisField = ManifestReader::path(field, key);
                if (got->size() != want->size())
                    r.bad(axisField, fmt::format("{} values", got->size()),
                          "{} (level {}'s merged in pairs)", want->size(), l - 1);
                for (size_t i = 0; i < got->size(); ++i)
                    if (std::abs((*got)[i] - (*want)[i]) > 1e-6 * std::max(1.0, std::abs((*want)[i])))
                        r.bad(ManifestReader::path(axisField, i), fmt::format("{}", (*got)[i]),
                              "{} (the mean of level {}'s pair)", (*want)[i], l - 1);
            }
        }
        info.bricks = grid::BrickLayout::forGrid(info.grid, brickSize);
        out.push_back(std::move(info));
    }
    return out;
}

// Variables: unique names and file stems, exact global statistics.
std::vector<VariableInfo> readVariables(const ManifestReader& r, const json& j)
{
    std::vector<VariableInfo> out;
    const json& variables = r.array(j, "", "variables", 1, kMaxVariables);
    for (size_t i = 0; i < variables.size(); ++i) {
        const std::string field = ManifestReader::path("variables", i);
        const json& v = variables[i];
        VariableInfo info;
        info.name = r.string(v, field, "name");
        if (info.name.empty())
            r.bad(ManifestReader::path(field, "name"), "\"\"", "a name");
        info.units = r.string(v, field, "units");
        info.derived = r.boolean(v, field, "derived");
        if (v.is_object() && v.contains("source"))
            info.source = r.string(v, field, "source");
        if (v.is_object() && v.contains("long_name"))
            info.longName = r.string(v, field, "long_name");
        // Datasets written before computed variables existed store every variable.
        if (v.is_object() && v.contains("stored"))
            info.stored = r.boolean(v, field, "stored");
        if (info.stored) {
            if (std::any_of(out.begin(), out.end(), [](const VariableInfo& o) { return !o.stored; }))
                r.bad(ManifestReader::path(field, "stored"), "true after a computed variable",
                      "every stored variable before the computed ones");
            info.fileStem = r.string(v, field, "file_stem");
            if (!plainFileStem(info.fileStem))
                r.bad(ManifestReader::path(field, "file_stem"), excerpt(v.at("file_stem")),
                      "a file name of letters, digits, '-', '.' and '_'");
        } else {
            // A computed variable: its kind, and in `source` the stored variable it is computed from.
            const std::string kind = r.string(v, field, "kind");
            const auto parsed = parseShellAnomalyKind(kind);
            if (!parsed)
                r.bad(ManifestReader::path(field, "kind"), excerpt(v.at("kind")), "'{}' or '{}'",
                      shellAnomalyKindName(ShellAnomalyKind::Difference), shellAnomalyKindName(ShellAnomalyKind::Percent));
            const auto base = std::find_if(out.begin(), out.end(),
                                           [&](const VariableInfo& o) { return o.stored && o.name == info.source; });
            if (base == out.end())
                r.bad(ManifestReader::path(field, "source"), fmt::format("'{}'", info.source),
                      "the name of a stored variable before it");
            info.computed = ShellAnomalyOf{size_t(base - out.begin()), *parsed};
        }
        for (const auto& other : out) {
            if (other.name == info.name)
                r.bad(ManifestReader::path(field, "name"), excerpt(v.at("name")), "a name no other variable has");
            if (info.stored && other.stored && other.fileStem == info.fileStem)
                r.bad(ManifestReader::path(field, "file_stem"), excerpt(v.at("file_stem")),
                      "a file stem no other variable has");
        }
        info.global = r.stats(r.member(v, field, "global"), ManifestReader::path(field, "global"));
        out.push_back(std::move(info));
    }
    return out;
}

// Per variable the shell means kept in `byName` (a manifest object at `field`, by variable name) of
// every variable a computed one is made from: `shells` numbers, null for a shell without a value;
// empty for the other variables. `level` names the level in a message ("" for none).
std::vector<std::vector<double>> readShellMeans(const ManifestReader& r, const json& byName, const std::string& field,
                                                const std::vector<VariableInfo>& variables, size_t shells,
                                                const std::string& level)
{
    if (!byName.is_object())
        r.bad(field, excerpt(byName), "an object of shell means by variable name");
    std::vector<std::vector<double>> out(variables.size());
    for (const VariableInfo& v : variables) {
        if (!v.computed || !out[v.computed->base].empty())
            continue;
        const std::string& baseName = variables[v.computed->base].name;
        const json& means = r.member(byName, field, baseName.c_str());
        const std::string baseField = fmt::format("{}[\"{}\"]", field, baseName);
        if (!means.is_array() || means.size() != shells)
            r.bad(baseField, excerpt(means), "an array of {} shell means (one per radius{})", shells, level);
        std::vector<double>& m = out[v.computed->base];
        for (size_t i = 0; i < shells; ++i)
            m.push_back(means[i].is_null() ? std::numeric_limits<double>::quiet_NaN()
                                           : r.number(means[i], ManifestReader::path(baseField, i)));
    }
    return out;
}

// Steps: in order (step i's arrays are in steps/i), times finite and increasing, statistics per variable
// within the global ones of `variables`.
std::vector<StepInfo> readSteps(const ManifestReader& r, const json& j, const std::vector<VariableInfo>& variables,
                                const std::vector<LevelInfo>& levels)
{
    const size_t shells = levels.front().grid.nR();
    std::vector<StepInfo> out;
    const json& steps = r.array(j, "", "steps", 1, 1000000);
    for (size_t s = 0; s < steps.size(); ++s) {
        const std::string field = ManifestReader::path("steps", s);
        const json& step = steps[s];
        StepInfo info;
        info.index = static_cast<int>(r.integer(step, field, "index", s, s));
        info.timeMyr = r.number(step, field, "time_myr");
        if (!out.empty() && !(info.timeMyr > out.back().timeMyr))
            r.bad(ManifestReader::path(field, "time_myr"),
                  fmt::format("{} after {}", info.timeMyr, out.back().timeMyr), "increasing times");
        info.source = r.string(step, field, "source");
        if (step.contains("origin")) {
            info.origin = step.at("origin");
            if (!info.origin.is_object())
                r.bad(ManifestReader::path(field, "origin"), excerpt(info.origin), "an object");
        }
        const json& stats = r.array(step, field, "stats", variables.size(), variables.size());
        for (size_t v = 0; v < stats.size(); ++v) {
            const std::string statsField = ManifestReader::path(ManifestReader::path(field, "stats"), v);
            VariableStats st = r.stats(stats[v], statsField);
            const ValueRange global = variables[v].global.range;
            if (st.range.min < global.min || st.range.max > global.max)
                r.bad(statsField, fmt::format("range [{}, {}]", st.range.min, st.range.max),
                      "a range within variables[{}].global [{}, {}]", v, global.min, global.max);
            info.stats.push_back(std::move(st));
        }
        // The level-0 shell means of every variable a computed one is made from (the sample's columns
        // of the computed variables are made with them): numbers, null for a shell without a value.
        const bool anyComputed = std::any_of(variables.begin(), variables.end(), [](const VariableInfo& v) { return bool(v.computed); });
        info.shellMeans = anyComputed ? readShellMeans(r, r.member(step, field, "shell_means"),
                                                       ManifestReader::path(field, "shell_means"), variables, shells, "")
                                      : std::vector<std::vector<double>>(variables.size());
        // Per level the same from the level's stored values (since 28 November 2026; optional: a
        // volume of a step without them computes them).
        if (step.contains("level_shell_means")) {
            const std::string levelsField = ManifestReader::path(field, "level_shell_means");
            const json& perLevel = r.array(step, field, "level_shell_means", levels.size(), levels.size());
            for (size_t l = 0; l < levels.size(); ++l)
                info.levelShellMeans.push_back(readShellMeans(r, perLevel[l], ManifestReader::path(levelsField, l),
                                                              variables, levels[l].grid.nR(),
                                                              fmt::format(" of level {}", l)));
        }
        out.push_back(std::move(info));
    }
    return out;
}

// The files: every array's size as the grid, the bricks and the encoding say, so that a damaged
// dataset is refused now, naming the file, and mapping never meets a short file.
void checkArrayFiles(const Dataset& dataset, size_t sampleRows, uint32_t brickSize)
{
    const std::filesystem::path& dir = dataset.dir();
    const std::vector<VariableInfo>& variables = dataset.variables();
    const bool encoded = dataset.encoding() == ValueEncoding::Uint16;
    const size_t valueSize = encoded ? sizeof(uint16_t) : sizeof(float);
    const std::string encoding(encodingName(dataset.encoding()));
    const size_t stored = size_t(std::count_if(variables.begin(), variables.end(), [](const auto& v) { return v.stored; }));
    for (size_t s = 0; s < dataset.steps().size(); ++s) {
        const auto stepDir = format::stepDir(dir, static_cast<int>(s));
        checkFileSize(stepDir / format::kStepSample, uint64_t(sampleRows) * stored * sizeof(float),
                      fmt::format("sample.rows {} x {} stored variables of float32", sampleRows, stored));
        for (size_t l = 0; l < dataset.levels().size(); ++l) {
            const auto levelDir = format::levelDir(stepDir, static_cast<int>(l));
            const LevelInfo& level = dataset.levels()[l];
            for (const auto& v : variables) {
                if (!v.stored)
                    continue;
                checkFileSize(encoded ? format::encodedValuesFile(levelDir, v.fileStem)
                                      : format::valuesFile(levelDir, v.fileStem),
                              uint64_t(level.grid.cellCount()) * valueSize,
                              fmt::format("levels[{}]: {} points of {}", l, level.grid.cellCount(), encoding));
                checkFileSize(format::boundsFile(levelDir, v.fileStem), uint64_t(level.bricks.brickCount()) * 2 * sizeof(float),
                              fmt::format("{} bricks of brick_size {} in levels[{}], two float32 each",
                                          level.bricks.brickCount(), brickSize, l));
            }
        }
    }
    checkFileSize(dir / format::kSampleCoords, uint64_t(sampleRows) * grid::coordinateInfos().size() * sizeof(float),
                  fmt::format("sample.rows {} x {} coordinates of float32", sampleRows, grid::coordinateInfos().size()));
    if (stored < variables.size())
        checkFileSize(dir / format::kSampleCells, uint64_t(sampleRows) * sizeof(uint32_t),
                      fmt::format("sample.rows {} grid-point indices of uint32", sampleRows));
}

}  // namespace

std::vector<std::vector<double>> readLevelShellMeans(const json& step, const std::string& what,
                                                     const std::vector<VariableInfo>& variables, size_t level,
                                                     size_t levelCount, size_t shells)
{
    RAYPC_CHECK(level < levelCount);
    if (!step.is_object() || !step.contains("level_shell_means"))
        return std::vector<std::vector<double>>(variables.size());
    const ManifestReader r(what);
    const json& perLevel = r.array(step, "", "level_shell_means", levelCount, levelCount);
    return readShellMeans(r, perLevel[level], ManifestReader::path("level_shell_means", level), variables, shells,
                          fmt::format(" of level {}", level));
}

std::shared_ptr<const Dataset> Dataset::open(const std::filesystem::path& dir)
{
    const auto manifestPath = dir / format::kManifest;
    if (!std::filesystem::is_directory(dir)) {
        // Nothing there is "not found"; a file where the directory should be is a wrong argument.
        std::error_code ec;
        if (!std::filesystem::exists(std::filesystem::symlink_status(dir, ec)))
            failNotFound("{}: not a directory (expected a RayPC dataset made by `raypc preprocess`)", dir.string());
        fail("{}: not a directory (expected a RayPC dataset made by `raypc preprocess`)", dir.string());
    }
    if (!std::filesystem::exists(manifestPath))
        failNotFound("{}: no {} (expected a RayPC dataset made by `raypc preprocess`)", dir.string(), format::kManifest);
    const json j = parseJsonInput(readFile(manifestPath), manifestPath.string());
    auto dataset = std::make_shared<Dataset>();
    dataset->m_dir = dir;
    // Every field is checked here, at open, so that what reads the dataset later (grids, bricks, the
    // kernels) may trust it: a manifest is outside input (a damaged or edited file), never an internal
    // check failing later.
    const ManifestReader r(manifestPath.string());
    dataset->m_encoding = readFormat(r, j, manifestPath);
    const std::string status = r.string(j, "", "status");
    if (status != "complete")
        fail("{}: preprocessing did not finish (status '{}'); run `raypc preprocess` again to resume", dir.string(),
             status);
    dataset->m_dtMyr = r.number(j, "", "dt_myr");
    if (!(dataset->m_dtMyr > 0))
        r.bad("dt_myr", excerpt(j.at("dt_myr")), "a positive number of Myr");
    const auto brickSize = static_cast<uint32_t>(r.integer(j, "", "brick_size", 1, kMaxBrickSize));
    dataset->m_levels = readLevels(r, j, manifestPath, brickSize);
    dataset->m_variables = readVariables(r, j);
    dataset->m_steps = readSteps(r, j, dataset->m_variables, dataset->m_levels);
    const json& sample = r.member(j, "", "sample");
    dataset->m_sampleRows = r.integer(sample, "sample", "rows", 0, grid::kMaxGridPoints);
    checkArrayFiles(*dataset, dataset->m_sampleRows, brickSize);
    return dataset;
}

std::vector<std::string> Dataset::variableNames() const
{
    std::vector<std::string> names;
    for (const auto& v : m_variables)
        names.push_back(v.name);
    return names;
}

int Dataset::variableIndex(const std::string& name) const
{
    for (size_t i = 0; i < m_variables.size(); ++i)
        if (m_variables[i].name == name)
            return static_cast<int>(i);
    return -1;
}

void Dataset::checkStep(int step, std::string_view what) const
{
    if (step < 0 || step >= static_cast<int>(m_steps.size()))
        failOutOfRange("{}: {} out of range 0..{}", what, step, m_steps.size() - 1);
}

void Dataset::checkLevel(int level, std::string_view what) const
{
    if (level < 0 || level >= static_cast<int>(m_levels.size()))
        failOutOfRange("{}: {} out of range 0..{}", what, level, m_levels.size() - 1);
}

std::shared_ptr<const StepVolume> Dataset::load(int step, int level) const
{
    checkStep(step, m_dir.string() + ": step");
    checkLevel(level, m_dir.string() + ": level");
    std::vector<std::string> stems;
    std::vector<ValueRange> ranges;
    std::vector<char> missing;
    std::vector<ShellAnomalyOf> computed;
    for (size_t v = 0; v < m_variables.size(); ++v) {
        if (m_variables[v].computed) {
            computed.push_back(*m_variables[v].computed);
            continue;
        }
        stems.push_back(m_variables[v].fileStem);
        ranges.push_back(m_steps[step].stats[v].range);
        missing.push_back(m_steps[step].stats[v].missingPoints > 0);
    }
    // The shell means kept in the manifest (stored variables come first: the same indices).
    std::span<const std::vector<double>> shellMeans;
    if (const auto& kept = m_steps[step].levelShellMeans; !kept.empty())
        shellMeans = std::span(kept[size_t(level)]).first(stems.size());
    return StepVolume::open(format::levelDir(format::stepDir(m_dir, step), level), m_levels[level], stems, m_encoding,
                            ranges, missing, computed, shellMeans);
}

SampleTable Dataset::loadSample(int step, SampleColumns which) const
{
    checkStep(step, m_dir.string() + ": step");
    const bool withCoords = which == SampleColumns::All;
    SampleTable table;
    if (withCoords)
        for (const auto& c : grid::coordinateInfos()) {
            table.columns.push_back(c.name);
            table.units.push_back(c.units);
        }
    for (const auto& v : m_variables) {
        table.columns.push_back(v.name);
        table.units.push_back(v.units);
    }
    const size_t nCoords = withCoords ? grid::coordinateInfos().size() : 0, nVars = m_variables.size(), rows = m_sampleRows;
    const size_t nStored = size_t(std::count_if(m_variables.begin(), m_variables.end(), [](const auto& x) { return x.stored; }));
    const MappedFile storedFile(format::stepDir(m_dir, step) / format::kStepSample);
    if (storedFile.size() != rows * nStored * sizeof(float))
        fail("{}: sample files do not hold {} rows", m_dir.string(), rows);
    const auto* stored = reinterpret_cast<const float*>(storedFile.bytes().data());
    // The computed variables' columns: from their base's column and the step's level-0 shell means at
    // each row's radius (the sample's grid points), as StepVolume computes them on level 0.
    std::vector<float> all;
    const float* v = stored;
    if (nStored < nVars) {
        const MappedFile cellFile(m_dir / format::kSampleCells);
        if (cellFile.size() != rows * sizeof(uint32_t))
            fail("{}: sample files do not hold {} rows", m_dir.string(), rows);
        const auto* cells = reinterpret_cast<const uint32_t*>(cellFile.bytes().data());
        const grid::SphericalGrid& g = m_levels.front().grid;
        all.resize(rows * nVars);
        for (size_t row = 0; row < rows; ++row) {
            if (cells[row] >= g.cellCount())
                fail("{}: sample point {} is grid point {}, beyond the grid's {}", (m_dir / format::kSampleCells).string(),
                     row, cells[row], g.cellCount());
            const size_t iR = (cells[row] / g.nLon()) % g.nR();
            for (size_t k = 0; k < nVars; ++k) {
                const auto& of = m_variables[k].computed;
                all[row * nVars + k] = of ? shellAnomalyValue(stored[row * nStored + of->base],
                                                              m_steps[step].shellMeans[of->base][iR], of->kind)
                                          : stored[row * nStored + k];
            }
        }
        v = all.data();
    }
    table.rows = rows;
    if (!withCoords) {
        table.values.assign(v, v + rows * nVars);
        return table;
    }
    const MappedFile coords(m_dir / format::kSampleCoords);
    if (coords.size() != rows * nCoords * sizeof(float))
        fail("{}: sample files do not hold {} rows", m_dir.string(), rows);
    const auto* c = reinterpret_cast<const float*>(coords.bytes().data());
    table.values.resize(rows * (nCoords + nVars));
    for (size_t row = 0; row < rows; ++row) {
        float* out = table.values.data() + row * (nCoords + nVars);
        std::copy_n(c + row * nCoords, nCoords, out);
        std::copy_n(v + row * nVars, nVars, out + nCoords);
    }
    return table;
}

DatasetWriteLock::DatasetWriteLock(const std::filesystem::path& dir) : m_path(dir / format::kLockFile)
{
    std::filesystem::create_directories(dir);
    // The holder may remove the file (removeFile) between our open and flock: then the lock we got
    // is on a file no longer at the path, and we try again with a new one.
    for (;;) {
        m_fd = ::open(m_path.c_str(), O_RDWR | O_CREAT | O_CLOEXEC, 0644);
        if (m_fd < 0)
            fail("{}: cannot open the lock file: {}", m_path.string(), std::strerror(errno));
        if (::flock(m_fd, LOCK_EX | LOCK_NB) != 0) {
            const int error = errno;
            char holder[256] = {};
            const ssize_t n = ::pread(m_fd, holder, sizeof holder - 1, 0);
            ::close(m_fd);
            m_fd = -1;
            if (error != EWOULDBLOCK)
                fail("{}: cannot lock: {}", m_path.string(), std::strerror(error));
            std::string who(holder, n > 0 ? static_cast<size_t>(n) : 0);
            while (!who.empty() && (who.back() == '\n' || who.back() == '\0'))
                who.pop_back();
            fail("{}: another raypc preprocess is writing this dataset ({}); wait for it to finish or use another "
                 "output directory",
                 dir.string(), who.empty() ? "pid unknown" : who);
        }
        struct stat held {}, atPath {};
        if (::fstat(m_fd, &held) == 0 && ::stat(m_path.c_str(), &atPath) == 0 && held.st_ino == atPath.st_ino &&
            held.st_dev == atPath.st_dev)
            break;
        ::close(m_fd);
    }
    char host[256] = {};
    ::gethostname(host, sizeof host - 1);
    const std::string who = fmt::format("pid {} on host {}\n", ::getpid(), host);
    if (::ftruncate(m_fd, 0) != 0 || ::pwrite(m_fd, who.data(), who.size(), 0) != static_cast<ssize_t>(who.size()))
        fail("{}: cannot write the lock file: {}", m_path.string(), std::strerror(errno));
}

DatasetWriteLock::~DatasetWriteLock()
{
    if (m_fd >= 0)
        ::close(m_fd);  // releases the lock
}

void DatasetWriteLock::removeFile()
{
    std::error_code ec;
    std::filesystem::remove(m_path, ec);
}

}  // namespace raypc::dataset
