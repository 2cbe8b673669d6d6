#include "data/dataset.h"

#include "core/atomic_file.h"
#include "core/error.h"
#include "core/json_input.h"
#include "core/strings.h"
#include "data/bricks.h"
#include "data/dataset_format.h"

#include <fcntl.h>
#include <fmt/format.h>
#include <sys/file.h>
#include <sys/stat.h>
#include <unistd.h>

#include <tbb/task_arena.h>

#include <cerrno>
#include <cmath>
#include <cstring>

namespace raypc {

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

nlohmann::json toJson(const SphericalGrid& grid)
{
    return {{"lat_deg", grid.latDeg}, {"r_km", grid.rKm}, {"lon_deg", grid.lonDeg}};
}

SphericalGrid gridFromJson(const nlohmann::json& j)
{
    SphericalGrid g;
    g.latDeg = j.at("lat_deg").get<std::vector<double>>();
    g.rKm = j.at("r_km").get<std::vector<double>>();
    g.lonDeg = j.at("lon_deg").get<std::vector<double>>();
    return g;
}

nlohmann::json toJson(const VariableStats& stats)
{
    return {{"min", stats.range.min}, {"max", stats.range.max}, {"mean", stats.mean},
            {"histogram", stats.histogram}};
}

VariableStats statsFromJson(const nlohmann::json& j)
{
    VariableStats s;
    s.range = {j.at("min").get<float>(), j.at("max").get<float>()};
    s.mean = j.at("mean").get<double>();
    s.histogram = j.at("histogram").get<std::vector<double>>();
    return s;
}

}  // namespace format

std::shared_ptr<StepVolume> StepVolume::fromSnapshot(const Snapshot& snapshot, uint32_t brickSize)
{
    auto volume = std::make_shared<StepVolume>();
    volume->m_grid = snapshot.grid;
    volume->m_bricks = BrickLayout::forGrid(snapshot.grid, brickSize);
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
    return volume;
}

std::shared_ptr<StepVolume> StepVolume::open(const std::filesystem::path& dir, const LevelInfo& level,
                                             const std::vector<std::string>& fileStems, ValueEncoding encoding)
{
    auto volume = std::make_shared<StepVolume>();
    volume->m_grid = level.grid;
    volume->m_bricks = level.bricks;
    volume->m_encoding = encoding;
    const size_t n = volume->m_grid.cellCount(), brickCount = volume->m_bricks.brickCount();
    const bool encoded = encoding == ValueEncoding::Uint16;
    const size_t valueBytes = n * (encoded ? sizeof(uint16_t) : sizeof(float));
    const size_t boundBytes = 2 * brickCount * sizeof(float);
    const size_t count = fileStems.size();
    volume->m_valuesStorage = std::make_unique<std::atomic<const float*>[]>(count);
    volume->m_values = {volume->m_valuesStorage.get(), count};
    volume->m_decoded.resize(count);
    volume->m_mapped.reserve(2 * count);  // references below must stay valid
    for (size_t i = 0; i < count; ++i) {
        const auto valuesPath = encoded ? format::encodedValuesFile(dir, fileStems[i]) : format::valuesFile(dir, fileStems[i]);
        const auto boundsPath = format::boundsFile(dir, fileStems[i]);
        const MappedFile& values = volume->m_mapped.emplace_back(valuesPath);
        if (values.size() != valueBytes)
            fail("{}: {} bytes, expected {} ({} points of {})", valuesPath.string(), values.size(), valueBytes, n,
                 encodingName(encoding));
        const MappedFile& boundsFile = volume->m_mapped.emplace_back(boundsPath);
        if (boundsFile.size() != boundBytes)
            fail("{}: {} bytes, expected {}", boundsPath.string(), boundsFile.size(), boundBytes);
        const auto* bounds = reinterpret_cast<const float*>(boundsFile.bytes().data());
        volume->m_bounds.push_back(bounds);
        if (encoded) {
            // Decoding trusts the bounds (value_encoding.h); checked here, where a bad file is an error.
            for (size_t b = 0; b < brickCount; ++b)
                if (!(std::isfinite(bounds[2 * b]) && std::isfinite(bounds[2 * b + 1]) &&
                      bounds[2 * b] <= bounds[2 * b + 1]))
                    fail("{}: brick {} has bounds ({}, {}), expected finite values with min <= max (a damaged "
                         "file; preprocess the step again)",
                         boundsPath.string(), b, bounds[2 * b], bounds[2 * b + 1]);
            volume->m_encoded.push_back(reinterpret_cast<const uint16_t*>(values.bytes().data()));
        } else {
            volume->m_values[i].store(reinterpret_cast<const float*>(values.bytes().data()));
        }
    }
    return volume;
}

