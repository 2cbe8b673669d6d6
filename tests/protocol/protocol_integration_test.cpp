// Integration tests of `raypc serve` against docs/protocol.md: a real server process on an ephemeral
// port, a client built with Beast. Connects to 127.0.0.1 only.
#include "fixture_server.h"
#include "state/render_state.h"

#include <boost/asio.hpp>
#include <boost/beast/core.hpp>
#include <boost/beast/http.hpp>
#include <boost/beast/websocket.hpp>
#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstring>
#include <csignal>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <mutex>
#include <numbers>
#include <optional>
#include <sstream>
#include <regex>
#include <set>
#include <thread>
#include <netinet/in.h>
#include <netinet/tcp.h>
#include <sys/socket.h>
#include <sys/syscall.h>
#include <sys/wait.h>
#include <poll.h>
#include <unistd.h>

namespace {

namespace fs = std::filesystem;
using namespace raypc::servertest;

// The dataset, preprocessed once per test process into a temporary directory (fixture_server.h).
const fs::path& g_work = WorkDirEnvironment::work();

void runOrDie(const std::string& command)
{
    const int status = std::system(command.c_str());
    ASSERT_EQ(status, 0) << command;
}

// ---------------------------------------------------------------------------------------------

TEST(Serve, InfoHistogramSampleOverHttp)
{
    FixtureServer server;
    EXPECT_TRUE(server.token.empty()) << "no token on loopback";
    const auto info = httpGet(server.port, "/api/info");
    ASSERT_EQ(info.status, 200) << info.body;
    EXPECT_EQ(info.contentType, "application/json");
    const json j = json::parse(info.body);
    EXPECT_EQ(j["protocol"], 1);
    EXPECT_EQ(j["steps"].size(), 3u);
    EXPECT_EQ(j["levels"].size(), 3u);
    EXPECT_EQ(j["levels"][0]["nLat"], 36);
    EXPECT_EQ(j["levels"][0]["nR"], 41);
    EXPECT_EQ(j["levels"][0]["nLon"], 72);
    ASSERT_FALSE(j["variables"].empty());
    EXPECT_EQ(j["variables"][0]["histogram"].size(), 256u);
    EXPECT_EQ(j["coordinates"].size(), 7u);
    EXPECT_TRUE(j["defaultState"].is_object());
    EXPECT_EQ(j["defaultState"]["version"], raypc::state::kRenderStateVersion);
    EXPECT_FALSE(j["colorMaps"].empty());

    const auto h = httpGet(server.port, "/api/histogram?step=2&var=temperature");
    ASSERT_EQ(h.status, 200) << h.body;
    EXPECT_EQ(json::parse(h.body)["histogram"].size(), 256u);
    const auto badStep = httpGet(server.port, "/api/histogram?step=300&var=temperature");
    EXPECT_EQ(badStep.status, 400);
    EXPECT_NE(json::parse(badStep.body)["error"].get<std::string>().find("step: 300 out of range 0..2"),
              std::string::npos);
    EXPECT_EQ(httpGet(server.port, "/api/histogram?step=0&var=pressure").status, 400);

    const auto sample = httpGet(server.port, "/api/sample?step=0");
    ASSERT_EQ(sample.status, 200);
    EXPECT_EQ(sample.body.size(),
              j["sample"]["rows"].get<size_t>() * j["sample"]["columns"].size() * sizeof(float));
    // A later step's variables alone: the same values as the variable columns of its whole sample.
    const auto whole = httpGet(server.port, "/api/sample?step=2&columns=all");
    const auto vars = httpGet(server.port, "/api/sample?step=2&columns=variables");
    ASSERT_EQ(whole.status, 200);
    ASSERT_EQ(vars.status, 200);
    const size_t rows = j["sample"]["rows"], nAll = j["sample"]["columns"].size(), nVars = j["variables"].size();
    ASSERT_EQ(vars.body.size(), rows * nVars * sizeof(float));
    std::vector<float> w(rows * nAll), v(rows * nVars);
    std::memcpy(w.data(), whole.body.data(), whole.body.size());
    std::memcpy(v.data(), vars.body.data(), vars.body.size());
    for (size_t row = 0; row < rows; row += 97)
        for (size_t k = 0; k < nVars; ++k)
            ASSERT_EQ(v[row * nVars + k], w[row * nAll + (nAll - nVars) + k]) << "row " << row << " variable " << k;
    const auto badColumns = httpGet(server.port, "/api/sample?step=0&columns=coordinates");
    EXPECT_EQ(badColumns.status, 400);
    EXPECT_NE(badColumns.body.find("columns: expected 'all' or 'variables', found 'coordinates'"), std::string::npos)
        << badColumns.body;
    EXPECT_EQ(httpGet(server.port, "/api/nothing").status, 404);
}

// TCP_NODELAY of each connection the server accepted, read from the server's own descriptors
// (pidfd_getfd: Linux 5.6, and the right to trace the process). Without it a frame's last segment
// waits for the browser's delayed acknowledgement of the one before (up to 40 ms per frame).
// nullopt: this process may not read them.
std::optional<std::vector<int>> noDelayOfAcceptedSockets(pid_t pid, uint16_t port)
{
    const int pidfd = int(syscall(SYS_pidfd_open, pid, 0));
    if (pidfd < 0)
        return std::nullopt;
    std::vector<int> found;
    bool permitted = false;
    for (const auto& entry : fs::directory_iterator("/proc/" + std::to_string(pid) + "/fd")) {
        const int fd = int(syscall(SYS_pidfd_getfd, pidfd, std::stoi(entry.path().filename().string()), 0));
        if (fd < 0)
            continue;
        permitted = true;
        sockaddr_storage local{}, peer{};
        socklen_t localSize = sizeof local, peerSize = sizeof peer;
        int noDelay = -1;
        socklen_t size = sizeof noDelay;
        // A connected TCP socket on the server's port: an accepted connection (the listener has no peer).
        if (getsockname(fd, reinterpret_cast<sockaddr*>(&local), &localSize) == 0 && local.ss_family == AF_INET &&
            ntohs(reinterpret_cast<sockaddr_in*>(&local)->sin_port) == port &&
            getpeername(fd, reinterpret_cast<sockaddr*>(&peer), &peerSize) == 0 &&
            getsockopt(fd, IPPROTO_TCP, TCP_NODELAY, &noDelay, &size) == 0)
            found.push_back(noDelay);
        close(fd);
    }
    close(pidfd);
    if (!permitted)
        return std::nullopt;
    return found;
}

TEST(Serve, AcceptedConnectionsSendWithoutDelay)
{
    FixtureServer server;
    WsClient ws(server.port);
    ws.hello();
    const auto noDelay = noDelayOfAcceptedSockets(server.pid(), server.port);
    if (!noDelay)
        GTEST_SKIP() << "this process may not read the server's descriptors (pidfd_open, pidfd_getfd)";
    ASSERT_FALSE(noDelay->empty()) << "no accepted connection found among the server's descriptors";
    for (const int v : *noDelay)
        EXPECT_NE(v, 0) << "an accepted connection without TCP_NODELAY";
}

TEST(Serve, StaticFilesAndPathTraversal)
{
    FixtureServer server;
    const auto index = httpGet(server.port, "/");
    EXPECT_EQ(index.status, 200);
    EXPECT_NE(index.body.find("raypc test page"), std::string::npos);
    EXPECT_EQ(httpGet(server.port, "/js/app.js").status, 200);
    for (const char* target : {"/../secret.txt", "/%2e%2e/secret.txt", "/%2E%2E/secret.txt", "/js/../../secret.txt",
                               "/js/%2e%2e/%2e%2e/secret.txt", "/..%2fsecret.txt", "/..%5csecret.txt",
                               "/%2fetc/passwd", "//etc/passwd", "/index.html%00", "/missing.html"}) {
        const auto r = httpGet(server.port, target);
        EXPECT_EQ(r.status, 404) << target;
        EXPECT_EQ(r.body.find("TOP-SECRET"), std::string::npos) << target;
        EXPECT_EQ(r.body.find("root:"), std::string::npos) << target;
    }
    // Targets a strict HTTP parser may reject outright: never 200, never the file.
    const std::string absolute = (g_work / "secret.txt").string();
    for (const std::string& target : {std::string("/..\\secret.txt"), absolute, std::string("/a b\x01")}) {
        const auto r = httpGet(server.port, target);
        EXPECT_NE(r.status, 200) << target;
        EXPECT_EQ(r.body.find("TOP-SECRET"), std::string::npos) << target;
    }
}

TEST(Serve, WebSocketFrameLayout)
{
    FixtureServer server;
    WsClient ws(server.port);
    ws.hello();
    ws.send({{"type", "ping"}, {"id", 7}});
    EXPECT_EQ(ws.receiveText(), (json{{"type", "pong"}, {"id", 7}}));

    const json state = smallState(30, "viridis", 2);
    ws.send({{"type", "state"}, {"id", 1}, {"state", state}, {"interactive", false}});
    const auto frames = ws.framesUntilConverged(1);
    ASSERT_EQ(frames.size(), 2u);
    for (size_t i = 0; i < frames.size(); ++i) {
        const json& h = frames[i].frame.header;
        EXPECT_EQ(h["type"], "frame");
        EXPECT_EQ(h["id"], 1);
        EXPECT_EQ(h["step"], 1);
        EXPECT_EQ(h["level"], 0);
        EXPECT_EQ(h["pass"], int(i) + 1);
        EXPECT_EQ(h["passes"], 2);
        EXPECT_EQ(h["converged"], i == 1);
        EXPECT_EQ(h["interactive"], false);
        EXPECT_EQ(h["width"], 128);
        EXPECT_EQ(h["height"], 96);
        EXPECT_EQ(h["camera"]["azimuthDeg"], 30.0);
        EXPECT_EQ(h["camera"]["distanceKm"], 20000.0);
        EXPECT_EQ(h["depthWidth"], 32);
        EXPECT_EQ(h["depthHeight"], 24);
        EXPECT_EQ(h["depthBytes"], 32 * 24 * 4);
        EXPECT_TRUE(h["stats"]["passMs"].is_number());
        EXPECT_GT(h["stats"]["samples"].get<double>(), 0);
        // The selection of a new still state follows its first frame (docs/protocol.md).
        if (i == 0) {
            EXPECT_TRUE(h["selection"].is_null());
        } else {
            EXPECT_TRUE(h["selection"]["fractionOfMantle"].is_number());
            EXPECT_NEAR(h["selection"]["fractionOfMantle"].get<double>(), 1.0, 1e-9);  // no brushes
        }
        const std::string jpeg = jpegOf(frames[i]);
        ASSERT_GE(jpeg.size(), 4u);
        EXPECT_EQ(uint8_t(jpeg[0]), 0xff);
        EXPECT_EQ(uint8_t(jpeg[1]), 0xd8);
        EXPECT_EQ(uint8_t(jpeg[jpeg.size() - 2]), 0xff);
        EXPECT_EQ(uint8_t(jpeg[jpeg.size() - 1]), 0xd9);
        ASSERT_EQ(frames[i].frame.depth.size(), 32u * 24u);
        // The planet fills the middle of the image: finite depths there (km from the eye, less than the
        // eye's distance from the centre), nothing hit in the corners.
        const float centre = frames[i].frame.depth[12 * 32 + 16];
        EXPECT_TRUE(std::isfinite(centre));
        EXPECT_GT(centre, 20000.0f - 6371.0f - 1.0f);
        EXPECT_LT(centre, 20000.0f);
        EXPECT_TRUE(std::isinf(frames[i].frame.depth[0]));
    }

    // Interactive: one pass, at a level chosen for the time budget.
    json fast = state;
    fast["camera"]["azimuthDeg"] = 60;
    ws.send({{"type", "state"}, {"id", 2}, {"state", fast}, {"interactive", true}});
    const auto interactive = ws.framesUntilConverged(2);
    const json& h = interactive.back().frame.header;
    EXPECT_EQ(h["interactive"], true);
    EXPECT_EQ(h["passes"], 1);
    EXPECT_EQ(h["camera"]["azimuthDeg"], 60.0);
    EXPECT_GE(h["level"].get<int>(), 0);
    EXPECT_LE(h["level"].get<int>(), 2);
}

// Two datasets side by side (`raypc serve A B`, docs/compare.md, "Side by side"): the fixture and a
// tomography model (tests/data/emc-layout: one step, vs and its anomalies, none of the contest's
// variables). Every endpoint of one dataset takes `dataset` (0 default, 1 the second); a session
// opened with /ws?dataset=1 draws the first's states for the second and says what it left out.
TEST(Serve, APairAnswersForEachDatasetByTheDatasetParameter)
{
    const fs::path work = WorkDirEnvironment::work();
    const fs::path second = work / "pair-second";
    if (!fs::exists(second / "dataset.json")) {
        const fs::path emc = fs::path(RAYPC_CONTEST_LAYOUT_DIR).parent_path() / "emc-layout" / "global_vs.nc";
        const std::string command = std::string("'") + RAYPC_EXE + "' preprocess '" + emc.string() + "' -o '" +
                                    second.string() + "' --quiet --sample-rows 500 >/dev/null";
        ASSERT_EQ(std::system(command.c_str()), 0) << command;
    }
    FixtureServer server({}, false, {}, {(work / "ds").string(), second.string()});

    const json first = json::parse(httpGet(server.port, "/api/info").body);
    ASSERT_TRUE(first.contains("pair")) << first.dump().substr(0, 300);
    EXPECT_EQ(first["pair"]["index"], 0);
    ASSERT_EQ(first["pair"]["datasets"].size(), 2u);
    EXPECT_EQ(first["pair"]["datasets"][0]["name"], first["name"]);
    EXPECT_EQ(first["pair"]["datasets"][0]["timesMyr"].size(), first["steps"].size());
    const auto secondAnswer = httpGet(server.port, "/api/info?dataset=1");
    ASSERT_EQ(secondAnswer.status, 200) << secondAnswer.body;
    const json other = json::parse(secondAnswer.body);
    EXPECT_EQ(other["pair"]["index"], 1);
    EXPECT_EQ(other["name"], first["pair"]["datasets"][1]["name"]);
    EXPECT_EQ(other["steps"].size(), 1u);
    EXPECT_EQ(other["pair"]["datasets"], first["pair"]["datasets"]);
    auto names = [](const json& info) {
        std::set<std::string> out;
        for (const auto& v : info["variables"])
            out.insert(v["name"].get<std::string>());
        return out;
    };
    EXPECT_TRUE(names(other).count("vs"));
    EXPECT_FALSE(names(other).count("temperature"));
    EXPECT_TRUE(names(first).count("temperature"));

    // Each dataset's own answers: a variable only the second has, its sample's shape.
    EXPECT_EQ(httpGet(server.port, "/api/histogram?step=0&var=vs&dataset=1").status, 200);
    EXPECT_EQ(httpGet(server.port, "/api/histogram?step=0&var=vs").status, 400);
    const auto sample = httpGet(server.port, "/api/sample?step=0&dataset=1");
    ASSERT_EQ(sample.status, 200);
    EXPECT_EQ(sample.body.size(),
              other["sample"]["rows"].get<size_t>() * other["sample"]["columns"].size() * sizeof(float));

    // Out of range, or on an endpoint that is not about one dataset: 400 naming it.
    auto errorOf = [&](const std::string& target) {
        const auto a = httpGet(server.port, target);
        EXPECT_EQ(a.status, 400) << target;
        return json::parse(a.body).value("error", std::string());
    };
    EXPECT_NE(errorOf("/api/histogram?step=0&var=vs&dataset=2").find("dataset: 2 for /api/histogram: expected an index of the datasets served; this server serves a pair, 0 and 1"),
              std::string::npos);
    EXPECT_NE(errorOf("/api/info?dataset=one").find("dataset: one for /api/info"), std::string::npos);
    EXPECT_NE(errorOf("/api/link?dataset=1").find("unknown parameter 'dataset' for /api/link"), std::string::npos);
    EXPECT_THROW(WsClient(server.port, "/ws?dataset=2"), std::exception);

    // Each dataset keeps its own analyses: the same brushes' statistics on the second are computed
    // for it (its one step), not answered from what the first kept.
    json depthState = smallState();
    depthState["brushes"] = {{{"name", "depth"}, {"min", 500}, {"max", 1500}}};
    const auto statsFirst = httpRequest(server.port, http::verb::post, "/api/stats?level=0", depthState.dump());
    ASSERT_EQ(statsFirst.status, 200) << statsFirst.body;
    const auto statsSecond = httpRequest(server.port, http::verb::post, "/api/stats?level=0&dataset=1", depthState.dump());
    ASSERT_EQ(statsSecond.status, 200) << statsSecond.body;
    EXPECT_EQ(statsSecond.stepsComputed, "1");
    EXPECT_EQ(json::parse(statsSecond.body)["steps"].size(), 1u);
    EXPECT_EQ(httpRequest(server.port, http::verb::post, "/api/stats?level=0&dataset=1", depthState.dump()).stepsComputed, "0");

    // Correlating the pair needs a variable both have (this pair has none), asked of the first.
    const auto corr = httpRequest(server.port, http::verb::post, "/api/correlate", depthState.dump());
    EXPECT_EQ(corr.status, 400);
    EXPECT_NE(json::parse(corr.body).value("error", std::string()).find("the second dataset has no variable 'temperature' to correlate"),
              std::string::npos) << corr.body;
    EXPECT_EQ(httpRequest(server.port, http::verb::post, "/api/correlate?dataset=1", depthState.dump()).status, 400);

    // The first's state, with a brush on a variable the second lacks, for the second: step matched
    // by time (its one step), the brush left out, the colour variable it lacks replaced; said in the
    // frames' `pair.notes`.
    json state = smallState(30, "viridis", 2);
    state["brushes"] = json::array({{{"name", "temperature"}, {"min", 2000}, {"max", 4000}}});
    const auto selection = httpRequest(server.port, http::verb::post, "/api/selection?dataset=1", state.dump());
    ASSERT_EQ(selection.status, 200) << selection.body;
    EXPECT_EQ(json::parse(selection.body)["step"], 0);
    EXPECT_NEAR(json::parse(selection.body)["fractionOfMantle"].get<double>(), 1.0, 1e-9);  // no brush left
    WsClient ws(server.port, "/ws?dataset=1");
    ws.hello();
    ws.send({{"type", "state"}, {"id", 1}, {"state", state}, {"interactive", false}});
    const auto frames = ws.framesUntilConverged(1);
    ASSERT_FALSE(frames.empty());
    const json& h = frames.back().frame.header;
    EXPECT_EQ(h["step"], 0);
    ASSERT_TRUE(h.contains("pair")) << h.dump();
    const std::string notes = h["pair"]["notes"].dump();
    EXPECT_NE(notes.find("brush on 'temperature' left out: the second dataset has no such variable"), std::string::npos) << notes;
    EXPECT_NE(notes.find("colour: the second dataset has no 'temperature'"), std::string::npos) << notes;
    // The first dataset's session draws the state as it is, without `pair` in its frames.
    WsClient ws0(server.port);
    ws0.hello();
    ws0.send({{"type", "state"}, {"id", 1}, {"state", state}, {"interactive", false}});
    const auto firstFrames = ws0.framesUntilConverged(1);
    ASSERT_FALSE(firstFrames.empty());
    const json& h0 = firstFrames.back().frame.header;
    EXPECT_EQ(h0["step"], 1);
    EXPECT_FALSE(h0.contains("pair"));
    EXPECT_LT(h0["selection"]["fractionOfMantle"].get<double>(), 1.0);
}

// A server of one dataset refuses the second's index, on HTTP and on /ws, and its info has no pair.
TEST(Serve, OneDatasetRefusesTheSecondIndex)
{
    FixtureServer server;
    EXPECT_FALSE(json::parse(httpGet(server.port, "/api/info").body).contains("pair"));
    EXPECT_EQ(httpGet(server.port, "/api/info?dataset=0").status, 200);
    const auto a = httpGet(server.port, "/api/histogram?step=0&var=temperature&dataset=1");
    EXPECT_EQ(a.status, 400);
    EXPECT_NE(json::parse(a.body)["error"].get<std::string>().find(
                  "dataset: 1 for /api/histogram: expected an index of the datasets served; this server serves one dataset, 0"),
              std::string::npos)
        << a.body;
    EXPECT_THROW(WsClient(server.port, "/ws?dataset=1"), std::exception);
    WsClient ws(server.port, "/ws?dataset=0");
    ws.hello();
}

TEST(Serve, DefaultStateOfInfoRendersAndInteractiveFitsTheBudget)
{
    FixtureServer server;
    json state = json::parse(httpGet(server.port, "/api/info").body)["defaultState"];
    WsClient ws(server.port);
    ws.hello();
    state["passes"] = 1;
    ws.send({{"type", "state"}, {"id", 1}, {"state", state}});
    const auto still = ws.framesUntilConverged(1);
    EXPECT_EQ(still.back().frame.header["width"], state["image"]["width"]);
    // A budget no level can meet: the interactive frame comes at the coarsest level and a reduced size
    // of the same aspect. The camera moves a degree, as in a drag: the same view again would be the
    // still frame the session keeps (server/frame_cache.h), at once and whole.
    state["timeBudgetMs"] = 0.001;
    state["camera"]["azimuthDeg"] = state["camera"]["azimuthDeg"].get<double>() + 1.0;
    ws.send({{"type", "state"}, {"id", 2}, {"state", state}, {"interactive", true}});
    const json h = ws.framesUntilConverged(2).back().frame.header;
    EXPECT_EQ(h["level"], 2);
    EXPECT_EQ(h["width"].get<int>() * state["image"]["height"].get<int>(),
              h["height"].get<int>() * state["image"]["width"].get<int>());
    EXPECT_LT(h["width"].get<int>(), state["image"]["width"].get<int>());
    EXPECT_EQ(h["depthWidth"], (h["width"].get<int>() + 3) / 4);
}

// A step of playback: the level fits the time the step is shown
// (timeBudgetMs), the frame keeps its size when a level fits, and the passes go on refining at that
// level until state.passes or the next state, sending the passes that may be the newest when the
// step's time is up; playback does not change the linked state.
TEST(Serve, PlaybackStepsGetTheirLevelFromTheBudgetThenRefine)
{
    FixtureServer server({"--frame-cache", "0"});  // no rendering ahead, which would stop the refinement
    json state = json::parse(httpGet(server.port, "/api/info").body)["defaultState"];
    WsClient ws(server.port);
    ws.hello();
    state["passes"] = 1;
    ws.send({{"type", "state"}, {"id", 1}, {"state", state}});  // measures the throughput
    ws.framesUntilConverged(1);
    const json linked = json::parse(httpGet(server.port, "/api/link").body);

    // Ample time: level 0 at the state's size; the first pass and the last are sent (the ones
    // between would be shown by no one: the next is done well before the step's time is up).
    state["step"] = 1;
    state["passes"] = 4;
    state["convergenceGreyLevels"] = 0;  // no adaptive stop: all four passes are rendered
    state["timeBudgetMs"] = 60000;
    ws.send({{"type", "state"}, {"id", 2}, {"state", state}, {"playback", true}});
    const auto frames = ws.framesUntilConverged(2);
    ASSERT_EQ(frames.size(), 2u);
    for (size_t i = 0; i < frames.size(); ++i) {
        const json& h = frames[i].frame.header;
        EXPECT_EQ(h["playback"], true);
        EXPECT_EQ(h["interactive"], false);
        EXPECT_EQ(h["level"], 0);
        EXPECT_EQ(h["pass"], i == 0 ? 1 : 4);
        EXPECT_EQ(h["width"], state["image"]["width"]);
        EXPECT_EQ(h["height"], state["image"]["height"]);
        EXPECT_TRUE(h["selection"]["fractionOfMantle"].is_number()) << "pass " << i + 1;
    }
    // No time: the coarsest level, refined as well, every pass sent.
    state["step"] = 2;
    state["timeBudgetMs"] = 0.001;
    state["passes"] = 2;
    ws.send({{"type", "state"}, {"id", 3}, {"state", state}, {"playback", true}});
    const auto coarse = ws.framesUntilConverged(3);
    EXPECT_EQ(coarse.back().frame.header["level"], 2);
    EXPECT_EQ(coarse.back().frame.header["pass"], 2);
    EXPECT_EQ(json::parse(httpGet(server.port, "/api/link").body)["version"], linked["version"])
        << "a step of playback changed the linked state";
}

// A still state whose level-0 pass misses its time budget is shown first by a preview (pass 0, at the
// level an interactive state would get), then its passes at level 0; with a level of its own, or a
// budget its pass fits, it has none.
TEST(Serve, SlowStillStatesAreShownFirstByAPreview)
{
    FixtureServer server;
    json state = json::parse(httpGet(server.port, "/api/info").body)["defaultState"];
    WsClient ws(server.port);
    ws.hello();
    state["passes"] = 2;
    state["convergenceGreyLevels"] = 0;
    state["timeBudgetMs"] = 60000;
    ws.send({{"type", "state"}, {"id", 1}, {"state", state}});
    auto frames = ws.framesUntilConverged(1);
    ASSERT_EQ(frames.size(), 2u);
    EXPECT_EQ(frames[0].frame.header["pass"], 1) << "no preview within the budget";
    EXPECT_EQ(frames[0].frame.header["preview"], false);

    state["timeBudgetMs"] = 0.001;
    state["camera"]["azimuthDeg"] = 70;
    ws.send({{"type", "state"}, {"id", 2}, {"state", state}});
    frames = ws.framesUntilConverged(2);
    ASSERT_EQ(frames.size(), 3u);
    const json& p = frames[0].frame.header;
    EXPECT_EQ(p["preview"], true);
    EXPECT_EQ(p["pass"], 0);
    EXPECT_EQ(p["converged"], false);
    EXPECT_EQ(p["level"], 2);
    EXPECT_EQ(p["camera"]["azimuthDeg"], 70.0);
    for (int i = 1; i <= 2; ++i) {
        EXPECT_EQ(frames[size_t(i)].frame.header["preview"], false);
        EXPECT_EQ(frames[size_t(i)].frame.header["pass"], i);
        EXPECT_EQ(frames[size_t(i)].frame.header["level"], 0);
        EXPECT_EQ(frames[size_t(i)].frame.header["width"], state["image"]["width"]);
    }

    state["level"] = 0;
    state["camera"]["azimuthDeg"] = 80;
    ws.send({{"type", "state"}, {"id", 3}, {"state", state}});
    frames = ws.framesUntilConverged(3);
    ASSERT_EQ(frames.size(), 2u);
    EXPECT_EQ(frames[0].frame.header["pass"], 1) << "a state with its own level has no preview";
}

TEST(Serve, PlaybackPrefetchesTheNextStep)
{
    FixtureServer server({}, true);
    WsClient ws(server.port);
    ws.hello();
    for (int step = 0; step < 2; ++step) {
        json state = smallState(30, "viridis", 1);
        state["step"] = step;
        state["level"] = 1;
        ws.send({{"type", "state"}, {"id", step}, {"state", state}, {"interactive", true}});
        EXPECT_EQ(ws.framesUntilConverged(step).back().frame.header["step"], step);
    }
    // The render thread logs the prefetch after the frame is sent: wait for the line (under load it
    // came after the ping's reply).
    for (int i = 0; i < 50 && server.output().find("playback: prefetching step 2 level 1") == std::string::npos; ++i)
        std::this_thread::sleep_for(std::chrono::milliseconds(100));
    EXPECT_NE(server.output().find("playback: prefetching step 2 level 1"), std::string::npos) << server.output();
}

// Frames rendered ahead (docs/protocol.md): after a still state, the session renders the other steps
// of that state in the background; a step of playback (or a still state) at a kept step is answered
// with the kept frame ("cached": true), whose JPEG and depth are those of a fresh render of the same
// state; any change but the step (a brush here) drops the kept frames.
TEST(Serve, FramesRenderedAheadAnswerPlaybackAndEqualAFreshRender)
{
    FixtureServer server;
    json state = json::parse(httpGet(server.port, "/api/info").body)["defaultState"];
    state["image"] = {{"width", 160}, {"height", 120}};
    state["passes"] = 3;
    state["convergenceGreyLevels"] = 0;
    state["timeBudgetMs"] = 60000;
    state["step"] = 0;
    WsClient ws(server.port);
    ws.hello();
    int64_t id = 1;
    ws.send({{"type", "state"}, {"id", id}, {"state", state}});
    const auto still = ws.framesUntilConverged(id);
    EXPECT_EQ(still.back().frame.header["cached"], false) << "the first frame of a state is rendered";

    // A step of playback, as the UI sends it (a short time budget); its frame, the last one sent.
    const auto play = [&](int step) {
        state["step"] = step;
        state["timeBudgetMs"] = 100;
        ws.send({{"type", "state"}, {"id", ++id}, {"state", state}, {"playback", true}});
        return ws.framesUntilConverged(id).back();
    };
    // The first loop: the steps after 0 are rendered ahead while it plays, first as drafts (one
    // pass), then finished; wait until a loop has every step finished from the cache (the
    // background thread has its own pace). A kept frame is either a draft or finished.
    bool allKept = false;
    for (int loop = 0; loop < 100 && !allKept; ++loop) {
        allKept = true;
        for (int step = 0; step < 3; ++step) {
            const json h = play(step).frame.header;
            if (h["cached"] == true) {
                EXPECT_TRUE(h["pass"] == 1 || h["pass"] == 3) << h.dump();
            }
            allKept = h["cached"] == true && h["pass"] == 3 && allKept;
        }
        if (!allKept)
            std::this_thread::sleep_for(std::chrono::milliseconds(100));
    }
    ASSERT_TRUE(allKept) << "no loop of playback came from the finished frames rendered ahead";
    // The next loop: every frame kept, at the state's quality: level 0, full size, every pass.
    std::vector<WsClient::Message> kept;
    for (int step = 0; step < 3; ++step) {
        kept.push_back(play(step));
        const json& h = kept.back().frame.header;
        EXPECT_EQ(h["cached"], true) << "step " << step;
        EXPECT_EQ(h["playback"], true);
        EXPECT_EQ(h["id"], id);
        EXPECT_EQ(h["step"], step);
        EXPECT_EQ(h["level"], 0);
        EXPECT_EQ(h["pass"], 3);
        EXPECT_EQ(h["converged"], true);
        EXPECT_EQ(h["width"], 160);
        EXPECT_EQ(h["height"], 120);
    }
    EXPECT_EQ(jpegOf(kept[0]), jpegOf(still.back())) << "step 0's kept frame is the still frame sent";

    // A fresh render of step 2 in another session (its own cache): the same bytes as the kept frame.
    {
        WsClient fresh(server.port);
        fresh.hello();
        state["step"] = 2;
        state["timeBudgetMs"] = 60000;
        fresh.send({{"type", "state"}, {"id", 1}, {"state", state}});
        const auto frames = fresh.framesUntilConverged(1);
        ASSERT_EQ(frames.back().frame.header["cached"], false);
        EXPECT_EQ(frames.back().frame.header["pass"], 3);
        EXPECT_EQ(jpegOf(frames.back()), jpegOf(kept[2])) << "the kept frame differs from a fresh render";
        EXPECT_EQ(frames.back().frame.depth, kept[2].frame.depth);
    }

    // A brush: another state, rendered afresh; back to the first state, its kept frames are gone.
    json brushed = state;
    brushed["brushes"] = json::array({{{"name", "temperature"}, {"min", 2000}, {"max", 4000}}});
    brushed["step"] = 1;
    ws.send({{"type", "state"}, {"id", ++id}, {"state", brushed}, {"playback", true}});
    EXPECT_EQ(ws.framesUntilConverged(id).back().frame.header["cached"], false) << "a brush answered from the cache";
    EXPECT_EQ(play(2).frame.header["cached"], false) << "a brush change did not drop the kept frames";
}

TEST(Serve, BadMessagesGetErrorsAndTheConnectionStays)
{
    FixtureServer server;
    WsClient ws(server.port);
    // Before hello: an error, not a crash.
    ws.send({{"type", "ping"}, {"id", 1}});
    EXPECT_EQ(ws.receiveText()["type"], "error");
    ws.hello();

    auto expectError = [&](const std::string& text, const std::string& fragment) {
        ws.sendText(text);
        const json reply = ws.receiveText();
        EXPECT_EQ(reply["type"], "error") << text.substr(0, 100);
        EXPECT_NE(reply["message"].get<std::string>().find(fragment), std::string::npos)
            << reply["message"] << " lacks " << fragment;
    };
    expectError(R"({"type": "state", "id": )", "not valid JSON");
    expectError("not json at all", "not valid JSON");
    expectError(R"({"type": "teleport"})", "unknown message type 'teleport'");
    expectError(R"({"type": "state", "state": {}})", "missing field 'id'");
    expectError(R"({"type": "ping"})", "missing field 'id'");
    expectError(std::string(R"({"type": "ping", "id": 1, "pad": ")") + std::string(300 * 1024, 'x') + "\"}",
                "over the limit");
    ws.sendBinary("\x01\x02\x03");
    EXPECT_EQ(ws.receiveText()["type"], "error");

    // A state the dataset cannot render: error with its id; the previous state stays.
    json unknownVar = smallState();
    unknownVar["color"]["variable"] = "pressure";
    ws.send({{"type", "state"}, {"id", 41}, {"state", unknownVar}});
    json reply = ws.receiveText();
    EXPECT_EQ(reply["type"], "error");
    EXPECT_EQ(reply["id"], 41);
    EXPECT_NE(reply["message"].get<std::string>().find("pressure"), std::string::npos);
    json badStep = smallState();
    badStep["step"] = 300;
    ws.send({{"type", "state"}, {"id", 42}, {"state", badStep}});
    reply = ws.receiveText();
    EXPECT_EQ(reply["id"], 42);
    EXPECT_NE(reply["message"].get<std::string>().find("step: 300 out of range 0..2"), std::string::npos);
    json huge = smallState();
    huge["image"] = {{"width", 8192}, {"height", 8192}};
    ws.send({{"type", "state"}, {"id", 45}, {"state", huge}});
    reply = ws.receiveText();
    EXPECT_EQ(reply["id"], 45);
    EXPECT_NE(reply["message"].get<std::string>().find("over the limit"), std::string::npos);
    json badKey = smallState();
    badKey["camera"]["zoom"] = 2;
    ws.send({{"type", "state"}, {"id", 43}, {"state", badKey}});
    EXPECT_EQ(ws.receiveText()["id"], 43);

    // Still working.
    ws.send({{"type", "ping"}, {"id", 5}});
    EXPECT_EQ(ws.receiveText(), (json{{"type", "pong"}, {"id", 5}}));
    ws.send({{"type", "state"}, {"id", 44}, {"state", smallState()}, {"interactive", true}});
    EXPECT_EQ(ws.framesUntilConverged(44).back().frame.header["id"], 44);
    EXPECT_TRUE(server.alive());
}

TEST(Serve, WrongProtocolVersionIsRefusedAndClosed)
{
    FixtureServer server;
    WsClient ws(server.port);
    ws.send({{"type", "hello"}, {"protocol", 2}});
    const json reply = ws.receiveText();
    EXPECT_EQ(reply["type"], "error");
    EXPECT_NE(reply["message"].get<std::string>().find("protocol 2"), std::string::npos);
    EXPECT_NE(reply["message"].get<std::string>().find("protocol 1"), std::string::npos);
    beast::flat_buffer buffer;
    beast::error_code ec;
    ws.stream().read(buffer, ec);
    EXPECT_EQ(ec, websocket::error::closed);
}

TEST(Serve, TwoSessionsKeepTheirOwnStates)
{
    FixtureServer server;
    WsClient a(server.port), b(server.port);
    a.hello();
    b.hello();
    a.send({{"type", "state"}, {"id", 1}, {"state", smallState(0, "viridis", 1)}});
    b.send({{"type", "state"}, {"id", 1}, {"state", smallState(120, "grayscale", 1)}});
    const auto fa = a.framesUntilConverged(1);
    const auto fb = b.framesUntilConverged(1);
    EXPECT_EQ(fa.back().frame.header["camera"]["azimuthDeg"], 0.0);
    EXPECT_EQ(fb.back().frame.header["camera"]["azimuthDeg"], 120.0);
    EXPECT_NE(jpegOf(fa.back()), jpegOf(fb.back()));
    // Session a's state is unchanged by b's: the same state again gives the same image.
    a.send({{"type", "state"}, {"id", 2}, {"state", smallState(0, "viridis", 1)}});
    EXPECT_EQ(jpegOf(a.framesUntilConverged(2).back()), jpegOf(fa.back()));
}

TEST(Serve, NewestStateWinsAndCancelStops)
{
    FixtureServer server;
    WsClient ws(server.port);
    ws.hello();
    const json slow = slowState(200, 256, 256);
    ws.send({{"type", "state"}, {"id", 1}, {"state", slow}});
    ws.send({{"type", "state"}, {"id", 2}, {"state", smallState(20, "viridis", 1)}});
    const auto frames = ws.framesUntilConverged(2);
    // Then nothing more of state 1: a ping is answered with no frame in between.
    ws.send({{"type", "ping"}, {"id", 9}});
    std::vector<WsClient::Message> after;
    EXPECT_EQ(ws.receiveText(&after)["id"], 9);
    EXPECT_TRUE(after.empty());
    int firstOfTwo = -1;
    for (size_t i = 0; i < frames.size(); ++i)
        if (frames[i].frame.header["id"] == 2 && firstOfTwo < 0)
            firstOfTwo = int(i);
    for (size_t i = size_t(firstOfTwo); i < frames.size(); ++i)
        EXPECT_EQ(frames[i].frame.header["id"], 2);
    EXPECT_LT(frames.size(), 200u);

    // cancel: the 200-pass state stops; a ping right after sees at most a few frames.
    ws.send({{"type", "state"}, {"id", 3}, {"state", slow}});
    ws.receive();  // its first pass
    ws.send({{"type", "cancel"}});
    ws.send({{"type", "ping"}, {"id", 10}});
    std::vector<WsClient::Message> late;
    EXPECT_EQ(ws.receiveText(&late)["id"], 10);
    ws.send({{"type", "ping"}, {"id", 11}});
    std::vector<WsClient::Message> later;
    EXPECT_EQ(ws.receiveText(&later)["id"], 11);
    EXPECT_LE(late.size(), 3u);
    EXPECT_TRUE(later.empty()) << later.size() << " frames after cancel";
}

TEST(Serve, ClosingATabStopsItsWork)
{
    FixtureServer server;
    {
        WsClient ws(server.port);
        ws.hello();
        const json slow = slowState(100000, 256, 256);
        ws.send({{"type", "state"}, {"id", 1}, {"state", slow}});
        ws.receive();
        ws.close();
    }
    // The server answers a new session promptly (the closed one's work was stopped).
    const auto start = std::chrono::steady_clock::now();
    WsClient ws(server.port);
    ws.hello();
    ws.send({{"type", "state"}, {"id", 1}, {"state", smallState()}, {"interactive", true}});
    ws.framesUntilConverged(1);
    EXPECT_LT(std::chrono::steady_clock::now() - start, std::chrono::seconds(20));
    EXPECT_TRUE(server.alive());
}

TEST(Serve, ScreenshotSelectionAndBodyLimit)
{
    FixtureServer server;
    json state = smallState(30, "viridis", 2);
    const auto png = httpRequest(server.port, http::verb::post, "/api/screenshot", state.dump());
    ASSERT_EQ(png.status, 200) << png.body;
    EXPECT_EQ(png.contentType, "image/png");
    ASSERT_GT(png.body.size(), 8u);
    EXPECT_EQ(png.body.substr(0, 8), std::string("\x89PNG\r\n\x1a\n", 8));

    state["brushes"] = {{{"name", "depth"}, {"min", 0}, {"max", 1000}}};
    const auto sel = httpRequest(server.port, http::verb::post, "/api/selection", state.dump());
    ASSERT_EQ(sel.status, 200) << sel.body;
    const json s = json::parse(sel.body);
    EXPECT_GT(s["fractionOfMantle"].get<double>(), 0.0);
    EXPECT_LT(s["fractionOfMantle"].get<double>(), 1.0);
    EXPECT_EQ(s["step"], 1);

    state["brushes"] = {{{"name", "pressure"}, {"min", 0}, {"max", 1}}};
    const auto bad = httpRequest(server.port, http::verb::post, "/api/selection", state.dump());
    EXPECT_EQ(bad.status, 400);
    EXPECT_NE(bad.body.find("pressure"), std::string::npos);
    EXPECT_EQ(httpRequest(server.port, http::verb::post, "/api/selection", "{nope").status, 400);
    const auto big = httpRequest(server.port, http::verb::post, "/api/selection", std::string(2 * 1024 * 1024, ' '));
    EXPECT_EQ(big.status, 413);
}

// Maps and sections: POST /api/slice answers the picture and where it put things; GET
// /api/probe the values at a point; bad requests get 400 naming what is wrong.
TEST(Serve, SliceAndProbe)
{
    FixtureServer server;
    json state = smallState(30, "viridis", 2);
    state["version"] = 9;
    state["map"] = {{"depthKm", 1000}, {"projection", "robinson"}, {"centralMeridianDeg", 40}};
    state["image"] = {{"width", 400}, {"height", 240}};
    for (const std::string view : {"map", "section"}) {
        const auto a = httpRequest(server.port, http::verb::post, "/api/slice?view=" + view, state.dump());
        ASSERT_EQ(a.status, 200) << a.body;
        EXPECT_EQ(a.contentType, "application/octet-stream");
        ASSERT_GT(a.body.size(), 4u);
        const uint32_t n = uint32_t(uint8_t(a.body[0])) | uint32_t(uint8_t(a.body[1])) << 8 |
                           uint32_t(uint8_t(a.body[2])) << 16 | uint32_t(uint8_t(a.body[3])) << 24;
        ASSERT_LT(4 + n, a.body.size());
        const json header = json::parse(a.body.substr(4, n));
        EXPECT_EQ(header["view"], view);
        EXPECT_EQ(header["width"], state["image"]["width"]);
        EXPECT_EQ(header["step"], 1);
        if (view == "map") {
            EXPECT_EQ(header["projection"], "robinson");
            EXPECT_EQ(header["centralMeridianDeg"], 40);
            EXPECT_GT(header["scale"].get<double>(), 1);
        } else {
            EXPECT_LT(header["plot"]["left"].get<double>(), header["plot"]["right"].get<double>());
            EXPECT_NEAR(header["depthSpanKm"].get<double>(), 6371 - 3485, 1e-6);
        }
        EXPECT_EQ(a.body.substr(4 + n, 8), std::string("\x89PNG\r\n\x1a\n", 8));
    }
    auto refused = [&](const std::string& target, const std::string& body, const std::string& names) {
        const auto a = body.empty() ? httpRequest(server.port, http::verb::get, target)
                                    : httpRequest(server.port, http::verb::post, target, body);
        EXPECT_EQ(a.status, 400) << target;
        EXPECT_NE(a.body.find(names), std::string::npos) << target << ": " << a.body;
    };
    refused("/api/slice?view=globe", state.dump(), "view");
    json deep = state;
    deep["map"]["depthKm"] = 3000;
    refused("/api/slice?view=map", deep.dump(), "map.depthKm");
    json antipodal = state;
    antipodal["section"] = {{"from", {{"latDeg", 10}, {"lonDeg", 0}}}, {"to", {{"latDeg", -10}, {"lonDeg", 180}}}};
    refused("/api/slice?view=section", antipodal.dump(), "antipodal");
    json huge = state;
    huge["image"] = {{"width", 16000}, {"height", 16000}};
    refused("/api/slice?view=map", huge.dump(), "limit");

    const auto p = httpRequest(server.port, http::verb::get, "/api/probe?step=1&lat=20&lon=40&depthKm=1000&var=temperature");
    ASSERT_EQ(p.status, 200) << p.body;
    const json probe = json::parse(p.body);
    EXPECT_NEAR(probe["point"]["radius"]["value"].get<double>(), 5371, 1e-9);
    // The fixture's temperature less its anomaly is 300 + 3700 (6371 - r) / 2886 K (its truth.json).
    const auto q = httpRequest(server.port, http::verb::get, "/api/probe?step=1&lat=20&lon=40&depthKm=1000");
    ASSERT_EQ(q.status, 200) << q.body;
    const json all = json::parse(q.body)["values"];
    EXPECT_NEAR(all["temperature"]["value"].get<double>() - all["temperature anomaly"]["value"].get<double>(),
                300 + 3700 * 1000.0 / 2886, 0.05);
    refused("/api/probe?step=1&lat=100&lon=0&depthKm=10", "", "lat");
    refused("/api/probe?step=1&lat=0&lon=0&depthKm=4000", "", "depthKm");
    refused("/api/probe?step=1&lat=0&lon=nan&depthKm=10", "", "lon");
    refused("/api/probe?step=1&lat=0&lon=0", "", "depthKm");
    refused("/api/probe?step=1&lat=0&lon=0&depthKm=10&var=pressure", "", "pressure");
    refused("/api/probe?step=9&lat=0&lon=0&depthKm=10", "", "step");
}

// GET /api/presets: every example state but demo.json, with a title (examples/titles.tsv), exactly as in the file; each
// is a valid state for the fixture once its step is one of the fixture's. A file that is not JSON is
// left out.
TEST(Serve, PresetsAreTheExampleStates)
{
    const fs::path examples = fs::path(RAYPC_SOURCE_DIR) / "examples";
    std::vector<std::string> expected;
    for (const auto& e : fs::directory_iterator(examples))
        if (e.path().extension() == ".json" && e.path().filename() != "demo.json")
            expected.push_back(e.path().stem().string());
    std::sort(expected.begin(), expected.end());
    ASSERT_GE(expected.size(), 6u);

    FixtureServer server({"--examples", examples.string()});
    const auto answer = httpGet(server.port, "/api/presets");
    ASSERT_EQ(answer.status, 200) << answer.body;
    const json presets = json::parse(answer.body);
    ASSERT_TRUE(presets.is_array());
    std::vector<std::string> names;
    for (const auto& p : presets) {
        const std::string name = p.at("name");
        names.push_back(name);
        EXPECT_FALSE(p.at("title").get<std::string>().empty()) << name;
        EXPECT_NE(p.at("title").get<std::string>(), name) << "the contest presets have human titles";
        std::ifstream in(examples / (name + ".json"));
        EXPECT_EQ(p.at("state"), json::parse(in)) << name;
        json state = p.at("state");
        state["step"] = 1;
        state["image"] = {{"width", 64}, {"height", 48}};
        const auto sel = httpRequest(server.port, http::verb::post, "/api/selection", state.dump());
        EXPECT_EQ(sel.status, 200) << name << ": " << sel.body;
    }
    EXPECT_EQ(names, expected);
    EXPECT_EQ(httpRequest(server.port, http::verb::post, "/api/presets", "{}").status, 405);

    const fs::path own = g_work / "own-examples";
    fs::create_directories(own);
    std::ofstream(own / "demo.json") << R"({"version": 1})";
    std::ofstream(own / "broken.json") << "{not json";
    std::ofstream(own / "my-view.json") << R"({"version": 1, "step": 0})";
    std::ofstream(own / "other-view.json") << R"({"version": 1, "step": 0})";
    std::ofstream(own / "titles.tsv") << "# titles\nother-view\tThe other view\nno tab here\n";
    FixtureServer second({"--examples", own.string()});
    const json mine = json::parse(httpGet(second.port, "/api/presets").body);
    ASSERT_EQ(mine.size(), 2u) << mine.dump();
    EXPECT_EQ(mine[0]["name"], "my-view");
    EXPECT_EQ(mine[0]["title"], "my view");  // not in titles.tsv: its name
    EXPECT_EQ(mine[1]["name"], "other-view");
    EXPECT_EQ(mine[1]["title"], "The other view");
}

// The kept analyses (docs/scaling.md): a second identical /api/stats or /api/features request, or one
// that differs only by the step (and, for features, the painting), computes no step
// (X-Raypc-Steps-Computed: 0) and answers what the first answered.
TEST(Serve, RepeatedStatisticsAndFeaturesAreAnsweredFromTheKeptAnalyses)
{
    FixtureServer server;
    json state = smallState();
    state["step"] = 1;
    state["brushes"] = {{{"name", "depth"}, {"min", 500}, {"max", 1500}}};
    const auto first = httpRequest(server.port, http::verb::post, "/api/stats?level=0", state.dump());
    ASSERT_EQ(first.status, 200) << first.body;
    EXPECT_EQ(first.stepsComputed, "3");
    const auto again = httpRequest(server.port, http::verb::post, "/api/stats?level=0", state.dump());
    EXPECT_EQ(again.stepsComputed, "0");
    EXPECT_EQ(again.body, first.body);
    state["step"] = 2;
    const auto stepped = httpRequest(server.port, http::verb::post, "/api/stats?level=0&profiles=all", state.dump());
    ASSERT_EQ(stepped.status, 200) << stepped.body;
    EXPECT_EQ(stepped.stepsComputed, "0") << "a step change computes nothing";
    const json s1 = json::parse(first.body), s2 = json::parse(stepped.body);
    EXPECT_EQ(s2["steps"], s1["steps"]);
    EXPECT_EQ(s2["profile"]["step"], 2);
    ASSERT_EQ(s2["profiles"].size(), 3u);
    EXPECT_EQ(s2["profiles"][1]["volumeKm3"], s1["profile"]["volumeKm3"]) << "step 1's profile, as the first answer gave it";
    EXPECT_EQ(s2["profiles"][2]["volumeKm3"], s2["profile"]["volumeKm3"]);
    state["brushes"][0]["max"] = 1600;
    EXPECT_EQ(httpRequest(server.port, http::verb::post, "/api/stats?level=0", state.dump()).stepsComputed, "3") << "a new brush";
    EXPECT_EQ(httpRequest(server.port, http::verb::post, "/api/stats?profiles=some", state.dump()).status, 400);

    const auto features = httpRequest(server.port, http::verb::post, "/api/features?job=kept-1", state.dump());
    ASSERT_EQ(features.status, 200) << features.body;
    EXPECT_EQ(features.stepsComputed, "3");
    state["step"] = 0;
    state["version"] = raypc::state::kRenderStateVersion;  // a document that has `features`
    state["features"] = {{"colorById", true}};
    const auto kept = httpRequest(server.port, http::verb::post, "/api/features?job=kept-2", state.dump());
    EXPECT_EQ(kept.stepsComputed, "0");
    EXPECT_EQ(kept.body, features.body);
    const json progress = json::parse(httpGet(server.port, "/api/job-progress?job=kept-2").body);
    EXPECT_EQ(progress["state"], "done") << progress.dump();
    EXPECT_EQ(progress["done"], 3) << progress.dump();
}

// POST /api/stats: the selected volume of every step at level 0 equals `raypc stats` and the
// analytic volume of the fixture (radial velocity = u0 everywhere, so depth <= 660 km selects
// whole shells: tests/cli/cli_test.sh, stats_analytic_selection); the depth profile has nothing
// below 660 km and full shells above; bad levels are 400.
TEST(Serve, StatsOverTimeMatchTheCliAndTheAnalyticSelection)
{
    FixtureServer server;
    json state = smallState();
    state["step"] = 2;
    state["brushes"] = {{{"name", "depth"}, {"min", 0}, {"max", 660}},
                        {{"name", "radial velocity"}, {"min", 0.15}, {"max", 0.16}}};
    const auto answer = httpRequest(server.port, http::verb::post, "/api/stats?level=0", state.dump());
    ASSERT_EQ(answer.status, 200) << answer.body;
    const json stats = json::parse(answer.body);
    EXPECT_EQ(stats["level"], 0);
    ASSERT_EQ(stats["steps"].size(), 3u);

    double prev = 0, edge = 0;
    for (int i = 0; i <= 40; ++i) {
        const double r = 3485 + i * 2886.0 / 40;
        if (r >= 5711) {
            edge = (prev + r) / 2;
            break;
        }
        prev = r;
    }
    const double analyticKm3 = 4.0 / 3.0 * std::numbers::pi * (std::pow(6371.0, 3) - std::pow(edge, 3));
    const double analyticFraction = (std::pow(6371.0, 3) - std::pow(edge, 3)) / (std::pow(6371.0, 3) - std::pow(3485.0, 3));

    const fs::path csv = g_work / "stats_cli.csv";
    runOrDie(std::string(RAYPC_EXE) + " stats " + (g_work / "ds").string() +
             " --range depth=0:660 --range 'radial velocity=0.15:0.16' --quiet -o " + csv.string() + " >/dev/null");
    std::ifstream in(csv);
    std::string line;
    std::getline(in, line);  // header
    for (int step = 0; step < 3; ++step) {
        const json& s = stats["steps"][size_t(step)];
        EXPECT_EQ(s["step"], step);
        const double v = s["volumeKm3"], f = s["fractionOfMantle"];
        EXPECT_NEAR(v, analyticKm3, 1e-6 * analyticKm3) << "step " << step;
        EXPECT_NEAR(f, analyticFraction, 1e-8) << "step " << step;
        ASSERT_TRUE(std::getline(in, line));
        std::stringstream fields(line);
        std::string cell[4];
        for (auto& c : cell)
            std::getline(fields, c, ',');
        EXPECT_EQ(std::stoi(cell[0]), step);
        EXPECT_NEAR(std::stod(cell[1]), s["timeMyr"].get<double>(), 1e-9);
        EXPECT_NEAR(std::stod(cell[2]), v, 1e-6 * v) << "CLI and endpoint differ at step " << step;
        EXPECT_NEAR(std::stod(cell[3]), 100 * f, 1e-6) << "CLI and endpoint differ at step " << step;
    }

    const json& p = stats["profile"];
    EXPECT_EQ(p["step"], 2);
    ASSERT_EQ(p["radiusKm"].size(), 41u);
    ASSERT_EQ(p["volumeKm3"].size(), 41u);
    double sum = 0;
    for (size_t i = 0; i < 41; ++i) {
        const double depth = p["depthKm"][i], selected = p["volumeKm3"][i], shell = p["shellVolumeKm3"][i];
        EXPECT_NEAR(depth, 6371.0 - p["radiusKm"][i].get<double>(), 1e-9);
        sum += selected;
        if (depth > 660) {
            EXPECT_EQ(selected, 0.0) << "selected below 660 km at depth " << depth;
        } else if (depth < 600) {
            EXPECT_NEAR(selected, shell, 1e-9 * shell) << "shell at depth " << depth << " not fully selected";
        }
    }
    EXPECT_NEAR(sum, analyticKm3, 1e-6 * analyticKm3);

    // Default level 1: close to the exact value, not necessarily equal.
    const auto quick = httpRequest(server.port, http::verb::post, "/api/stats", state.dump());
    ASSERT_EQ(quick.status, 200) << quick.body;
    const json q = json::parse(quick.body);
    EXPECT_EQ(q["level"], 1);
    EXPECT_EQ(q["steps"].size(), 3u);
    EXPECT_EQ(q["profile"]["radiusKm"].size(), 21u);

    // Nothing selected beside u0.
    state["brushes"][1]["min"] = 0.2, state["brushes"][1]["max"] = 0.3;
    const json none = json::parse(httpRequest(server.port, http::verb::post, "/api/stats?level=0", state.dump()).body);
    for (const auto& s : none["steps"])
        EXPECT_EQ(s["volumeKm3"], 0.0);

    const auto badLevel = httpRequest(server.port, http::verb::post, "/api/stats?level=7", state.dump());
    EXPECT_EQ(badLevel.status, 400);
    EXPECT_NE(badLevel.body.find("level: 7 out of range 0..2"), std::string::npos) << badLevel.body;
    EXPECT_EQ(httpRequest(server.port, http::verb::post, "/api/stats?level=x", state.dump()).status, 400);
    state["brushes"] = {{{"name", "pressure"}, {"min", 0}, {"max", 1}}};
    EXPECT_EQ(httpRequest(server.port, http::verb::post, "/api/stats", state.dump()).status, 400);
    EXPECT_EQ(httpGet(server.port, "/api/stats").status, 405);
}

// GET /api/pathlines: u32 header length, JSON header, lines x columns float32; the window's sets
// are those injected at steps max(0, step - window + 1)..step; bad parameters are 400.
TEST(Serve, PathlineAttributesOfAWindow)
{
    FixtureServer server;
    auto fetch = [&](const std::string& query) {
        const auto a = httpGet(server.port, "/api/pathlines?" + query);
        EXPECT_EQ(a.status, 200) << query << ": " << a.body;
        EXPECT_EQ(a.contentType, "application/octet-stream");
        uint32_t n = 0;
        for (int i = 0; i < 4; ++i)
            n |= uint32_t(uint8_t(a.body[size_t(i)])) << (8 * i);
        json header = json::parse(a.body.substr(4, n));
        std::vector<float> values((a.body.size() - 4 - n) / 4);
        EXPECT_EQ(values.size() * 4, a.body.size() - 4 - n);
        std::memcpy(values.data(), a.body.data() + 4 + n, values.size() * 4);
        return std::pair(header, values);
    };
    const auto [all, values] = fetch("step=2&window=10");
    EXPECT_EQ(all["step"], 2);
    EXPECT_EQ(all["window"], 10);
    ASSERT_EQ(all["sets"].size(), 3u) << all.dump();
    size_t lines = 0;
    for (size_t i = 0; i < 3; ++i) {
        EXPECT_EQ(all["sets"][i]["injectionStep"], int(i));
        lines += all["sets"][i]["lines"].get<size_t>();
    }
    EXPECT_EQ(all["lines"], lines);
    ASSERT_GT(lines, 0u) << "the fixture's pathlines are empty";
    const auto& columns = all["columns"];
    EXPECT_EQ(columns[0], "seed kind");
    EXPECT_NE(std::find(columns.begin(), columns.end(), "length"), columns.end());
    EXPECT_NE(std::find(columns.begin(), columns.end(), "start temperature"), columns.end());
    EXPECT_EQ(all["units"].size(), columns.size());
    EXPECT_EQ(values.size(), lines * columns.size());
    // Lengths are non-negative and the injection time column matches each set's time.
    const size_t nc = columns.size();
    const size_t kLength = size_t(std::find(columns.begin(), columns.end(), "length") - columns.begin());
    const size_t kInjection = size_t(std::find(columns.begin(), columns.end(), "injection time") - columns.begin());
    size_t row = 0;
    for (const auto& set : all["sets"])
        for (size_t i = 0; i < set["lines"].get<size_t>(); ++i, ++row) {
            EXPECT_GE(values[row * nc + kLength], 0.0f);
            EXPECT_NEAR(values[row * nc + kInjection], set["injectionTimeMyr"].get<double>(), 1e-3);
        }

    const auto [last, lastValues] = fetch("step=2&window=1");
    ASSERT_EQ(last["sets"].size(), 1u);
    EXPECT_EQ(last["sets"][0]["injectionStep"], 2);
    EXPECT_EQ(last["lines"], all["sets"][2]["lines"]);
    EXPECT_EQ(fetch("step=1").first["window"], 10) << "window defaults to 10";

    EXPECT_EQ(httpGet(server.port, "/api/pathlines?step=3&window=2").status, 400);
    EXPECT_EQ(httpGet(server.port, "/api/pathlines?step=1&window=0").status, 400);
    EXPECT_EQ(httpGet(server.port, "/api/pathlines?window=2").status, 400);
    EXPECT_EQ(httpRequest(server.port, http::verb::post, "/api/pathlines?step=0", "{}").status, 405);
}

// GET /api/persistence: the fixture's temperature anomaly is four Gaussian blobs (truth.json: +400,
// +300, -350, -300 K) on a near-zero background, so its diagram has three pairs that stand out: the
// global pair (the +400 K maximum and the -350 K minimum, about 750 K apart) and one pair for each
// 300 K blob, at their centres; every other pair is far weaker. The 5° grid samples a blob up to half
// a cell off its centre, where it is up to 13 % weaker (the -300 K blob's grid minimum is -265 K at
// step 1): 15 % tolerance. The stored seeds' threshold is the
// preprocess default, 5 % of the step's range. Bad parameters are 400 with a message.
TEST(Serve, PersistenceDiagramOfAStep)
{
    FixtureServer server;
    const auto a = httpGet(server.port, "/api/persistence?step=1&top=5");
    ASSERT_EQ(a.status, 200) << a.body;
    EXPECT_EQ(a.contentType, "application/json");
    const json d = json::parse(a.body);
    EXPECT_EQ(d["step"], 1);
    EXPECT_EQ(d["variable"], "temperature anomaly");
    ASSERT_EQ(d["pairs"].size(), 5u);
    const auto& p = d["pairs"];
    EXPECT_EQ(p[0]["kind"], "global");
    EXPECT_NEAR(p[0]["persistence"].get<double>(), 750, 0.15 * 750);
    EXPECT_NEAR(p[0]["persistence"].get<double>(), d["range"].get<double>(), 1e-6);
    // The global pair's extremum is the +400 K blob's maximum (lat 20, lon 40 at t = 0, r 4300 km);
    // step 1 is 2 Myr later: rotated by omega t (under 0.01 degrees) and risen by u0 t (3 km).
    EXPECT_NEAR(p[0]["lat"].get<double>(), 20, 5.1);
    EXPECT_NEAR(p[0]["lon"].get<double>(), 40, 5.1);
    EXPECT_NEAR(p[0]["depthKm"].get<double>(), 6371 - 4300, 80);
    EXPECT_NEAR(p[0]["birth"].get<double>() + p[0]["persistence"].get<double>(), p[0]["death"].get<double>(), 1e-3);
    std::set<std::string> kinds;
    for (size_t i = 1; i < 3; ++i) {
        EXPECT_NEAR(p[i]["persistence"].get<double>(), 300, 0.15 * 300) << p[i].dump();
        kinds.insert(p[i]["kind"].get<std::string>());
    }
    EXPECT_EQ(kinds, (std::set<std::string>{"minimum-saddle", "saddle-maximum"}));
    EXPECT_LT(p[3]["persistence"].get<double>(), 0.2 * 300) << "a fourth feature stands out";
    for (size_t i = 1; i < p.size(); ++i)
        EXPECT_LE(p[i]["persistence"].get<double>(), p[i - 1]["persistence"].get<double>());
    const size_t total = d["pairCount"];
    EXPECT_EQ(d["rest"]["count"].get<size_t>(), total - 5);
    EXPECT_EQ(d["counts"]["global"], 1);
    EXPECT_EQ(d["counts"]["minimum-saddle"].get<size_t>() + d["counts"]["saddle-maximum"].get<size_t>() + 1, total);
    const json more = json::parse(httpGet(server.port, "/api/persistence?step=1&top=6").body);
    EXPECT_EQ(more["pairs"][5]["persistence"], d["rest"]["maxPersistence"]);
    // The stored seeds: the default rule, 5 % of the range, and as many lines as /api/pathlines has.
    const json& stored = d["stored"];
    ASSERT_TRUE(stored.is_object()) << d.dump();
    EXPECT_EQ(stored["rule"], "persistence");
    EXPECT_NEAR(stored["threshold"].get<double>(), 0.05 * d["range"].get<double>(), 1e-6 * d["range"].get<double>());
    EXPECT_EQ(stored["seedPersistenceColumn"], true);
    const auto lines = httpGet(server.port, "/api/pathlines?step=1&window=1");
    uint32_t n = 0;
    for (int i = 0; i < 4; ++i)
        n |= uint32_t(uint8_t(lines.body[size_t(i)])) << (8 * i);
    EXPECT_EQ(json::parse(lines.body.substr(4, n))["lines"], stored["lines"]);
    EXPECT_EQ(json::parse(httpGet(server.port, "/api/persistence?step=1").body)["pairs"].size(),
              std::min<size_t>(500, total)) << "top defaults to 500";
    // Another variable has no stored threshold.
    const json other = json::parse(httpGet(server.port, "/api/persistence?step=1&top=1&var=temperature").body);
    EXPECT_TRUE(other["stored"].is_null());
    for (const char* bad : {"step=3", "step=-1", "top=5", "step=1&top=-1", "step=1&top=20001", "step=1&top=many",
                            "step=1&var=pressure"}) {
        const auto r = httpGet(server.port, std::string("/api/persistence?") + bad);
        EXPECT_EQ(r.status, 400) << bad << ": " << r.body;
    }
    const auto badTop = httpGet(server.port, "/api/persistence?step=1&top=many");
    EXPECT_NE(badTop.body.find("top: expected an integer"), std::string::npos) << badTop.body;
}

TEST(Serve, NonLoopbackNeedsTheToken)
{
    FixtureServer server({"--host", "0.0.0.0"});
    ASSERT_EQ(server.token.size(), 32u) << server.banner;
    EXPECT_EQ(httpGet(server.port, "/api/info").status, 401);
    EXPECT_EQ(httpGet(server.port, "/").status, 401);
    EXPECT_EQ(httpGet(server.port, "/api/info?token=0000").status, 401);
    EXPECT_EQ(httpGet(server.port, "/api/info?token=" + server.token).status, 200);
    EXPECT_EQ(httpGet(server.port, "/api/info", {{http::field::authorization, "Bearer " + server.token}}).status, 200);
    EXPECT_EQ(httpGet(server.port, "/api/info", {{http::field::cookie, "raypc_token=" + server.token}}).status, 200);
    const auto page = httpGet(server.port, "/?token=" + server.token);
    EXPECT_EQ(page.status, 200);
    EXPECT_NE(page.setCookie.find("raypc_token=" + server.token), std::string::npos);

    EXPECT_THROW(WsClient(server.port, "/ws"), beast::system_error);
    WsClient ws(server.port, "/ws?token=" + server.token);
    ws.hello();
}

// The linked state (docs/protocol.md, GET/POST /api/link): what a program reads and sets
// of the state the UI shows.
json linkOf(uint16_t port)
{
    const auto answer = httpGet(port, "/api/link");
    EXPECT_EQ(answer.status, 200) << answer.body;
    EXPECT_EQ(answer.contentType, "application/json");
    return json::parse(answer.body);
}

HttpAnswer postLink(uint16_t port, const std::string& body,
                                const std::vector<std::pair<http::field, std::string>>& headers = {})
{
    return httpRequest(port, http::verb::post, "/api/link", body, headers);
}

json brushedState(double minKm, double maxKm)
{
    json state = smallState(30, "viridis", 1);
    state["brushes"] = json::array({{{"name", "depth"}, {"min", minKm}, {"max", maxKm}}});
    return state;
}

TEST(Serve, LinkedStateIsReadAndSetBothWays)
{
    FixtureServer server;
    EXPECT_EQ(linkOf(server.port), json::parse(R"({"version": 0, "state": null, "source": null, "sessions": 0})"));
    WsClient ws(server.port);
    ws.hello();
    EXPECT_EQ(linkOf(server.port)["sessions"], 1);

    // A bad state gets the message a WebSocket state message gets, and changes nothing.
    json unknownVar = brushedState(560, 760);
    unknownVar["brushes"][0]["name"] = "pressure";
    json badKey = brushedState(560, 760);
    badKey["camera"]["zoom"] = 2;
    json badStep = brushedState(560, 760);
    badStep["step"] = 300;
    int64_t id = 100;
    for (const json& bad : {unknownVar, badKey, badStep}) {
        const auto answer = postLink(server.port, json{{"state", bad}}.dump());
        EXPECT_EQ(answer.status, 400) << answer.body;
        ws.send({{"type", "state"}, {"id", ++id}, {"state", bad}});
        const json reply = ws.receiveText();
        ASSERT_EQ(reply["type"], "error") << reply;
        EXPECT_EQ(json::parse(answer.body)["error"], reply["message"]) << bad.dump();
    }
    const auto bare = postLink(server.port, brushedState(560, 760).dump());  // the document without {"state": …}
    EXPECT_EQ(bare.status, 400);
    EXPECT_NE(bare.body.find(R"(body: expected {\"state\": )"), std::string::npos) << bare.body;
    const auto extra = postLink(server.port, json{{"state", brushedState(560, 760)}, {"id", 1}}.dump());
    EXPECT_EQ(extra.status, 400);
    EXPECT_NE(extra.body.find("body: unknown field 'id', expected only 'state'"), std::string::npos) << extra.body;
    EXPECT_EQ(postLink(server.port, "{\"state\": ").status, 400);
    EXPECT_EQ(linkOf(server.port)["version"], 0);

    // A good state: the new version, pushed to the open session.
    const auto set = postLink(server.port, json{{"state", brushedState(560, 760)}}.dump());
    ASSERT_EQ(set.status, 200) << set.body;
    EXPECT_EQ(json::parse(set.body), (json{{"version", 1}, {"sessions", 1}}));
    EXPECT_EQ(ws.receiveText(), (json{{"type", "link"}, {"version", 1}, {"state", brushedState(560, 760)}}));
    json link = linkOf(server.port);
    EXPECT_EQ(link["version"], 1);
    EXPECT_EQ(link["source"], "api");
    EXPECT_EQ(link["state"], brushedState(560, 760));

    // The UI sends it back unchanged (keys in another order): no new version.
    ws.sendText(json{{"type", "state"}, {"id", 1}, {"state", json::parse(brushedState(560, 760).dump())}}.dump());
    ws.framesUntilConverged(1);
    EXPECT_EQ(linkOf(server.port)["version"], 1);
    EXPECT_EQ(linkOf(server.port)["source"], "api");

    // Dragging does not change the linked state; the released brush does.
    ws.send({{"type", "state"}, {"id", 2}, {"state", brushedState(100, 200)}, {"interactive", true}});
    ws.framesUntilConverged(2);
    EXPECT_EQ(linkOf(server.port)["version"], 1);
    ws.send({{"type", "state"}, {"id", 3}, {"state", brushedState(100, 300)}, {"interactive", false}});
    ws.framesUntilConverged(3);
    link = linkOf(server.port);
    EXPECT_EQ(link["version"], 2);
    EXPECT_EQ(link["source"], "ui");
    EXPECT_EQ(link["state"], brushedState(100, 300));

    // A closed tab is no longer counted (nor sent to).
    ws.close();
    for (int i = 0; i < 100 && linkOf(server.port)["sessions"] != 0; ++i)
        std::this_thread::sleep_for(std::chrono::milliseconds(20));
    EXPECT_EQ(linkOf(server.port)["sessions"], 0);
    const auto nobody = postLink(server.port, json{{"state", brushedState(560, 760)}}.dump());
    EXPECT_EQ(json::parse(nobody.body), (json{{"version", 3}, {"sessions", 0}}));
}

TEST(Serve, LinkedStateKeepsTheAccessRules)
{
    const std::string body = json{{"state", brushedState(560, 760)}}.dump();
    {
        FixtureServer server({"--host", "0.0.0.0"});
        ASSERT_FALSE(server.token.empty()) << server.banner;
        EXPECT_EQ(httpGet(server.port, "/api/link").status, 401);
        EXPECT_EQ(postLink(server.port, body).status, 401);
        EXPECT_EQ(httpGet(server.port, "/api/link?token=" + server.token).status, 200);
        EXPECT_EQ(httpRequest(server.port, http::verb::post, "/api/link?token=" + server.token, body).status, 200);
    }
    FixtureServer server;
    const auto crossSite = postLink(
        server.port, body, {{http::field::content_type, "text/plain"}, {http::field::origin, "http://evil.example"}});
    EXPECT_EQ(crossSite.status, 403) << crossSite.body;
    EXPECT_EQ(linkOf(server.port)["version"], 0);
    EXPECT_EQ(postLink(server.port, std::string(2 << 20, ' ')).status, 413);
    EXPECT_EQ(httpRequest(server.port, http::verb::put, "/api/link", body).status, 405);
}

TEST(Serve, StopsCleanlyOnSigtermWhileRendering)
{
    FixtureServer server;
    WsClient ws(server.port);
    ws.hello();
    ws.send({{"type", "state"}, {"id", 1}, {"state", smallState(0, "viridis", 100000)}});
    ws.receive();
    EXPECT_TRUE(server.stop());
}

// ---- netCDF files served at once -----------------------------------------------------------

// The contest-layout files copied into `dir` (the dataset goes beside them by default); `broken`:
// the second file cut short, so that only the background run fails.
std::vector<std::string> copyContestFiles(const fs::path& dir, bool broken = false)
{
    fs::remove_all(dir);
    fs::create_directories(dir);
    std::vector<std::string> files;
    for (const char* name : {"spherical001.nc", "spherical002.nc", "spherical003.nc"}) {
        fs::copy_file(fs::path(RAYPC_CONTEST_LAYOUT_DIR) / name, dir / name);
        files.push_back((dir / name).string());
    }
    if (broken)
        fs::resize_file(dir / "spherical002.nc", 4000);
    return files;
}

// GET /api/progress (with the token) until `state`, at most `seconds`; the last answer.
json waitForProgress(uint16_t port, const std::string& token, const std::string& state, double seconds)
{
    json p;
    const auto deadline = std::chrono::steady_clock::now() + std::chrono::duration<double>(seconds);
    while (std::chrono::steady_clock::now() < deadline) {
        try {
            const auto answer = httpGet(port, "/api/progress?token=" + token);
            if (answer.status == 200)
                p = json::parse(answer.body);
        } catch (const std::exception&) {
            // between the two servers
        }
        if (p.value("state", "") == state)
            break;
        std::this_thread::sleep_for(std::chrono::milliseconds(100));
    }
    return p;
}

TEST(ServeNetcdf, FirstStepAtOnceThenTheWholeSeriesOnTheSameAddress)
{
    const fs::path dir = g_work / "nc-series";
    const auto files = copyContestFiles(dir);
    std::vector<std::string> extra = {"--host", "0.0.0.0", "--sample-rows", "2000"};
    {
        FixtureServer server(extra, false, {}, files);
        ASSERT_EQ(server.token.size(), 32u) << server.banner;
        const json done = waitForProgress(server.port, server.token, "complete", 60);
        ASSERT_EQ(done.value("state", ""), "complete") << done.dump() << server.output();
        const std::string out = server.output();
        EXPECT_NE(out.find("spherical001.nc: step 0 ready in"), std::string::npos) << out;
        EXPECT_NE(out.find("all 3 steps are ready; serving them at the same address"), std::string::npos) << out;
        // The replacing server: same port, same token, the whole series in file order (2 Myr apart).
        EXPECT_EQ(httpGet(server.port, "/api/info").status, 401);
        const json info = json::parse(httpGet(server.port, "/api/info?token=" + server.token).body);
        ASSERT_EQ(info["steps"].size(), 3u);
        for (int s = 0; s < 3; ++s) {
            EXPECT_EQ(info["steps"][s]["source"], fs::path(files[size_t(s)]).filename().string());
            EXPECT_DOUBLE_EQ(info["steps"][s]["timeMyr"].get<double>(), 2.0 * s);
        }
        WsClient ws(server.port, "/ws?token=" + server.token);
        ws.hello();
        json state = smallState();
        state["step"] = 2;
        ws.send({{"type", "state"}, {"id", 1}, {"state", state}});
        const auto frames = ws.framesUntilConverged(1);
        EXPECT_EQ(frames.back().frame.header.value("step", -1), 2);
        EXPECT_TRUE(fs::exists(dir / "spherical.raypc" / "dataset.json"));
        EXPECT_FALSE(fs::exists(dir / "spherical.raypc" / "preview")) << "the preview stays after the series is done";
        EXPECT_TRUE(server.stop()) << server.output();
    }
    // A second run finds the dataset complete and serves it without a preview.
    FixtureServer again(extra, false, {}, files);
    EXPECT_EQ(waitForProgress(again.port, again.token, "complete", 5).value("state", ""), "complete");
    const std::string out = again.output();
    EXPECT_NE(out.find("3 of 3 steps already done"), std::string::npos) << out;
    EXPECT_EQ(out.find("step 0 ready"), std::string::npos) << out;
    EXPECT_TRUE(again.stop());
}

// The step served alone while the series is made is the series' own step 0, its files hard-linked
// (the first file is not preprocessed twice): checked while the series is held after that step
// (RAYPC_TEST_HOLD_SERIES), then the series goes on and replaces it.
TEST(ServeNetcdf, TheStepServedFirstIsTheSeriesOwnStepZero)
{
    const fs::path dir = g_work / "nc-held";
    const auto files = copyContestFiles(dir);
    const fs::path go = dir / "go";
    ::setenv("RAYPC_TEST_HOLD_SERIES", go.c_str(), 1);
    FixtureServer server({"--sample-rows", "2000"}, false, {}, files);
    ::unsetenv("RAYPC_TEST_HOLD_SERIES");
    const json held = json::parse(httpGet(server.port, "/api/progress").body);
    EXPECT_EQ(held.value("state", ""), "preparing") << held.dump();
    EXPECT_EQ(held.value("done", -1), 1) << held.dump();
    EXPECT_EQ(json::parse(httpGet(server.port, "/api/info").body)["steps"].size(), 1u);
    const fs::path series = dir / "spherical.raypc" / "steps" / "0000";
    const fs::path preview = dir / "spherical.raypc" / "preview" / "steps" / "0000";
    size_t linked = 0;
    for (const auto& entry : fs::recursive_directory_iterator(preview)) {
        if (!entry.is_regular_file())
            continue;
        const fs::path theirs = series / fs::relative(entry.path(), preview);
        ASSERT_TRUE(fs::exists(theirs)) << theirs;
        EXPECT_TRUE(fs::equivalent(entry.path(), theirs)) << entry.path() << " is a copy, not the series' file";
        ++linked;
    }
    EXPECT_GT(linked, 10u);
    { std::ofstream(go).put('\n'); }
    EXPECT_EQ(waitForProgress(server.port, "", "complete", 60).value("state", ""), "complete") << server.output();
    EXPECT_FALSE(fs::exists(dir / "spherical.raypc" / "preview"));
    EXPECT_TRUE(server.stop()) << server.output();
}

TEST(ServeNetcdf, ALaterBadFileStopsTheBackgroundRunAndTheFirstStepStaysServed)
{
    const fs::path dir = g_work / "nc-broken";
    const auto files = copyContestFiles(dir, true);
    FixtureServer server({"--sample-rows", "2000"}, false, {}, files);
    const json failed = waitForProgress(server.port, "", "failed", 60);
    ASSERT_EQ(failed.value("state", ""), "failed") << failed.dump() << server.output();
    EXPECT_NE(failed.value("message", "").find("spherical002.nc"), std::string::npos) << failed.dump();
    EXPECT_EQ(failed["steps"], 3);
    const json info = json::parse(httpGet(server.port, "/api/info").body);
    ASSERT_EQ(info["steps"].size(), 1u);
    EXPECT_EQ(info["steps"][0]["source"], "spherical001.nc");
    WsClient ws(server.port);
    ws.hello();
    json state = smallState();
    state["step"] = 0;
    ws.send({{"type", "state"}, {"id", 1}, {"state", state}});
    EXPECT_FALSE(ws.framesUntilConverged(1).empty());
    EXPECT_TRUE(server.alive());
    EXPECT_TRUE(server.stop()) << server.output();
}

}  // namespace
