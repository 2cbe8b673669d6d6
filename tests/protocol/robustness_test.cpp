// Robustness of `raypc serve` (docs/reliability.md, Server): requests from
// other web sites, screenshot limits, cancellation and scheduling, bounded sessions and queues, a
// failed thread creation, descriptor exhaustion and message ids. Each case starts the real server on
// the contest-layout fixture and talks to it on 127.0.0.1; limits are lowered per process with
// prlimit(2) where the case needs the machine to run out of something.
#include "fixture_server.h"

#include <gtest/gtest.h>

#include <chrono>
#include <cstdlib>
#include <fstream>
#include <poll.h>
#include <sys/resource.h>
#include <thread>

namespace {

namespace fs = std::filesystem;
using namespace raypc::servertest;
using Clock = std::chrono::steady_clock;
using Headers = std::vector<std::pair<http::field, std::string>>;

// `raypc serve` of the prepared dataset, with waits on its log.
class Server : public FixtureServer {
public:
    using FixtureServer::FixtureServer;
    // Waits up to `seconds` for `text` to appear in the server's log.
    bool waitForLog(const std::string& text, double seconds)
    {
        const auto deadline = Clock::now() + std::chrono::duration<double>(seconds);
        while (Clock::now() < deadline) {
            if (output().find(text) != std::string::npos)
                return true;
            std::this_thread::sleep_for(std::chrono::milliseconds(50));
        }
        return output().find(text) != std::string::npos;
    }
    // Waits up to `seconds` until the log holds `texts` at least `count` times together.
    bool waitForLogCount(std::initializer_list<const char*> texts, size_t count, double seconds)
    {
        const auto deadline = Clock::now() + std::chrono::duration<double>(seconds);
        for (;;) {
            size_t n = 0;
            for (const char* t : texts)
                n += countInLog(t);
            if (n >= count)
                return true;
            if (Clock::now() >= deadline)
                return false;
            std::this_thread::sleep_for(std::chrono::milliseconds(50));
        }
    }
    size_t countInLog(const std::string& text)
    {
        const std::string log = output();
        size_t n = 0;
        for (size_t at = log.find(text); at != std::string::npos; at = log.find(text, at + 1))
            ++n;
        return n;
    }
};

std::string errorOf(const HttpAnswer& a)
{
    const json j = json::parse(a.body, nullptr, false);
    return j.is_object() && j.contains("error") ? j["error"].get<std::string>() : a.body;
}

// The headers of a browser's WebSocket upgrade from a page of `origin`.
Headers upgradeFrom(const std::string& origin)
{
    return {{http::field::connection, "Upgrade"},
            {http::field::upgrade, "websocket"},
            {http::field::sec_websocket_key, "dGhlIHNhbXBsZSBub25jZQ=="},
            {http::field::sec_websocket_version, "13"},
            {http::field::origin, origin}};
}

// A request sent on a connection that the caller keeps (and may close) without reading the answer.
struct PendingRequest {
    net::io_context ioc;
    tcp::socket socket{ioc};

