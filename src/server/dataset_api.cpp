#include "server/dataset_api.h"

#include "core/error.h"
#include "core/spherical.h"

#include <spdlog/spdlog.h>

#include <algorithm>
#include <cstdlib>
#include <cstring>
#include <fstream>
#include <map>
#include <sstream>

namespace raypc::server {

namespace fs = std::filesystem;
using nlohmann::json;

std::optional<fs::path> findExamplesDir(const std::optional<fs::path>& explicitDir)
{
    if (explicitDir) {
        if (!fs::is_directory(*explicitDir))
            fail("--examples {}: not a directory", explicitDir->string());
        return fs::weakly_canonical(*explicitDir);
    }
    std::vector<fs::path> candidates;
    if (const char* env = std::getenv("RAYPC_EXAMPLES"); env && *env)
        candidates.emplace_back(env);
#ifdef RAYPC_EXAMPLES_DIR
    candidates.emplace_back(RAYPC_EXAMPLES_DIR);
#endif
    std::error_code ec;
    const fs::path exe = fs::read_symlink("/proc/self/exe", ec);
    if (!ec)
        candidates.push_back(exe.parent_path() / "examples");
    for (const auto& dir : candidates)
        if (fs::is_directory(dir, ec))
            return fs::weakly_canonical(dir, ec);
    return std::nullopt;
}

namespace {

// Short titles of the contest presets (docs/tasks.md); other files are titled by their name.
const std::map<std::string, std::string> kPresetTitles = {
    {"task1-slabs-660km", "1 · Cold slabs at 660 km"},
    {"task2-slabs-1600km", "2 · Cold slabs at 1600 km"},
    {"task3-plumes-1600km", "3 · Hot plumes at 1600 km"},
    {"task4-plumes-660km", "4 · Hot plumes at 660 km"},
    {"task5a-expansivity-negative", "5a · Negative expansivity anomaly"},
    {"task5b-expansivity-negative-cold-high", "5b · Negative expansivity, cold, shallow"},
    {"task5c-expansivity-negative-hot-deep", "5c · Negative expansivity, hot, deep"},
    {"task5d-expansivity-positive", "5d · Positive expansivity anomaly"},
    {"task5e-expansivity-negative-pathlines", "5e · Negative expansivity, pathlines"},
    {"appendix-cut-by-x", "Appendix · Cut at x = 0"},
    {"appendix-hot-with-pathlines", "Appendix · Hot mantle with pathlines"},
};

}  // namespace

json presetsJson(const std::optional<fs::path>& dir)
{
    json out = json::array();
    if (!dir)
        return out;
    std::vector<fs::path> files;
    std::error_code ec;
    for (const auto& entry : fs::directory_iterator(*dir, ec))
        if (entry.is_regular_file() && entry.path().extension() == ".json" && entry.path().filename() != "demo.json")
            files.push_back(entry.path());
    std::sort(files.begin(), files.end());
    for (const auto& file : files) {
        std::ifstream in(file, std::ios::binary);
        std::ostringstream text;
        text << in.rdbuf();
        json state;
        try {
            state = json::parse(text.str());
        } catch (const json::parse_error& e) {
            spdlog::warn("presets: {}: not valid JSON ({}), left out", file.string(), e.what());
            continue;
        }
        const std::string name = file.stem().string();
        std::string title = name;
        if (const auto it = kPresetTitles.find(name); it != kPresetTitles.end())
            title = it->second;
        else
            std::replace(title.begin(), title.end(), '-', ' ');
        out.push_back({{"name", name}, {"title", title}, {"state", std::move(state)}});
    }
    return out;
}

json selectionStatsJson(const Dataset& dataset, StepCache& cache, std::span<const RangeFilter> filters, int level,
                        int profileStep)
{
    dataset.checkLevel(level);
    dataset.checkStep(profileStep);
    const auto selections = selectionOverTime(dataset, filters, level, 0, int(dataset.steps().size()) - 1,
                                              [&](int step, int l) { return cache.getWithoutEvicting(step, l); });
    json steps = json::array();
    for (const StepSelection& sel : selections)
        steps.push_back({{"step", sel.step},
                         {"timeMyr", sel.timeMyr},
                         {"volumeKm3", sel.stats.volumeKm3},
                         {"fractionOfMantle", sel.stats.fractionOfMantle}});
    const SelectionStats& profile = selections[size_t(profileStep)].stats;
    const SphericalGrid& grid = dataset.levels()[size_t(level)].grid;
    json radius = json::array(), depth = json::array(), selected = json::array(), shell = json::array();
    for (size_t iR = 0; iR < grid.nR(); ++iR) {
        radius.push_back(grid.rKm[iR]);
        depth.push_back(kSurfaceRadiusKm - grid.rKm[iR]);
        selected.push_back(iR < profile.volumeByRadiusKm3.size() ? profile.volumeByRadiusKm3[iR] : 0.0);
        shell.push_back(iR < profile.shellVolumeByRadiusKm3.size() ? profile.shellVolumeByRadiusKm3[iR] : 0.0);
    }
    return {{"level", level},
            {"steps", std::move(steps)},
            {"profile",
             {{"step", profileStep},
              {"radiusKm", std::move(radius)},
              {"depthKm", std::move(depth)},
              {"volumeKm3", std::move(selected)},
              {"shellVolumeKm3", std::move(shell)}}}};
}

PathlineCache::PathlineCache(fs::path datasetDir, size_t maxEntries)
    : m_dir(std::move(datasetDir)), m_maxEntries(std::max<size_t>(1, maxEntries))
{
}

std::shared_ptr<const PathlineCache::Window> PathlineCache::get(int step, int window)
{
    {
        std::lock_guard lock(m_mutex);
        for (auto it = m_lru.begin(); it != m_lru.end(); ++it)
            if (it->step == step && it->window == window) {
                m_lru.splice(m_lru.begin(), m_lru, it);
                return it->sets;
            }
    }
    // Load outside the lock; two threads may load the same window once each, which is harmless.
    auto sets = std::make_shared<const Window>(loadPathlineWindow(m_dir, step, window));
    std::lock_guard lock(m_mutex);
    m_lru.push_front({step, window, sets});
    while (m_lru.size() > m_maxEntries)
        m_lru.pop_back();
    return sets;
}

std::string pathlineAttributesPayload(const PathlineCache::Window& sets, int step, int window)
{
    std::vector<std::string> columns, units;
    if (!sets.empty())
        columns = sets.front().columns, units = sets.front().units;
    size_t lines = 0;
    json setInfo = json::array();
    for (const auto& s : sets) {
        if (s.columns != columns)
            fail("pathlines: the set injected at step {} has other attribute columns than the first of the window",
                 s.injectionStep);
        lines += s.lineCount();
        setInfo.push_back({{"injectionStep", s.injectionStep},
                           {"injectionTimeMyr", s.injectionTimeMyr},
                           {"lines", s.lineCount()}});
    }
    const std::string header = json{{"step", step},
                                    {"window", window},
                                    {"lines", lines},
                                    {"columns", columns},
                                    {"units", units},
                                    {"sets", setInfo}}
                                   .dump(-1, ' ', false, json::error_handler_t::replace);
    std::string out(4, '\0');
    const uint32_t n = uint32_t(header.size());
    for (int i = 0; i < 4; ++i)
        out[size_t(i)] = char((n >> (8 * i)) & 0xff);
    out += header;
    for (const auto& s : sets)  // float32 little-endian (the host order on every supported target)
        out.append(reinterpret_cast<const char*>(s.attributes.data()), s.attributes.size() * sizeof(float));
    return out;
}

}  // namespace raypc::server
