// What the gtest programs of this folder share on top of harness.h: the contest-layout fixture
// preprocessed once per program before its tests, and `raypc serve` of it. Each program is built
// with RAYPC_EXE (the raypc executable) and RAYPC_CONTEST_LAYOUT_DIR (the fixture's folder)
// defined (CMakeLists.txt, raypc_fixture_server_test).
#pragma once

#include "harness.h"

#include <filesystem>
#include <string>
#include <utility>
#include <vector>

namespace raypc::servertest {

// Registered during static initialisation, so that gtest runs it before the first test.
inline ::testing::Environment* const g_fixtureEnvironment =
    ::testing::AddGlobalTestEnvironment(new WorkDirEnvironment(RAYPC_EXE, RAYPC_CONTEST_LAYOUT_DIR));

// `raypc serve` of the prepared work directory; the arguments are ServerProcess's.
class FixtureServer : public ServerProcess {
public:
    explicit FixtureServer(std::vector<std::string> extra = {}, bool verbose = false,
                           std::vector<std::string> launcher = {}, std::vector<std::string> inputs = {})
        : ServerProcess(RAYPC_EXE, WorkDirEnvironment::work(), std::move(extra), verbose, std::move(launcher),
                        std::move(inputs))
    {
    }
};

}  // namespace raypc::servertest
