// The distributed server (docs/scaling.md): `raypc serve` under mpirun
// (scripts/mpirun-local.sh) against the same server alone, through the WebSocket protocol. A
// still state's frames must be the same bytes whatever the number of ranks (the tiles are gathered
// as sums, so the picture is bit for bit one process's, and the JPEG encoder is deterministic); a
// new state must cancel a pass on every rank; a rank that dies must end the job, not hang it.
#include "fixture_server.h"

#include <fmt/format.h>
#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include <chrono>
#include <csignal>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <regex>
#include <string>
#include <sys/wait.h>
#include <thread>
#include <vector>

namespace {

using namespace raypc::servertest;

// `raypc serve` of the prepared dataset on `ranks` ranks (1: alone, without mpirun).
// `inputs`: what it serves (default: the fixture's dataset).
class Server : public FixtureServer {
public:
    explicit Server(int ranks, bool verbose = false, std::vector<std::string> inputs = {})
        : FixtureServer({}, verbose,
                        ranks == 1 ? std::vector<std::string>{}
                                   : std::vector<std::string>{RAYPC_MPIRUN_LOCAL, "-np", std::to_string(ranks)},
                        std::move(inputs))
    {
    }
};

// SIGTERM ends the server without an error. Alone its exit status is 0; mpirun exits with 1
// whenever it is sent SIGTERM (whatever its ranks do), so there the log tells: rank 0 stopped the
// other ranks, and neither a rank nor mpirun reported an error.
void expectCleanStop(Server& server, int ranks)
{
    if (ranks == 1) {
        EXPECT_TRUE(server.stop()) << "the server stops cleanly on SIGTERM; output: " << server.output();
        return;
    }
    ::kill(server.pid(), SIGTERM);
    const std::optional<int> status = server.waitExit(30);
    ASSERT_TRUE(status.has_value()) << "still running 30 s after SIGTERM: " << server.output();
    const std::string out = server.output();
    EXPECT_NE(out.find(fmt::format("distributed: ranks 1..{} stopped", ranks - 1)), std::string::npos) << out;
    EXPECT_EQ(out.find("error"), std::string::npos) << out;
    EXPECT_EQ(out.find("mpirun noticed"), std::string::npos) << out;
}

// The states whose converged frames are compared: the small still state; a stereo pair (two views,
// each shared out) with pathlines; a size that is not a multiple of the 32-pixel tiles.
std::vector<json> comparedStates()
{
    json stereo = smallState(60, "viridis", 3);
    stereo["version"] = 5;
    stereo["stereo"] = {{"mode", "side-by-side"}, {"eyeSeparationKm", 600}};
    stereo["pathlines"] = {{"visible", true}, {"window", 2}};
    json odd = smallState(-40, "inferno", 2);
    odd["image"] = {{"width", 203}, {"height", 117}};
    return {smallState(30, "viridis", 2), stereo, odd};
}

// The converged frame of each compared state, in order, from a server on `ranks` ranks.
std::vector<WsClient::Message> convergedFrames(int ranks)
{
    Server server(ranks);
    WsClient ws(server.port);
    ws.hello();
    std::vector<WsClient::Message> out;
    int64_t id = 0;
    for (const json& state : comparedStates()) {
        ++id;
        ws.send({{"type", "state"}, {"id", id}, {"state", state}, {"interactive", false}});
        std::vector<WsClient::Message> frames = ws.framesUntilConverged(id);
        out.push_back(std::move(frames.back()));
    }
    ws.close();
    expectCleanStop(server, ranks);
    return out;
}

TEST(DistributedServer, FramesEqualOneProcessOnTwoAndThreeRanks)
{
    const std::vector<WsClient::Message> alone = convergedFrames(1);
    ASSERT_EQ(alone.size(), comparedStates().size());
    for (const auto& m : alone)
        EXPECT_EQ(m.frame.header["ranks"], 1);
    for (int ranks : {2, 3}) {
        const std::vector<WsClient::Message> shared = convergedFrames(ranks);
        ASSERT_EQ(shared.size(), alone.size());
        for (size_t i = 0; i < alone.size(); ++i) {
            const json& h = shared[i].frame.header;
            EXPECT_EQ(h["ranks"], ranks) << "state " << i;
            EXPECT_EQ(h["width"], alone[i].frame.header["width"]) << "state " << i;
            EXPECT_EQ(h["passes"], alone[i].frame.header["passes"]) << "state " << i;
            // Every rank's samples are counted: the same total as one process.
            EXPECT_EQ(h["stats"]["samples"], alone[i].frame.header["stats"]["samples"]) << "state " << i;
            EXPECT_TRUE(jpegOf(shared[i]) == jpegOf(alone[i]))
                << "state " << i << " on " << ranks << " ranks: the JPEG differs from one process's";
            EXPECT_EQ(shared[i].frame.depth, alone[i].frame.depth) << "state " << i << ": depth map";
        }
    }
}

// A still state's level is known before it is prepared: the other ranks prepare its frame while
// rank 0 does, not when its first pass arrives. An interactive state's level depends on rank 0's
// estimate: the other ranks prepare it with its first pass.
TEST(DistributedServer, RanksPrepareAStillFrameAheadOfItsFirstPass)
{
    Server server(2, true);
    WsClient ws(server.port);
    ws.hello();
    ws.send({{"type", "state"}, {"id", 1}, {"state", smallState(30, "viridis", 2)}, {"interactive", false}});
    ws.framesUntilConverged(1);
    ws.send({{"type", "state"}, {"id", 2}, {"state", smallState(40, "viridis", 2)}, {"interactive", true}});
    ws.framesUntilConverged(2);
    ws.close();
    expectCleanStop(server, 2);
    const std::string out = server.output();
    EXPECT_NE(out.find("rank 1: session 1 frame 1 prepared ahead of its first pass"), std::string::npos) << out;
    EXPECT_EQ(out.find("rank 1: session 1 frame 1 prepared at its first pass"), std::string::npos) << out;
    EXPECT_NE(out.find("rank 1: session 1 frame 2 prepared at its first pass"), std::string::npos) << out;
}

// A new state while a long still is being rendered: the ranks drop the old pass, the new state's
// frames follow at once and the old state never converges; and the worker stops part-way through
// its tiles. Whether the new state reaches rank 0 while a pass is shared out or just before the next
// is handed out is timing (then no rank has anything to stop), so the scenario runs up to five
// times, each on a fresh server, until a part-way stop is seen; every run checks the rest.
TEST(DistributedServer, NewStateCancelsThePassOnEveryRank)
{
    const std::regex stopped("session 1 frame 1 pass [0-9]+: 1 of 1 other ranks stopped part-way");
    bool seen = false;
    std::string lastOutput;
    // Whether the new state finds a worker mid-pass is timing: each run sends it at another moment
    // after the first frame (a later one is safe since the gather no longer takes a finished
    // worker's tiles after rank 0's own were cancelled), until a part-way stop is seen.
    const int delaysMs[] = {0, 150, 300, 450, 600};
    for (int attempt = 0; attempt < 5 && !seen; ++attempt) {
        Server server(2);
        WsClient ws(server.port);
        ws.hello();
        const json slow = slowState(400, 1024, 768);
        ws.send({{"type", "state"}, {"id", 1}, {"state", slow}, {"interactive", false}});
        const WsClient::Message first = ws.receive();
        ASSERT_TRUE(first.binary) << first.raw;
        EXPECT_EQ(first.frame.header["id"], 1);
        EXPECT_EQ(first.frame.header["ranks"], 2);
        std::this_thread::sleep_for(std::chrono::milliseconds(delaysMs[attempt]));
        ws.send({{"type", "state"}, {"id", 2}, {"state", smallState(50)}, {"interactive", false}});
        const auto sent = std::chrono::steady_clock::now();
        const std::vector<WsClient::Message> frames = ws.framesUntilConverged(2);
        const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - sent).count();
        for (const auto& m : frames)
            if (m.frame.header["id"] == 1) {
                EXPECT_FALSE(m.frame.header["converged"].get<bool>()) << "the old state went on to converge";
            }
        // 400 passes of 1024x768 take minutes; the new state's 2 small passes come after one old pass at most.
        EXPECT_LT(seconds, 60.0);
        EXPECT_LT(frames.size(), 12u) << "old frames kept coming after the new state";
        // Rank 0 says so once it has gathered the pass (waited for: the line may follow the new
        // state's frames).
        for (int i = 0; i < 20 && !std::regex_search(server.output(), stopped); ++i)
            std::this_thread::sleep_for(std::chrono::milliseconds(100));
        seen = std::regex_search(server.output(), stopped);
        lastOutput = server.output();
        ws.close();
        expectCleanStop(server, 2);
    }
    EXPECT_TRUE(seen) << "in five runs no worker stopped part-way; the last run's log:\n" << lastOutput;
}

