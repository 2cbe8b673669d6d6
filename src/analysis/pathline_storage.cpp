#include "analysis/pathline_storage.h"

#include "core/atomic_file.h"
#include "core/error.h"
#include "core/json_input.h"

#include <fmt/format.h>
#include <nlohmann/json.hpp>

#include <algorithm>
#include <cstring>
#include <fstream>

namespace raypc::analysis {
namespace {

namespace fs = std::filesystem;
using nlohmann::json;

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

}  // namespace

fs::path pathlineDir(const fs::path& dataset, int step) { return dataset / "pathlines" / fmt::format("{:04d}", step); }

void writePathlineSet(const fs::path& dir, const PathlineSet& set)
{
    fs::create_directories(dir);
    json j;
    j["format"] = "raypc-pathlines";
    j["version"] = kPathlineSetVersion;
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

std::string noPathlinesReason(const fs::path& dataset)
{
    // The manifest's word (docs/format.md, dataset.json: no_pathlines), read for this message alone.
    try {
        const json j = parseJsonInput(readFile(dataset / "dataset.json"), (dataset / "dataset.json").string());
        if (j.is_object() && j.contains("no_pathlines") && j.at("no_pathlines").is_string())
            return j.at("no_pathlines").get<std::string>();
    } catch (const Error&) {
    }
    return "the dataset was preprocessed with --no-pathlines, or the step does not exist";
}

PathlineSet loadPathlineSet(const fs::path& dataset, int step)
{
    const fs::path dir = pathlineDir(dataset, step);
    const fs::path jsonPath = dir / "lines.json";
    if (!fs::exists(jsonPath))
        fail("{}: no pathlines for step {} ({})", dataset.string(), step, noPathlinesReason(dataset));
    PathlineSet set;
    try {
        const json j = parseJsonInput(readFile(jsonPath), jsonPath.string());
        // Version 1 (before the "seed persistence" column) reads as it is, with its own columns.
        const int version = j.at("format").get<std::string>() == "raypc-pathlines" ? j.at("version").get<int>() : 0;
        if (version < 1 || version > kPathlineSetVersion)
            fail("{}: not a raypc-pathlines file of version 1 to {}", jsonPath.string(), kPathlineSetVersion);
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

void checkPathlineWindow(int window, const std::string& what)
{
    if (window < 1 || window > kMaxPathlineWindow)
        fail("{}: {} out of range 1..{}", what, window, kMaxPathlineWindow);
}

std::vector<PathlineSet> loadPathlineWindow(const fs::path& dataset, int step, int window)
{
    checkPathlineWindow(window);
    std::vector<PathlineSet> sets;
    for (int s = std::max(0, step - window + 1); s <= step; ++s)
        sets.push_back(loadPathlineSet(dataset, s));
    return sets;
}

}  // namespace raypc::analysis
