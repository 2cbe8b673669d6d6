#include "core/install_paths.h"

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

}  // namespace raypc
