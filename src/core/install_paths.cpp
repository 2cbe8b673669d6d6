#include "core/install_paths.h"

#include "core/error.h"

#include <cstdlib>
#include <initializer_list>
#include <system_error>

namespace raypc {

namespace fs = std::filesystem;

namespace {

// $envVar (if set and not empty), then builtInDir, then each of nextToExecutable relative to the
// directory of the running executable.
std::vector<fs::path> candidates(const char* envVar, const char* builtInDir,
                                 std::initializer_list<const char*> nextToExecutable)
{
    std::vector<fs::path> out;
    if (const char* env = std::getenv(envVar); env && *env)
        out.emplace_back(env);
    out.emplace_back(builtInDir);
    std::error_code ec;
    const fs::path exe = fs::read_symlink("/proc/self/exe", ec);
    if (!ec)
        for (const char* relative : nextToExecutable)
            out.push_back(exe.parent_path() / relative);
    return out;
}

}  // namespace

std::vector<fs::path> uiAssetCandidates()
{
    return candidates("RAYPC_ASSETS", RAYPC_WEB_DIST_DIR, {"web", "../web/dist"});
}

std::vector<fs::path> exampleCandidates()
{
    return candidates("RAYPC_EXAMPLES", RAYPC_EXAMPLES_DIR, {"examples"});
}

namespace {

// `explicitDir` (named by `option` in the error), else the first candidate `accept` takes.
template <class Accept>
std::optional<fs::path> findDir(const std::optional<fs::path>& explicitDir, const char* option,
                                const std::vector<fs::path>& candidates, Accept&& accept)
{
    if (explicitDir) {
        if (!fs::is_directory(*explicitDir))
            fail("{} {}: not a directory", option, explicitDir->string());
        return fs::weakly_canonical(*explicitDir);
    }
    std::error_code ec;
    for (const auto& dir : candidates)
        if (accept(dir, ec))
            return fs::weakly_canonical(dir, ec);
    return std::nullopt;
}

}  // namespace

std::optional<fs::path> findAssetDir(const std::optional<fs::path>& explicitDir)
{
    return findDir(explicitDir, "--assets", uiAssetCandidates(),
                   [](const fs::path& dir, std::error_code& ec) { return fs::is_regular_file(dir / "index.html", ec); });
}

std::optional<fs::path> findExamplesDir(const std::optional<fs::path>& explicitDir)
{
    return findDir(explicitDir, "--examples", exampleCandidates(),
                   [](const fs::path& dir, std::error_code& ec) { return fs::is_directory(dir, ec); });
}

}  // namespace raypc
