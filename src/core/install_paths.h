// Where RayPC finds the data it is installed with: the one search order for the UI's files (and
// the coastlines the UI build writes beside them) and for the example states. The build tree's
// directories are compiled in here (src/core/CMakeLists.txt) and nowhere else.
#pragma once

#include <filesystem>
#include <optional>
#include <vector>

namespace raypc {

// The UI's files, in order: $RAYPC_ASSETS, the build tree's web/dist, web/ and ../web/dist beside
// the running executable.
std::vector<std::filesystem::path> uiAssetCandidates();

// The example states (presets), in order: $RAYPC_EXAMPLES, the source tree's examples/, examples/
// beside the running executable.
std::vector<std::filesystem::path> exampleCandidates();

// The directory of the UI's files (`--assets`): `explicitDir` if given (throws raypc::Error if it is
// not a directory), else the first of uiAssetCandidates holding an index.html; nullopt when none.
std::optional<std::filesystem::path> findAssetDir(const std::optional<std::filesystem::path>& explicitDir);

// The directory of example states (`--examples`): `explicitDir` if given (throws raypc::Error if it
// is not a directory), else the first of exampleCandidates that exists; nullopt when none.
std::optional<std::filesystem::path> findExamplesDir(const std::optional<std::filesystem::path>& explicitDir);

}  // namespace raypc