// A new state at any moment of a shared-out still gets frames, never an error: when rank 0's own
// tiles of a pass were cancelled while rank 1 had finished its own, rank 0 once gathered rank 1's
// tiles, a pass ahead of its frame, and answered the new state with "gathered tile … block with 3
// passes (frame: 2)". The moments vary, so that some fall between rank 1's last tile and rank 0's.
TEST(DistributedServer, NewStatesAtAnyMomentOfAStillGetFramesNotErrors)
{
    Server server(2);
    WsClient ws(server.port);
    ws.hello();
    int64_t id = 0;
    for (int delayMs : {0, 60, 150, 250, 330, 420, 520, 650, 800, 1000}) {
        const json slow = slowState(400, 1024, 768, 10 + delayMs / 10.0);
        ws.send({{"type", "state"}, {"id", ++id}, {"state", slow}, {"interactive", false}});
        const WsClient::Message first = ws.receive();
        ASSERT_TRUE(first.binary) << "delay " << delayMs << " ms: " << first.raw;
        std::this_thread::sleep_for(std::chrono::milliseconds(delayMs));
        ws.send({{"type", "state"}, {"id", ++id}, {"state", smallState(50 + delayMs / 10.0)}, {"interactive", false}});
        try {
            ws.framesUntilConverged(id);  // throws on a text message (an error)
        } catch (const std::exception& e) {
            FAIL() << "new state " << delayMs << " ms after the first frame: " << e.what();
        }
    }
    ws.close();
    expectCleanStop(server, 2);
}

