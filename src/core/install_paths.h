// Where RayPC finds the data it is installed with: the one search order for the UI's files (and
// the coastlines the UI build writes beside them) and for the example states. The build tree's
// directories are compiled in here (src/core/CMakeLists.txt) and nowhere else.
#pragma once

#include <filesystem>
#include <vector>

namespace raypc {

// The UI's files, in order: $RAYPC_ASSETS, the build tree's web/dist, web/ and ../web/dist beside
// the running executable.
std::vector<std::filesystem::path> uiAssetCandidates();

// The example states (presets), in order: $RAYPC_EXAMPLES, the source tree's examples/, examples/
// beside the running executable.
std::vector<std::filesystem::path> exampleCandidates();

}  // namespace raypc