const float* StepVolume::decode(size_t var) const
{
    RAYPC_CHECK(var < variableCount());
    std::lock_guard lock(m_decodeMutex);
    if (const float* p = m_values[var].load(std::memory_order_acquire))
        return p;  // another thread decoded it while this one waited
    RAYPC_CHECK(m_encoding == ValueEncoding::Uint16);
    const size_t n = m_grid.cellCount();
    auto values = std::make_unique_for_overwrite<float[]>(n);
    // Isolated: while this thread waits inside the parallel loop it must not pick up another task
    // that asks this volume for values and blocks on the lock it holds.
    tbb::this_task_arena::isolate([&] {
        decodeUint16(m_grid, m_bricks, {m_encoded[var], n}, {m_bounds[var], 2 * m_bricks.brickCount()},
                     {values.get(), n});
    });
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
    return decodeUint16Point(m_grid, m_bricks, m_encoded[var], m_bounds[var], iLat, iR, iLon);
}

double StepVolume::errorBound(size_t var, size_t iLat, size_t iR, size_t iLon) const
{
    RAYPC_CHECK(var < variableCount());
    if (m_encoding != ValueEncoding::Uint16)
        return 0;
    const uint32_t s = m_bricks.size;
    const size_t brick = m_bricks.index(uint32_t(iLat / s), uint32_t(iR / s), uint32_t(iLon / s));
    return uint16ErrorBound(m_bounds[var][2 * brick], m_bounds[var][2 * brick + 1]);
}

size_t StepVolume::memoryBytes() const
{
    size_t bytes = decodedBytes();
    for (const auto& file : m_mapped)
        bytes += file.size();
    for (const auto& array : m_owned)
        bytes += array.size() * sizeof(float);
    return bytes;
}

void StepVolume::touchPages() const
{
    volatile uint8_t sink = 0;
    for (const auto& file : m_mapped) {
        const auto bytes = file.bytes();
        for (size_t i = 0; i < bytes.size(); i += 4096)
            sink = sink + uint8_t(bytes[i]);
    }
}

const float* StepVolume::brickBounds(size_t var, uint32_t brickSize) const
{
    RAYPC_CHECK(var < variableCount());
    if (brickSize == m_bricks.size)
        return m_bounds[var];
    std::lock_guard lock(m_derivedMutex);
    std::vector<float>& bounds = m_derivedBounds[{var, brickSize}];
    if (bounds.empty()) {
        const BrickLayout layout = BrickLayout::forGrid(m_grid, brickSize);
        bounds.resize(2 * layout.brickCount());
        // Isolated: while this thread waits inside the parallel loop it must not pick up another
        // task that asks this volume for derived data and blocks on the lock it holds.
        tbb::this_task_arena::isolate(
            [&] { computeBrickBounds(m_grid, layout, {values(var), m_grid.cellCount()}, bounds); });
    }
    return bounds.data();
}

const NodeGradient& StepVolume::nodeGradient(size_t var) const
{
    RAYPC_CHECK(var < variableCount());
    std::lock_guard lock(m_derivedMutex);
    auto it = m_gradients.find(var);
    if (it == m_gradients.end())
        it = m_gradients
                 .emplace(var, tbb::this_task_arena::isolate([&] { return raypc::nodeGradient(m_grid, values(var)); }))
                 .first;  // isolated as above
    return it->second;
}