// POST /api/features on a distributed server: each rank finds the features of a block of steps (with
// the links from the step before its block, and the flux) and rank 0 follows the tracks through
// them: the answer is one process's, byte for byte, on 2 and 3 ranks (3 steps: blocks of 2 + 1 and
// 1 + 1 + 1), for a brush of one shell a step and one of a variable's range.
TEST(DistributedServer, FeaturesAreSharedOutAndAnswerAsOneProcess)
{
    json shell = smallState();
    shell["brushes"] = {{{"name", "depth"}, {"min", 500}, {"max", 1600}}};
    json hot = smallState();
    hot["brushes"] = {{{"name", "temperature"}, {"min", 1800}, {"max", 4000}}, {{"name", "depth"}, {"min", 200}, {"max", 2800}}};
    const std::vector<json> states{shell, hot};
    auto answers = [&](int ranks) {
        Server server(ranks);
        std::vector<std::string> out;
        for (const json& state : states) {
            const auto a = httpRequest(server.port, http::verb::post, "/api/features?job=f1", state.dump());
            EXPECT_EQ(a.status, 200) << ranks << " ranks: " << a.body;
            EXPECT_EQ(a.stepsComputed, "3");
            out.push_back(a.body);
            const json progress = json::parse(httpGet(server.port, "/api/job-progress?job=f1").body);
            EXPECT_EQ(progress["state"], "done") << progress.dump();
            EXPECT_EQ(progress["done"], 3) << progress.dump();
        }
        expectCleanStop(server, ranks);
        if (ranks > 1) {
            EXPECT_NE(server.output().find(fmt::format("features: 3 steps at level 0 computed on {} ranks", ranks)),
                      std::string::npos)
                << server.output();
        }
        return out;
    };
    const std::vector<std::string> alone = answers(1);
    ASSERT_EQ(alone.size(), states.size());
    const json first = json::parse(alone[0]);
    ASSERT_EQ(first["steps"].size(), 3u);
    EXPECT_FALSE(first["tracks"].empty()) << alone[0].substr(0, 400);
    EXPECT_FALSE(first["flux"].is_null());
    for (const int ranks : {2, 3}) {
        const std::vector<std::string> shared = answers(ranks);
        ASSERT_EQ(shared.size(), alone.size());
        for (size_t i = 0; i < alone.size(); ++i)
            EXPECT_TRUE(shared[i] == alone[i]) << "brush " << i << " on " << ranks << " ranks: the answer differs:\n"
                                               << shared[i].substr(0, 600) << "\nalone:\n" << alone[i].substr(0, 600);
    }
}

