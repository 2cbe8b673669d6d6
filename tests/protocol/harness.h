// What the server's integration tests and the soak client share: the contest-layout fixture
// preprocessed into a work directory, `raypc serve` in a child process, an HTTP and a WebSocket
// client (Beast, 127.0.0.1 only), and readings of a process from /proc. Failures throw
// std::runtime_error naming what went wrong.
#pragma once

#include "server/protocol.h"

#include <boost/asio.hpp>
#include <boost/beast/core.hpp>
#include <boost/beast/http.hpp>
#include <boost/beast/websocket.hpp>
#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include <cstdint>
#include <filesystem>
#include <mutex>
#include <optional>
#include <string>
#include <sys/types.h>
#include <thread>
#include <utility>
#include <vector>

namespace raypc::servertest {

// The short names the tests use (`using namespace raypc::servertest::aliases;`).
namespace aliases {
namespace beast = boost::beast;
namespace http = beast::http;
namespace websocket = beast::websocket;
namespace net = boost::asio;
using tcp = net::ip::tcp;
using nlohmann::json;
using raypc::server::decodeFrame;
using raypc::server::DecodedFrame;
}  // namespace aliases
using namespace aliases;

// Preprocesses the contest-layout fixture's folder `fixtureDir` (tests/data/contest-layout, written at
// test time) into `work`/ds (2000 sample rows) and writes a small asset directory `work`/assets and a
// file outside it, `work`/secret.txt.
void prepareWorkDir(const std::filesystem::path& work, const std::string& raypcExe, const std::string& fixtureDir);

// For gtest programs: prepareWorkDir in a new temporary directory before the tests (removed after).
class WorkDirEnvironment : public ::testing::Environment {
public:
    WorkDirEnvironment(std::string raypcExe, std::string fixtureDir)
        : m_exe(std::move(raypcExe)), m_fixture(std::move(fixtureDir))
    {
    }
    void SetUp() override;
    void TearDown() override;
    static const std::filesystem::path& work();

private:
    std::string m_exe, m_fixture;
};

// `raypc serve` in a child process; stopped (SIGTERM, then SIGKILL) on destruction. `launcher`, if
// given, starts it (e.g. {"scripts/mpirun-local.sh", "-np", "2"}: a distributed server). `inputs`:
// what it serves (default: the fixture's dataset `work`/ds).
class ServerProcess {
public:
    ServerProcess(const std::string& raypcExe, const std::filesystem::path& work, std::vector<std::string> extra = {},
                  bool verbose = false, std::vector<std::string> launcher = {}, std::vector<std::string> inputs = {});
    ~ServerProcess() { stop(); }
    ServerProcess(const ServerProcess&) = delete;
    ServerProcess& operator=(const ServerProcess&) = delete;

    // Everything the server wrote to stdout and stderr so far.
    std::string output();
    // SIGTERM, then SIGKILL after 5 s. True when the server exited by itself with status 0.
    bool stop();
    // Waits up to `seconds` for the server to exit by itself: its wait status, or nullopt if it
    // still runs then.
    std::optional<int> waitExit(double seconds);
    bool alive() const;
    pid_t pid() const { return m_pid; }

    uint16_t port = 0;
    std::string token, banner;

private:
    pid_t m_pid = -1;
    int m_out = -1;
    std::thread m_drain;
    std::mutex m_mutex;
    std::string m_output;
};

void setReceiveTimeout(tcp::socket& socket, int seconds);

struct HttpAnswer {
    int status = 0;
    std::string body, contentType, setCookie;
    std::string stepsComputed;  // the header X-Raypc-Steps-Computed, empty without it
};
// One request on a new connection (Host: 127.0.0.1:PORT unless `headers` sets it).
HttpAnswer httpRequest(uint16_t port, http::verb method, const std::string& target, const std::string& body = "",
                       const std::vector<std::pair<http::field, std::string>>& headers = {});
HttpAnswer httpGet(uint16_t port, const std::string& target,
                   const std::vector<std::pair<http::field, std::string>>& headers = {});

// A WebSocket client: text messages are parsed as JSON, binary ones as frames.
class WsClient {
public:
    explicit WsClient(uint16_t port, const std::string& target = "/ws");
    void sendText(const std::string& text);
    void sendBinary(const std::string& bytes);
    void send(const json& message) { sendText(message.dump()); }

    struct Message {
        bool binary = false;
        json text;
        DecodedFrame frame;
        std::string raw;
    };
    Message receive();
    // Next text message (binary frames before it are collected into `frames`).
    json receiveText(std::vector<Message>* frames = nullptr);
    void hello();
    // Frames until the converged one of state `id` (frames of other ids are returned too).
    std::vector<Message> framesUntilConverged(int64_t id);
    void close() { m_ws.close(websocket::close_code::normal); }
    websocket::stream<tcp::socket>& stream() { return m_ws; }

private:
    net::io_context m_ioc;
    websocket::stream<tcp::socket> m_ws;
};

// A small still state of the fixture: step 1, 128 x 96, temperature. With more than
// kLongStillPasses passes, adaptive refinement is off, so that every pass renders every pixel.
constexpr int kLongStillPasses = 8;
json smallState(double azimuthDeg = 30, const std::string& colorMap = "viridis", int passes = 2);
// A still that keeps the server busy: smallState(azimuthDeg, "viridis", passes) at width x height.
json slowState(int passes, int width, int height, double azimuthDeg = 10);
std::string jpegOf(const WsClient::Message& m);

// From /proc/PID: anonymous resident memory (kB, RssAnon), its peak as sampled by the caller is up
// to the caller; CPU time used so far (user + system, seconds); open file descriptors.
long rssAnonKb(pid_t pid);
double cpuSeconds(pid_t pid);
int openFileDescriptors(pid_t pid);

}  // namespace raypc::servertest