std::shared_ptr<const Dataset> Dataset::open(const std::filesystem::path& dir)
{
    const auto manifestPath = dir / format::kManifest;
    if (!std::filesystem::is_directory(dir))
        fail("{}: not a directory (expected a RayPC dataset made by `raypc preprocess`)", dir.string());
    if (!std::filesystem::exists(manifestPath))
        fail("{}: no {} (expected a RayPC dataset made by `raypc preprocess`)", dir.string(), format::kManifest);
    nlohmann::json j = parseJsonInput(readFile(manifestPath), manifestPath.string());
    auto dataset = std::make_shared<Dataset>();
    dataset->m_dir = dir;
    try {
        if (j.at("format").get<std::string>() != format::kFormatName)
            fail("{}: format is '{}', expected '{}'", manifestPath.string(), j.at("format").get<std::string>(),
                 format::kFormatName);
        const int version = j.at("version").get<int>();
        if (version < format::kOldestReadableVersion || version > format::kVersion)
            fail("{}: format version {}, this raypc reads versions {} to {}", manifestPath.string(), version,
                 format::kOldestReadableVersion, format::kVersion);
        // Version 1 stored float32 only; version 2 names its encoding.
        dataset->m_encoding = version == 1 ? ValueEncoding::Float32
                                           : parseEncoding(j.at("encoding").get<std::string>(), manifestPath.string());
        if (j.at("status").get<std::string>() != "complete")
            fail("{}: preprocessing did not finish (status '{}'); run `raypc preprocess` again to resume",
                 dir.string(), j.at("status").get<std::string>());
        dataset->m_dtMyr = j.at("dt_myr").get<double>();
        const uint32_t brickSize = j.at("brick_size").get<uint32_t>();
        for (const auto& level : j.at("levels")) {
            LevelInfo info;
            info.grid = format::gridFromJson(level);
            info.bricks = BrickLayout::forGrid(info.grid, brickSize);
            dataset->m_levels.push_back(std::move(info));
        }
        for (const auto& v : j.at("variables")) {
            VariableInfo info;
            info.name = v.at("name").get<std::string>();
            info.units = v.at("units").get<std::string>();
            info.derived = v.at("derived").get<bool>();
            info.fileStem = v.at("file_stem").get<std::string>();
            info.global = format::statsFromJson(v.at("global"));
            dataset->m_variables.push_back(std::move(info));
        }
        for (const auto& s : j.at("steps")) {
            StepInfo info;
            info.index = s.at("index").get<int>();
            info.timeMyr = s.at("time_myr").get<double>();
            info.source = s.at("source").get<std::string>();
            for (const auto& st : s.at("stats"))
                info.stats.push_back(format::statsFromJson(st));
            if (info.stats.size() != dataset->m_variables.size())
                fail("{}: step {} has stats for {} variables, expected {}", manifestPath.string(), info.index,
                     info.stats.size(), dataset->m_variables.size());
            dataset->m_steps.push_back(std::move(info));
        }
        dataset->m_sampleRows = j.at("sample").at("rows").get<size_t>();
    } catch (const nlohmann::json::exception& e) {
        fail("{}: malformed manifest: {}", manifestPath.string(), e.what());
    }
    if (dataset->m_levels.empty() || dataset->m_steps.empty() || dataset->m_variables.empty())
        fail("{}: the manifest lists no levels, steps or variables", manifestPath.string());
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
        fail("{}: {} out of range 0..{}", what, step, m_steps.size() - 1);
}

void Dataset::checkLevel(int level, std::string_view what) const
{
    if (level < 0 || level >= static_cast<int>(m_levels.size()))
        fail("{}: {} out of range 0..{}", what, level, m_levels.size() - 1);
}

std::shared_ptr<const StepVolume> Dataset::load(int step, int level) const
{
    if (step < 0 || step >= static_cast<int>(m_steps.size()))
        fail("{}: step {} out of range, the dataset has steps 0..{}", m_dir.string(), step, m_steps.size() - 1);
    if (level < 0 || level >= static_cast<int>(m_levels.size()))
        fail("{}: level {} out of range, the dataset has levels 0..{}", m_dir.string(), level,
             m_levels.size() - 1);
    std::vector<std::string> stems;
    for (const auto& v : m_variables)
        stems.push_back(v.fileStem);
    return StepVolume::open(format::levelDir(format::stepDir(m_dir, step), level), m_levels[level], stems, m_encoding);
}

SampleTable Dataset::loadSample(int step, SampleColumns which) const
{
    if (step < 0 || step >= static_cast<int>(m_steps.size()))
        fail("{}: step {} out of range, the dataset has steps 0..{}", m_dir.string(), step, m_steps.size() - 1);
    const bool withCoords = which == SampleColumns::All;
    SampleTable table;
    if (withCoords)
        for (const auto& c : coordinateInfos()) {
            table.columns.push_back(c.name);
            table.units.push_back(c.units);
        }
    for (const auto& v : m_variables) {
        table.columns.push_back(v.name);
        table.units.push_back(v.units);
    }
    const size_t nCoords = withCoords ? coordinateInfos().size() : 0, nVars = m_variables.size(), rows = m_sampleRows;
    const MappedFile vars(format::stepDir(m_dir, step) / format::kStepSample);
    if (vars.size() != rows * nVars * sizeof(float))
        fail("{}: sample files do not hold {} rows", m_dir.string(), rows);
    const auto* v = reinterpret_cast<const float*>(vars.bytes().data());
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

}  // namespace raypc