// A step of another rank's block that cannot be read (values damaged after preprocessing, which
// only its load finds): the request fails with one error naming the rank, the file and the point,
// as one process names them; the server goes on serving.
TEST(DistributedServer, AFeaturesStepThatFailsOnAnotherRankIsOneErrorNamingIt)
{
    const std::filesystem::path ds = WorkDirEnvironment::work() / "ds-damaged";
    std::filesystem::remove_all(ds);
    const std::string preprocess = std::string(RAYPC_EXE) + " preprocess " + RAYPC_CONTEST_LAYOUT_DIR + " -o " +
                                   ds.string() + " --encoding float32 --no-pathlines --quiet >/dev/null";
    ASSERT_EQ(std::system(preprocess.c_str()), 0) << preprocess;
    {  // step 2 (rank 1's of 2: steps 0-1 and 2): NaN where temperature has no missing values
        std::fstream f(ds / "steps" / "0002" / "L0" / "temperature.f32", std::ios::in | std::ios::out | std::ios::binary);
        ASSERT_TRUE(f.good());
        f.seekp(4000);
        const std::string nan(400, '\xff');
        f.write(nan.data(), std::streamsize(nan.size()));
    }
    json state = smallState();
    state["brushes"] = {{{"name", "depth"}, {"min", 500}, {"max", 1600}}};
    auto answer = [&](int ranks) {
        Server server(ranks, false, {ds.string()});
        const auto a = httpRequest(server.port, http::verb::post, "/api/features", state.dump());
        EXPECT_EQ(httpGet(server.port, "/api/info").status, 200) << "the server goes on serving";
        expectCleanStop(server, ranks);
        return a;
    };
    const auto alone = answer(1), shared = answer(2);
    EXPECT_EQ(alone.status, 400) << alone.body;
    EXPECT_EQ(shared.status, 400) << shared.body;
    const std::string message = json::parse(alone.body).at("error").get<std::string>();
    EXPECT_NE(message.find("0002/L0/temperature.f32: point 1000"), std::string::npos) << message;
    EXPECT_EQ(json::parse(shared.body).at("error").get<std::string>(), "rank 1: " + message);
}

// Rank 1 exits in the middle of a pass (the test hook of docs/scaling.md): the job ends with an
// error that names the rank, well within the timeout, and the client's connection closes.
TEST(DistributedServer, RankThatDiesEndsTheJobWithoutHanging)
{
    ::setenv("RAYPC_TEST_DIE_RANK", "1", 1);
    ::setenv("RAYPC_TEST_DIE_AT", "serve-pass", 1);
    Server server(2);
    ::unsetenv("RAYPC_TEST_DIE_RANK");
    ::unsetenv("RAYPC_TEST_DIE_AT");
    WsClient ws(server.port);
    ws.hello();
    setReceiveTimeout(ws.stream().next_layer(), 60);
    ws.send({{"type", "state"}, {"id", 1}, {"state", smallState()}, {"interactive", false}});
    bool closed = false;
    try {
        for (int i = 0; i < 100; ++i)
            ws.receive();
    } catch (const std::exception&) {
        closed = true;
    }
    EXPECT_TRUE(closed) << "the connection stays open after a rank died";
    const std::optional<int> status = server.waitExit(60);
    ASSERT_TRUE(status.has_value()) << "the job still runs 60 s after rank 1 died; output: " << server.output();
    EXPECT_FALSE(WIFEXITED(*status) && WEXITSTATUS(*status) == 0) << "exit status 0 after a rank died";
    const std::string out = server.output();
    EXPECT_NE(out.find("rank 1 exits"), std::string::npos) << out;
    EXPECT_NE(out.find("exited with non-zero status"), std::string::npos) << "mpirun names the rank: " << out;
}

}  // namespace
