#include "harness.h"

#include <chrono>
#include <csignal>
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <regex>
#include <sstream>
#include <stdexcept>
#include <poll.h>
#include <sys/socket.h>
#include <sys/wait.h>
#include <unistd.h>

namespace raypc::servertest {

namespace fs = std::filesystem;

void prepareWorkDir(const fs::path& work, const std::string& raypcExe, const std::string& fixtureDir)
{
    const std::string command = raypcExe + " preprocess " + fixtureDir + " -o " +
                                (work / "ds").string() + " --quiet --sample-rows 2000 >/dev/null";
    if (std::system(command.c_str()) != 0)
        throw std::runtime_error("failed: " + command);
    fs::create_directories(work / "assets" / "js");
    std::ofstream(work / "assets" / "index.html") << "<html>raypc test page</html>";
    std::ofstream(work / "assets" / "js" / "app.js") << "console.log('app')";
    std::ofstream(work / "secret.txt") << "TOP-SECRET-CONTENT";
}

namespace {
fs::path g_work;
}

void WorkDirEnvironment::SetUp()
{
    char pattern[] = "/tmp/raypc_protocol_XXXXXX";
    ASSERT_NE(::mkdtemp(pattern), nullptr);
    g_work = pattern;
    prepareWorkDir(g_work, m_exe, m_fixture);
}

void WorkDirEnvironment::TearDown()
{
    std::error_code ec;
    fs::remove_all(g_work, ec);
}

const fs::path& WorkDirEnvironment::work()
{
    return g_work;
}

ServerProcess::ServerProcess(const std::string& raypcExe, const fs::path& work, std::vector<std::string> extra,
                             bool verbose, std::vector<std::string> launcher, std::vector<std::string> inputs)
{
    int out[2];
    if (::pipe(out) != 0)
        throw std::runtime_error("pipe");
    std::vector<std::string> args = launcher;
    args.push_back(raypcExe);
    if (verbose)
        args.push_back("-v");
    if (inputs.empty())
        inputs.push_back((work / "ds").string());
    args.push_back("serve");
    args.insert(args.end(), inputs.begin(), inputs.end());
    for (const std::string& a : {std::string("--port"), std::string("0"), std::string("--assets"), (work / "assets").string()})
        args.push_back(a);
    args.insert(args.end(), extra.begin(), extra.end());
    m_pid = ::fork();
    if (m_pid == 0) {
        ::dup2(out[1], 1);
        if (!launcher.empty())
            ::dup2(out[1], 2);  // mpirun reports a rank that died on stderr
        ::close(out[0]);
        ::close(out[1]);
        std::vector<char*> argv;
        for (auto& a : args)
            argv.push_back(a.data());
        argv.push_back(nullptr);
        ::execv(argv[0], argv.data());
        _exit(127);
    }
    ::close(out[1]);
    m_out = out[0];
    // Wait for "raypc: serving http://HOST:PORT/[?token=T]".
    std::string text;
    const auto deadline = std::chrono::steady_clock::now() + std::chrono::seconds(60);
    const std::regex line(R"(raypc: serving http://[^ ]*:(\d+)/(\?token=([0-9a-f]+))?\n)");
    std::smatch m;
    while (!std::regex_search(text, m, line)) {
        pollfd p{m_out, POLLIN, 0};
        const int left = int(std::chrono::duration_cast<std::chrono::milliseconds>(
                                 deadline - std::chrono::steady_clock::now())
                                 .count());
        if (left <= 0 || ::poll(&p, 1, left) <= 0)
            throw std::runtime_error("no 'raypc: serving' line in time; output: " + text);
        char buffer[512];
        const ssize_t n = ::read(m_out, buffer, sizeof buffer);
        if (n <= 0)
            throw std::runtime_error("server exited early; output: " + text);
        text.append(buffer, size_t(n));
    }
    port = uint16_t(std::stoi(m[1]));
    token = m[3];
    banner = text;
    // Keep draining the server's output (its log) so that it never blocks on a full pipe.
    m_output = text;
    m_drain = std::thread([this] {
        char buffer[4096];
        for (;;) {
            const ssize_t n = ::read(m_out, buffer, sizeof buffer);
            if (n <= 0)
                return;
            std::lock_guard lock(m_mutex);
            m_output.append(buffer, size_t(n));
        }
    });
}

std::string ServerProcess::output()
{
    std::lock_guard lock(m_mutex);
    return m_output;
}

bool ServerProcess::stop()
{
    if (m_pid < 0)
        return false;
    ::kill(m_pid, SIGTERM);
    bool clean = false;
    int status = 0;
    int i = 0;
    for (; i < 100; ++i) {
        if (::waitpid(m_pid, &status, WNOHANG) == m_pid) {
            clean = WIFEXITED(status) && WEXITSTATUS(status) == 0;
            break;
        }
        ::usleep(50000);
    }
    if (i == 100) {
        ::kill(m_pid, SIGKILL);
        ::waitpid(m_pid, nullptr, 0);
    }
    if (m_drain.joinable())
        m_drain.join();  // ends at EOF: the server has exited
    ::close(m_out);
    m_pid = -1;
    return clean;
}

std::optional<int> ServerProcess::waitExit(double seconds)
{
    if (m_pid < 0)
        return std::nullopt;
    const auto deadline = std::chrono::steady_clock::now() + std::chrono::duration<double>(seconds);
    int status = 0;
    while (::waitpid(m_pid, &status, WNOHANG) != m_pid) {
        if (std::chrono::steady_clock::now() > deadline)
            return std::nullopt;
        ::usleep(50000);
    }
    if (m_drain.joinable())
        m_drain.join();
    ::close(m_out);
    m_pid = -1;
    return status;
}

bool ServerProcess::alive() const
{
    return ::kill(m_pid, 0) == 0;
}

void setReceiveTimeout(tcp::socket& socket, int seconds)
{
    timeval tv{seconds, 0};
    ::setsockopt(socket.native_handle(), SOL_SOCKET, SO_RCVTIMEO, &tv, sizeof tv);
}


HttpAnswer httpRequest(uint16_t port, http::verb method, const std::string& target, const std::string& body,
                       const std::vector<std::pair<http::field, std::string>>& headers)
{
    net::io_context ioc;
    tcp::socket socket(ioc);
    socket.connect(tcp::endpoint(net::ip::make_address("127.0.0.1"), port));
    setReceiveTimeout(socket, 120);
    http::request<http::string_body> req{method, target, 11};
    req.set(http::field::host, "127.0.0.1:" + std::to_string(port));  // as a browser sends it
    for (const auto& [field, value] : headers)
        req.set(field, value);
    if (method == http::verb::post) {
        req.set(http::field::content_type, "application/json");
        req.body() = body;
        req.prepare_payload();
    }
    // A server may answer an oversized body (413) and close before the client has written it
    // all; a failed write is then expected, and the answer is still there to read.
    beast::error_code writeError;
    http::write(socket, req, writeError);
    beast::flat_buffer buffer;
    http::response_parser<http::string_body> parser;
    parser.body_limit(64 * 1024 * 1024);
    beast::error_code ec;
    http::read(socket, buffer, parser, ec);
    if (ec)
        throw std::runtime_error("HTTP " + target + ": " + ec.message() +
                                 (writeError ? " (after a failed write: " + writeError.message() + ")" : ""));
    const auto& res = parser.get();
    return {int(res.result_int()), res.body(), std::string(res[http::field::content_type]),
            std::string(res[http::field::set_cookie]), std::string(res["X-Raypc-Steps-Computed"])};
}

HttpAnswer httpGet(uint16_t port, const std::string& target,
                   const std::vector<std::pair<http::field, std::string>>& headers)
{
    return httpRequest(port, http::verb::get, target, "", headers);
}

// A WebSocket client: text messages are parsed as JSON, binary ones as frames.

WsClient::WsClient(uint16_t port, const std::string& target) : m_ws(m_ioc)
{
    auto& socket = beast::get_lowest_layer(m_ws);
    socket.connect(tcp::endpoint(net::ip::make_address("127.0.0.1"), port));
    setReceiveTimeout(socket, 60);
    m_ws.read_message_max(64 * 1024 * 1024);
    m_ws.handshake("127.0.0.1:" + std::to_string(port), target);
}

void WsClient::sendText(const std::string& text)
{
    m_ws.text(true);
    m_ws.write(net::buffer(text));
}

void WsClient::sendBinary(const std::string& bytes)
{
    m_ws.binary(true);
    m_ws.write(net::buffer(bytes));
}

WsClient::Message WsClient::receive()
{
    beast::flat_buffer buffer;
    m_ws.read(buffer);
    Message m;
    m.raw = beast::buffers_to_string(buffer.data());
    m.binary = m_ws.got_binary();
    if (m.binary) {
        m.frame = raypc::server::decodeFrame(m.raw);  // its jpeg view is not used after the move; see jpegOf
    } else {
        m.text = json::parse(m.raw);
    }
    return m;
}

json WsClient::receiveText(std::vector<Message>* frames)
{
    for (;;) {
        Message m = receive();
        if (!m.binary)
            return m.text;
        if (frames)
            frames->push_back(std::move(m));
    }
}

void WsClient::hello()
{
    send({{"type", "hello"}, {"protocol", 1}});
    const json reply = receiveText();
    if (reply.value("type", "") != "hello" || reply.value("protocol", 0) != 1 || !reply["session"].is_string())
        throw std::runtime_error("unexpected answer to hello: " + reply.dump());
}

std::vector<WsClient::Message> WsClient::framesUntilConverged(int64_t id)
{
    std::vector<Message> frames;
    for (;;) {
        Message m = receive();
        if (!m.binary)
            throw std::runtime_error("unexpected text message: " + m.raw);
        const bool done = m.frame.header["id"] == id && m.frame.header["converged"] == true;
        frames.push_back(std::move(m));
        if (done)
            return frames;
    }
}

json smallState(double azimuthDeg, const std::string& colorMap, int passes)
{
    json state{{"version", 1},
               {"step", 1},
               {"camera", {{"azimuthDeg", azimuthDeg}, {"elevationDeg", 20}, {"distanceKm", 20000}, {"fovYDeg", 40}}},
               {"image", {{"width", 128}, {"height", 96}}},
               {"color", {{"variable", "temperature"}, {"colorMap", colorMap}, {"opacity", {{0, 0.1}, {1, 0.9}}}}},
               {"passes", passes}};
    if (passes > kLongStillPasses) {
        // A long still keeps the server busy for all its passes: no adaptive refinement, which
        // would stop every block of this small image after a few (docs/state.md, version 6).
        state["version"] = 6;
        state["convergenceGreyLevels"] = 0;
    }
    return state;
}

json slowState(int passes, int width, int height, double azimuthDeg)
{
    json state = smallState(azimuthDeg, "viridis", passes);
    state["image"] = {{"width", width}, {"height", height}};
    return state;
}

std::string jpegOf(const WsClient::Message& m)
{
    const auto& h = m.frame.header;
    const size_t headerBytes = m.raw.size() - h["jpegBytes"].get<size_t>() - h["depthBytes"].get<size_t>() - 4;
    return m.raw.substr(4 + headerBytes, h["jpegBytes"].get<size_t>());
}

// ---------------------------------------------------------------------------------------------

namespace {

// The value of "Key:   N kB" in /proc/PID/status, -1 when absent.
long statusKb(pid_t pid, const std::string& key)
{
    std::ifstream in("/proc/" + std::to_string(pid) + "/status");
    std::string line;
    while (std::getline(in, line))
        if (line.rfind(key + ":", 0) == 0)
            return std::stol(line.substr(key.size() + 1));
    return -1;
}

}  // namespace

long rssAnonKb(pid_t pid)
{
    return statusKb(pid, "RssAnon");
}

double cpuSeconds(pid_t pid)
{
    std::ifstream in("/proc/" + std::to_string(pid) + "/stat");
    std::string text((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
    // Fields after the command name (which may hold spaces) in parentheses: utime is the 14th field.
    std::istringstream fields(text.substr(text.rfind(')') + 2));
    std::string field;
    unsigned long long utime = 0, stime = 0;
    for (int i = 3; i <= 15 && fields >> field; ++i) {
        if (i == 14)
            utime = std::stoull(field);
        if (i == 15)
            stime = std::stoull(field);
    }
    return double(utime + stime) / double(::sysconf(_SC_CLK_TCK));
}

int openFileDescriptors(pid_t pid)
{
    int n = 0;
    for ([[maybe_unused]] const auto& entry : fs::directory_iterator("/proc/" + std::to_string(pid) + "/fd"))
        ++n;
    return n;
}

}  // namespace raypc::servertest