    PendingRequest(uint16_t port, const std::string& target, const std::string& body)
    {
        socket.connect(tcp::endpoint(net::ip::make_address("127.0.0.1"), port));
        http::request<http::string_body> req{http::verb::post, target, 11};
        req.set(http::field::host, "127.0.0.1");
        req.set(http::field::content_type, "application/json");
        req.body() = body;
        req.prepare_payload();
        http::write(socket, req);
    }
    // True when any answer has arrived (without consuming it).
    bool answered()
    {
        pollfd p{socket.native_handle(), POLLIN, 0};
        return ::poll(&p, 1, 0) > 0;
    }
    HttpAnswer read(int timeoutSeconds)
    {
        setReceiveTimeout(socket, timeoutSeconds);
        beast::flat_buffer buffer;
        http::response_parser<http::string_body> parser;
        http::read(socket, buffer, parser);
        return {int(parser.get().result_int()), parser.get().body(), "", "", ""};
    }
    void close()
    {
        beast::error_code ignored;
        socket.close(ignored);
    }
};

// `count` connections to the server that send nothing, open until the caller drops them.
std::vector<tcp::socket> openIdleConnections(net::io_context& ioc, uint16_t port, int count)
{
    std::vector<tcp::socket> held;
    for (int i = 0; i < count; ++i) {
        held.emplace_back(ioc);
        held.back().connect(tcp::endpoint(net::ip::make_address("127.0.0.1"), port));
    }
    return held;
}

// A screenshot that takes tens of seconds on the fixture (at the pixel-pass limit).
json longScreenshot()
{
    json state = smallState(30, "viridis", 1024);
    state["image"] = {{"width", 512}, {"height", 512}};
    return state;
}

// ---------------------------------------------------------------------------------------------
// Item 10: cross-site access on loopback.

TEST(CrossSite, ForeignOriginsAndHostsAreRefusedOnLoopback)
{
    Server server;
    const std::string port = std::to_string(server.port);
    const std::string own = "http://127.0.0.1:" + port;

    const auto crossSiteSocket = httpGet(server.port, "/ws", upgradeFrom("http://evil.example"));
    EXPECT_EQ(crossSiteSocket.status, 403);
    EXPECT_NE(errorOf(crossSiteSocket).find("Origin 'http://evil.example'"), std::string::npos)
        << crossSiteSocket.body;
    EXPECT_EQ(httpGet(server.port, "/ws", upgradeFrom(own)).status, 101) << "the server's own page";

    // DNS rebinding: a page of evil.example whose name now resolves to 127.0.0.1 sends its own name as
    // Host (and, being same-origin with itself, a matching Origin).
    for (const Headers& headers : {Headers{{http::field::host, "evil.example:" + port}},
                                   Headers{{http::field::host, "evil.example:" + port},
                                           {http::field::origin, "http://evil.example:" + port}}}) {
        const auto rebound = httpGet(server.port, "/api/info", headers);
        EXPECT_EQ(rebound.status, 403);
        EXPECT_NE(errorOf(rebound).find("Host 'evil.example:" + port + "'"), std::string::npos) << rebound.body;
        EXPECT_NE(errorOf(rebound).find("DNS-rebinding"), std::string::npos) << rebound.body;
        EXPECT_EQ(httpGet(server.port, "/", headers).status, 403) << "static files too";
    }

    // A cross-site "simple" POST (text/plain needs no CORS preflight, so the browser sends it).
    const auto post = httpRequest(server.port, http::verb::post, "/api/selection", smallState().dump(),
                                  {{http::field::content_type, "text/plain"}, {http::field::origin, "http://evil.example"}});
    EXPECT_EQ(post.status, 403);
    EXPECT_NE(errorOf(post).find("cross-site request refused"), std::string::npos) << post.body;

    // The server's own page, under each of its names, and clients that are not browsers.
    EXPECT_EQ(httpGet(server.port, "/api/info", {{http::field::origin, own}}).status, 200);
    EXPECT_EQ(httpRequest(server.port, http::verb::post, "/api/selection", smallState().dump(),
                          {{http::field::origin, own}})
                  .status,
              200);
    EXPECT_EQ(httpGet(server.port, "/api/info",
                      {{http::field::host, "localhost:" + port}, {http::field::origin, "http://localhost:" + port}})
                  .status,
              200);
    EXPECT_EQ(httpGet(server.port, "/api/info").status, 200);
    WsClient ws(server.port);
    ws.hello();
}

TEST(CrossSite, AllowOriginAddsATrustedPage)
{
    Server server({"--allow-origin", "http://viz.lab:9000"});
    EXPECT_EQ(httpGet(server.port, "/api/info", {{http::field::origin, "http://viz.lab:9000"}}).status, 200);
    EXPECT_EQ(httpGet(server.port, "/ws", upgradeFrom("http://viz.lab:9000")).status, 101);
    EXPECT_EQ(httpGet(server.port, "/api/info", {{http::field::host, "viz.lab:9000"}}).status, 200)
        << "the allowed page's host names this server";
    EXPECT_EQ(httpGet(server.port, "/api/info", {{http::field::origin, "http://viz.lab:9001"}}).status, 403);
    EXPECT_EQ(httpGet(server.port, "/ws", upgradeFrom("http://evil.example")).status, 403);

    // A malformed value is refused at start with one line naming the option.
    const std::string command = std::string(RAYPC_EXE) + " serve " +
                                (WorkDirEnvironment::work() / "ds").string() +
                                " --port 0 --allow-origin viz.lab:9000 2>&1";
    FILE* pipe = ::popen(command.c_str(), "r");
    ASSERT_NE(pipe, nullptr);
    std::string text;
    char buffer[512];
    while (size_t n = std::fread(buffer, 1, sizeof buffer, pipe))
        text.append(buffer, n);
    const int status = ::pclose(pipe);
    EXPECT_NE(status, 0);
    EXPECT_NE(text.find("--allow-origin 'viz.lab:9000'"), std::string::npos) << text;
    EXPECT_EQ(text.find("raypc: serving"), std::string::npos) << text;
}

TEST(CrossSite, OffLoopbackTheTokenIsKeptAndOriginsAreChecked)
{
    Server server({"--host", "0.0.0.0"});
    ASSERT_EQ(server.token.size(), 32u);
    const Headers bearer{{http::field::authorization, "Bearer " + server.token}};
    EXPECT_EQ(httpGet(server.port, "/api/info").status, 401);
    EXPECT_EQ(httpGet(server.port, "/api/info", bearer).status, 200);
    Headers crossSite = bearer;
    crossSite.emplace_back(http::field::origin, "http://evil.example");
    EXPECT_EQ(httpGet(server.port, "/api/info", crossSite).status, 403);
    Headers otherName = bearer;
    otherName.emplace_back(http::field::host, "my-workstation:" + std::to_string(server.port));
    EXPECT_EQ(httpGet(server.port, "/api/info", otherName).status, 200) << "any name reaches the machine";
}

// ---------------------------------------------------------------------------------------------
// Item 7: screenshots.

TEST(Screenshot, LimitsOnPassesAndSizeAreClearErrors)
{
    Server server;
    auto shoot = [&](int width, int height, int passes) {
        json state = smallState(30, "viridis", passes);
        state["image"] = {{"width", width}, {"height", height}};
        return httpRequest(server.port, http::verb::post, "/api/screenshot", state.dump());
    };
    const auto manyPasses = shoot(128, 96, 100000);
    EXPECT_EQ(manyPasses.status, 400);
    EXPECT_NE(errorOf(manyPasses).find("passes 100000 is over the limit of 1024"), std::string::npos)
        << manyPasses.body;
    const auto huge = shoot(16384, 16384, 1);
    EXPECT_EQ(huge.status, 400);
    EXPECT_NE(errorOf(huge).find("image 16384x16384 is over the limit of 16777216 pixels"), std::string::npos)
        << huge.body;
    const auto tooMuchWork = shoot(2048, 2048, 100);
    EXPECT_EQ(tooMuchWork.status, 400);
    EXPECT_NE(errorOf(tooMuchWork).find("2048x2048 at 100 passes is over the limit of 268435456 pixel-passes"),
              std::string::npos)
        << tooMuchWork.body;
    const auto fine = shoot(64, 48, 2);
    EXPECT_EQ(fine.status, 200) << fine.body;
}

// While a long screenshot renders, the quick endpoints answer (the screenshot has not finished when
// they have); when its client goes away it is cancelled, and the next screenshot starts at once.
TEST(Screenshot, DoesNotBlockOthersAndIsCancelledWhenItsClientGoesAway)
{
    Server server;
    PendingRequest shot(server.port, "/api/screenshot", longScreenshot().dump());
    std::this_thread::sleep_for(std::chrono::milliseconds(500));

    EXPECT_EQ(httpGet(server.port, "/api/sample?step=0").status, 200);
    EXPECT_EQ(httpGet(server.port, "/api/presets").status, 200);
    EXPECT_EQ(httpGet(server.port, "/api/pathlines?step=1").status, 200);
    EXPECT_EQ(httpRequest(server.port, http::verb::post, "/api/selection", smallState().dump()).status, 200);
    EXPECT_EQ(httpRequest(server.port, http::verb::post, "/api/stats", smallState().dump()).status, 200);
    EXPECT_FALSE(shot.answered()) << "the screenshot finished before the others were answered";

    shot.close();
    EXPECT_TRUE(server.waitForLogCount({"screenshot cancelled after", "cancelled before it started"}, 1, 20))
        << server.output();
    const auto next = httpRequest(server.port, http::verb::post, "/api/screenshot", smallState().dump());
    EXPECT_EQ(next.status, 200) << next.body;
}

TEST(Screenshot, WaitingScreenshotsAreBounded)
{
    Server server;
    std::vector<std::unique_ptr<PendingRequest>> shots;
    for (int i = 0; i < 5; ++i)  // one renders, four wait
        shots.push_back(std::make_unique<PendingRequest>(server.port, "/api/screenshot", longScreenshot().dump()));
    PendingRequest sixth(server.port, "/api/screenshot", longScreenshot().dump());
    const auto busy = sixth.read(30);
    EXPECT_EQ(busy.status, 503);
    EXPECT_NE(errorOf(busy).find("busy: 5 requests of /api/screenshot"), std::string::npos) << busy.body;
    for (auto& s : shots)
        s->close();
    // The running one stops within a tile, the waiting ones are not started: five cancellations, at
    // least four of them before the start (the first may not have started either).
    EXPECT_TRUE(server.waitForLogCount({"screenshot cancelled after", "cancelled before it started"}, 5, 20))
        << server.output();
    EXPECT_GE(server.countInLog("cancelled before it started"), 4u) << server.output();
    EXPECT_EQ(httpRequest(server.port, http::verb::post, "/api/screenshot", smallState().dump()).status, 200);
}

// Query parameters are checked as JSON keys are: one the endpoint does not take, or one given twice,
// is 400 naming it; a NUL in a value does not cut the message short.
TEST(Query, UnknownRepeatedAndControlCharactersAreRefusedWhole)
{
    Server server;
    const auto unknown = httpGet(server.port, "/api/histogram?step=0&var=temperature&colour=red");
    EXPECT_EQ(unknown.status, 400);
    EXPECT_NE(errorOf(unknown).find("unknown parameter 'colour' for /api/histogram (it takes step,var)"),
              std::string::npos)
        << unknown.body;
    const auto twice = httpGet(server.port, "/api/histogram?step=0&step=1&var=temperature");
    EXPECT_EQ(twice.status, 400);
    EXPECT_NE(errorOf(twice).find("parameter 'step' is given twice"), std::string::npos) << twice.body;
    const auto none = httpGet(server.port, "/api/info?verbose=1");
    EXPECT_EQ(none.status, 400);
    EXPECT_NE(errorOf(none).find("(it takes none)"), std::string::npos) << none.body;
    const auto nul = httpGet(server.port, "/api/job-progress?job=ab%00cd");
    EXPECT_EQ(nul.status, 400);
    EXPECT_NE(errorOf(nul).find("'ab\\x00cd' is not a job id"), std::string::npos) << nul.body;
    EXPECT_EQ(httpGet(server.port, "/api/histogram?step=0&var=temperature").status, 200);
}

// Map and section pictures run on a lane of their own, bounded as screenshots are: large maps
// asked for at once get 503 beyond one running and four waiting, and the quick requests (presets,
// which waited 40 s behind eight 4096² Robinson maps) are answered while they run.
TEST(Slices, WaitingSlicesAreBoundedAndQuickRequestsAnswer)
{
    Server server;
    json state = smallState(30, "viridis", 1);
    state["version"] = 9;
    state["map"] = {{"depthKm", 1000}, {"projection", "robinson"}};
    state["image"] = {{"width", 4096}, {"height", 4096}};
    std::vector<std::unique_ptr<PendingRequest>> maps;
    for (int i = 0; i < 5; ++i)  // one draws, four wait
        maps.push_back(std::make_unique<PendingRequest>(server.port, "/api/slice?view=map", state.dump()));
    PendingRequest sixth(server.port, "/api/slice?view=map", state.dump());
    const auto busy = sixth.read(30);
    EXPECT_EQ(busy.status, 503);
    EXPECT_NE(errorOf(busy).find("busy: 5 requests of /api/slice"), std::string::npos) << busy.body;
    EXPECT_EQ(httpGet(server.port, "/api/presets").status, 200);
    EXPECT_EQ(httpGet(server.port, "/api/info").status, 200);
    EXPECT_FALSE(maps.back()->answered()) << "the last map was drawn before the quick requests were answered";
    const auto first = maps.front()->read(120);
    EXPECT_EQ(first.status, 200) << first.body;
}

TEST(Screenshot, SigtermDuringALongScreenshotExitsWithinFiveSeconds)
{
    Server server;
    PendingRequest shot(server.port, "/api/screenshot", longScreenshot().dump());
    std::this_thread::sleep_for(std::chrono::seconds(1));
    ASSERT_FALSE(shot.answered());
    const auto start = Clock::now();
    EXPECT_TRUE(server.stop()) << "not stopped by SIGTERM within 5 s, or a non-zero exit";
    EXPECT_LT(Clock::now() - start, std::chrono::seconds(5));
}

// ---------------------------------------------------------------------------------------------
// Item 6: bounded sessions and queues.

// A client that sends pings and never reads the pongs: the replies waiting for it stay under the
// bound, then the server closes the connection; the server's memory does not follow the client.
TEST(Sessions, AClientThatDoesNotReadIsClosedAndMemoryStaysBounded)
{
    Server server;
    WsClient ws(server.port);
    ws.hello();
    const long baselineKb = rssAnonKb(server.pid());
    long peakKb = baselineKb;
    bool closed = false;
    const auto deadline = Clock::now() + std::chrono::seconds(60);
    for (int64_t i = 0; Clock::now() < deadline; ++i) {
        beast::error_code ec;
        ws.stream().text(true);
        ws.stream().write(net::buffer(R"({"type": "ping", "id": )" + std::to_string(i) + "}"), ec);
        if (ec) {
            closed = true;
            break;
        }
        if (i % 2000 == 0)
            peakKb = std::max(peakKb, rssAnonKb(server.pid()));
    }
    EXPECT_TRUE(closed) << "a client that does not read was not closed within 60 s";
    EXPECT_LT(peakKb - baselineKb, 64 * 1024) << "anonymous memory grew by " << (peakKb - baselineKb) << " kB";
    EXPECT_TRUE(server.waitForLog("wait for a client that does not read", 10)) << server.output();
    EXPECT_TRUE(server.alive());
    EXPECT_EQ(httpGet(server.port, "/api/info").status, 200);
}

// A client that asks for frames and never reads them: frames are replaced (never queued), and a
// write not taken within 30 s closes the connection.
TEST(Sessions, AFrameThatIsNotTakenClosesTheConnection)
{
    Server server;
    {
        net::io_context ioc;
        websocket::stream<tcp::socket> ws(ioc);
        // A small receive buffer, so that the kernel does not absorb megabytes of frames.
        ws.next_layer().open(tcp::v4());
        ws.next_layer().set_option(net::socket_base::receive_buffer_size(16 * 1024));
        ws.next_layer().connect(tcp::endpoint(net::ip::make_address("127.0.0.1"), server.port));
        ws.handshake("127.0.0.1", "/ws");
        ws.write(net::buffer(std::string(R"({"type": "hello", "protocol": 1})")));
        json state = smallState(30, "viridis", 100000);
        state["image"] = {{"width", 512}, {"height", 512}};
        ws.write(net::buffer(json{{"type", "state"}, {"id", 1}, {"state", state}}.dump()));
        const long baselineKb = rssAnonKb(server.pid());
        long peakKb = baselineKb;
        const auto deadline = Clock::now() + std::chrono::seconds(75);
        bool closedByServer = false;
        while (Clock::now() < deadline && !closedByServer) {
            std::this_thread::sleep_for(std::chrono::milliseconds(500));
            peakKb = std::max(peakKb, rssAnonKb(server.pid()));
            closedByServer = server.output().find("was not taken within 30 s") != std::string::npos;
        }
        EXPECT_TRUE(closedByServer) << "not closed within 75 s";
        EXPECT_LT(peakKb - baselineKb, 64 * 1024) << "anonymous memory grew by " << (peakKb - baselineKb) << " kB";
    }
    EXPECT_TRUE(server.alive());
    WsClient ws(server.port);
    ws.hello();
    ws.send({{"type", "state"}, {"id", 2}, {"state", smallState(0, "viridis", 1)}});
    ws.framesUntilConverged(2);
}

TEST(Sessions, TheNumberOfSessionsIsCapped)
{
    Server server({"--max-sessions", "2"});
    auto a = std::make_unique<WsClient>(server.port);
    a->hello();
    WsClient b(server.port);
    b.hello();
    const auto third = httpGet(server.port, "/ws", upgradeFrom("http://127.0.0.1:" + std::to_string(server.port)));
    EXPECT_EQ(third.status, 503);
    EXPECT_NE(errorOf(third).find("too many sessions: 2 are open, the limit is 2 (--max-sessions)"), std::string::npos)
        << third.body;
    a->close();
    a.reset();
    // The closed session's place is free again (as soon as the server has seen the close).
    int status = 0;
    for (int i = 0; i < 100 && status != 101; ++i) {
        status = httpGet(server.port, "/ws", upgradeFrom("http://127.0.0.1:" + std::to_string(server.port))).status;
        if (status != 101)
            std::this_thread::sleep_for(std::chrono::milliseconds(100));
    }
    EXPECT_EQ(status, 101);
}

TEST(Sessions, FrameMemoryIsSharedWithinABudget)
{
    Server server({"--session-memory", "100"});
    json big = smallState(30, "viridis", 1);
    big["image"] = {{"width", 1024}, {"height", 1024}};  // 72 MiB of frame memory
    json small = smallState(30, "viridis", 1);
    small["image"] = {{"width", 256}, {"height", 256}};  // 4.5 MiB
    auto a = std::make_unique<WsClient>(server.port);
    a->hello();
    a->send({{"type", "state"}, {"id", 1}, {"state", big}});
    a->framesUntilConverged(1);

    WsClient b(server.port);
    b.hello();
    b.send({{"type", "state"}, {"id", 1}, {"state", big}});
    const json refused = b.receiveText();
    EXPECT_EQ(refused["type"], "error");
    EXPECT_EQ(refused["id"], 1);
    EXPECT_NE(refused["message"].get<std::string>().find(
                  "image: 1024x1024 needs 72 MiB of frame memory, over the limit of the sessions' frame memory: 100 MiB, "
                  "of which other sessions hold 72 MiB (--session-memory)"),
              std::string::npos)
        << refused;
    b.send({{"type", "state"}, {"id", 2}, {"state", small}});
    EXPECT_EQ(b.framesUntilConverged(2).back().frame.header["width"], 256);

    a->close();
    a.reset();
    bool rendered = false;
    for (int id = 3; id < 100 && !rendered; ++id) {  // until the server has seen a's close
        b.send({{"type", "state"}, {"id", id}, {"state", big}});
        WsClient::Message m = b.receive();  // a frame or the error
        while (m.binary && m.frame.header["preview"] == true)  // a quick pass first (docs/protocol.md): the pass follows
            m = b.receive();
        rendered = m.binary && m.frame.header["width"] == 1024;
        if (!rendered)
            std::this_thread::sleep_for(std::chrono::milliseconds(100));
    }
    EXPECT_TRUE(rendered);
}

// With its address space limited, the server cannot create a render thread for a new session: that
// session gets an error and a close, the server and the sessions it has keep working.
TEST(Sessions, AFailedThreadCreationEndsOnlyThatSession)
{
    Server server;
    WsClient first(server.port);
    first.hello();
    long vmKb = -1;
    {
        std::ifstream in("/proc/" + std::to_string(server.pid()) + "/status");
        std::string line;
        while (std::getline(in, line))
            if (line.rfind("VmSize:", 0) == 0)
                vmKb = std::stol(line.substr(7));
    }
    ASSERT_GT(vmKb, 0);
    rlimit limited{rlim_t(vmKb + 40 * 1024) * 1024, RLIM_INFINITY}, old{};
    ASSERT_EQ(::prlimit(server.pid(), RLIMIT_AS, &limited, &old), 0);

    std::vector<std::unique_ptr<WsClient>> sessions;
    std::string refusal;
    for (int i = 0; i < 40 && refusal.empty(); ++i) {
        auto ws = std::make_unique<WsClient>(server.port);
        ws->send({{"type", "hello"}, {"protocol", 1}});
        const json reply = ws->receiveText();
        if (reply["type"] == "error")
            refusal = reply["message"];
        sessions.push_back(std::move(ws));
    }
    EXPECT_NE(refusal.find("the server cannot start a session now"), std::string::npos) << refusal;
    EXPECT_TRUE(server.alive());
    EXPECT_EQ(httpGet(server.port, "/api/info").status, 200);
    first.send({{"type", "ping"}, {"id", 3}});
    EXPECT_EQ(first.receiveText()["id"], 3);

    ASSERT_EQ(::prlimit(server.pid(), RLIMIT_AS, &old, nullptr), 0);
    sessions.clear();
    WsClient again(server.port);
    again.hello();
    again.send({{"type", "state"}, {"id", 1}, {"state", smallState(0, "viridis", 1)}});
    again.framesUntilConverged(1);
}

// ---------------------------------------------------------------------------------------------
// Item 9: out of file descriptors.

TEST(Descriptors, OutOfDescriptorsTheAcceptLoopBacksOffAndLogsOnce)
{
    Server server;
    const int open = openFileDescriptors(server.pid());
    rlimit limited{rlim_t(open + 2), 0}, old{};
    ASSERT_EQ(::prlimit(server.pid(), RLIMIT_NOFILE, nullptr, &old), 0);
    limited.rlim_max = old.rlim_max;
    ASSERT_EQ(::prlimit(server.pid(), RLIMIT_NOFILE, &limited, nullptr), 0);

    // Two connections take the last descriptors; the others wait in the listen backlog while every
    // accept fails.
    net::io_context ioc;
    std::vector<tcp::socket> held = openIdleConnections(ioc, server.port, 8);
    std::this_thread::sleep_for(std::chrono::milliseconds(500));
    const double cpuBefore = cpuSeconds(server.pid());
    std::this_thread::sleep_for(std::chrono::seconds(3));
    const double cpuSpent = cpuSeconds(server.pid()) - cpuBefore;
    EXPECT_LT(cpuSpent, 0.5) << "the accept loop spins";
    EXPECT_EQ(server.countInLog("Too many open files"), 1u) << server.output().substr(0, 2000);

    ASSERT_EQ(::prlimit(server.pid(), RLIMIT_NOFILE, &old, nullptr), 0);
    held.clear();
    EXPECT_EQ(httpGet(server.port, "/api/info").status, 200);
    EXPECT_TRUE(server.waitForLog("accepting again", 5)) << server.output().substr(0, 2000);
}

TEST(Connections, OneMoreThanTheLimitIsAnswered503)
{
    Server server({"--max-connections", "4"});
    net::io_context ioc;
    std::vector<tcp::socket> held = openIdleConnections(ioc, server.port, 4);
    std::this_thread::sleep_for(std::chrono::milliseconds(300));
    const auto refused = httpGet(server.port, "/api/info");
    EXPECT_EQ(refused.status, 503);
    EXPECT_NE(errorOf(refused).find("too many open connections"), std::string::npos) << refused.body;
    held.clear();
    int status = 0;
    for (int i = 0; i < 50 && status != 200; ++i) {
        std::this_thread::sleep_for(std::chrono::milliseconds(100));
        status = httpGet(server.port, "/api/info").status;
    }
    EXPECT_EQ(status, 200);
}

// ---------------------------------------------------------------------------------------------
// Item 11: ids are echoed exactly or refused, never wrapped.

TEST(Messages, IdsAreEchoedExactlyOrRefused)
{
    Server server;
    WsClient ws(server.port);
    ws.hello();
    ws.sendText(R"({"type": "ping", "id": 18446744073709551615})");
    WsClient::Message reply = ws.receive();
    ASSERT_FALSE(reply.binary);
    EXPECT_EQ(reply.text["type"], "error") << reply.raw;
    EXPECT_NE(reply.raw.find("18446744073709551615, out of range"), std::string::npos) << reply.raw;
    for (const char* id : {"9223372036854775807", "-9223372036854775808", "0"}) {
        ws.sendText(std::string(R"({"type": "ping", "id": )") + id + "}");
        reply = ws.receive();
        EXPECT_EQ(reply.raw, std::string(R"({"id":)") + id + R"(,"type":"pong"})");
    }
    ws.sendText(R"({"type": "state", "id": 18446744073709551615, "state": {}})");
    reply = ws.receive();
    EXPECT_EQ(reply.text["type"], "error") << reply.raw;
    EXPECT_NE(reply.raw.find("out of range"), std::string::npos) << reply.raw;
}

// JSON nested 100 000 deep (200 KB, under the body and message limits) crashed
// the server through every path that takes JSON from a client. Each now gets a short error reply
// naming the nesting, and the server and the connection live on.
TEST(Messages, DeeplyNestedJsonIsRefusedAndTheServerLives)
{
    Server server;
    const std::string deep = std::string(100000, '[') + std::string(100000, ']');
    const auto post = httpRequest(server.port, http::verb::post, "/api/selection", R"({"version": 7, "step": )" + deep + "}");
    EXPECT_EQ(post.status, 400);
    EXPECT_NE(post.body.find("nested deeper than"), std::string::npos) << post.body.substr(0, 300);
    EXPECT_LT(post.body.size(), 300u);
    WsClient ws(server.port);
    ws.hello();
    for (const std::string& text : {R"({"type": "ping", "id": )" + deep + "}",
                                    R"({"type": "state", "id": 1, "state": {"version": 7, "step": )" + deep + "}}"}) {
        ws.sendText(text);
        const json reply = ws.receiveText();
        EXPECT_EQ(reply["type"], "error");
        EXPECT_NE(reply.value("message", "").find("nested deeper than"), std::string::npos) << reply.dump().substr(0, 300);
    }
    ws.sendText(R"({"type": "ping", "id": 5})");
    EXPECT_EQ(ws.receiveText()["type"], "pong");
    EXPECT_TRUE(server.alive());
}

// A dataset file cut short while it is served (`truncate -s 0`) killed the server with
// SIGBUS when a session next read it. Now the session gets an error naming the file and the server
// serves on.
TEST(DamagedDataset, AFileCutShortWhileServedIsAnErrorReplyNotACrash)
{
    const auto work = WorkDirEnvironment::work();
    const auto copy = work / "ds-cut";
    std::filesystem::remove_all(copy);
    std::filesystem::copy(work / "ds", copy, std::filesystem::copy_options::recursive);
    FixtureServer server({}, false, {}, {copy.string()});
    WsClient ws(server.port);
    ws.hello();
    ws.send({{"type", "state"}, {"id", 1}, {"state", smallState()}});  // step 1, coloured by temperature
    ws.framesUntilConverged(1);
    for (int level = 0; level < 3; ++level)
        std::filesystem::resize_file(copy / "steps" / "0001" / ("L" + std::to_string(level)) / "vx.u16", 0);
    json byVx = smallState();
    byVx["color"]["variable"] = "vx";
    ws.send({{"type", "state"}, {"id", 2}, {"state", byVx}});
    const json reply = ws.receiveText();
    EXPECT_EQ(reply.value("type", ""), "error") << reply.dump();
    EXPECT_NE(reply.value("message", "").find("vx.u16"), std::string::npos) << reply.dump();
    EXPECT_TRUE(server.alive());
    // The session and the server go on: temperature at step 1, and vx at another step.
    ws.send({{"type", "state"}, {"id", 3}, {"state", smallState(60)}});
    ws.framesUntilConverged(3);
    json step0 = byVx;
    step0["step"] = 0;
    ws.send({{"type", "state"}, {"id", 4}, {"state", step0}});
    ws.framesUntilConverged(4);
    EXPECT_TRUE(server.alive());
    EXPECT_EQ(httpGet(server.port, "/api/info").status, 200);
}

// What counts as a local request: duplicate Host headers, the token on other loopback addresses.

// The status of one raw HTTP request (`text` sent as it is) to `address`:`port`; 0 if none came.
int rawHttpStatus(const std::string& address, uint16_t port, const std::string& text)
{
    net::io_context ioc;
    tcp::socket socket{ioc};
    socket.connect(tcp::endpoint(net::ip::make_address(address), port));
    net::write(socket, net::buffer(text));
    setReceiveTimeout(socket, 10);
    beast::flat_buffer buffer;
    http::response_parser<http::string_body> parser;
    beast::error_code ec;
    http::read(socket, buffer, parser, ec);
    return ec ? 0 : int(parser.get().result_int());
}

TEST(CrossSite, TwoHostHeadersAreRefused)
{
    Server server;
    const std::string port = std::to_string(server.port);
    const std::string one = "GET /api/info HTTP/1.1\r\nHost: 127.0.0.1:" + port + "\r\nConnection: close\r\n\r\n";
    EXPECT_EQ(rawHttpStatus("127.0.0.1", server.port, one), 200);
    const std::string two = "GET /api/info HTTP/1.1\r\nHost: 127.0.0.1:" + port + "\r\nHost: evil.example:" + port +
                            "\r\nConnection: close\r\n\r\n";
    EXPECT_EQ(rawHttpStatus("127.0.0.1", server.port, two), 400);
}

TEST(CrossSite, OtherLoopbackAddressesNeedTheToken)
{
    Server server({"--host", "127.0.0.2"});
    ASSERT_EQ(server.token.size(), 32u) << server.banner;
    const std::string port = std::to_string(server.port);
    const std::string request = "GET /api/info{} HTTP/1.1\r\nHost: 127.0.0.2:" + port + "\r\nConnection: close\r\n\r\n";
    auto withTarget = [&](const std::string& query) {
        std::string r = request;
        r.replace(r.find("{}"), 2, query);
        return r;
    };
    EXPECT_EQ(rawHttpStatus("127.0.0.2", server.port, withTarget("")), 401);
    EXPECT_EQ(rawHttpStatus("127.0.0.2", server.port, withTarget("?token=" + server.token)), 200);
}

}  // namespace
