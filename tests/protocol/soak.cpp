// raypc_soak: N WebSocket clients change their state as fast as they can (or every --interval-ms)
// for a while against a `raypc serve` of its own on loopback, while /api/info is asked every 100 ms
// and the server's memory is sampled. Prints frames per client, frame latency (from the state sent to
// its frame) p50/p99, the longest time a client went without a frame, /api/info latency and the
// server's peak anonymous memory; with --max-* bounds, exits 1 naming each bound that was broken.
// The short run is a ctest case (tests/protocol/CMakeLists.txt), the long one bench/soak/run.sh.
//
// raypc_soak --raypc EXE (--fixture CONTEST_LAYOUT_DIR | --dataset DIR) [--clients 4] [--seconds 30]
//            [--size 256x256] [--interval-ms 0] [--server-arg ARG]... [--max-gap-s S]
//            [--max-info-ms MS] [--max-rss-mib MIB]
#include "harness.h"

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <deque>
#include <filesystem>
#include <fstream>
#include <cmath>
#include <iostream>
#include <memory>
#include <optional>
#include <string>
#include <thread>
#include <vector>

namespace {

namespace fs = std::filesystem;
namespace servertest = raypc::servertest;
using namespace servertest::aliases;
using Clock = std::chrono::steady_clock;

struct Options {
    std::string raypc, fixture, dataset;
    int clients = 4;
    double seconds = 30;
    int width = 256, height = 256;
    int intervalMs = 0;
    std::vector<std::string> serverArgs;
    std::optional<double> maxGapSeconds, maxInfoMs, maxRssMiB;
};

[[noreturn]] void usage(const std::string& why)
{
    std::fprintf(stderr, "raypc_soak: %s\n", why.c_str());
    std::exit(2);
}

Options parseOptions(int argc, char** argv)
{
    Options o;
    for (int i = 1; i < argc; ++i) {
        const std::string a = argv[i];
        auto value = [&]() -> std::string {
            if (i + 1 >= argc)
                usage(a + " needs a value");
            return argv[++i];
        };
        auto number = [&]() {
            const std::string v = value();
            try {
                return std::stod(v);
            } catch (const std::exception&) {
                usage(a + ": expected a number, found '" + v + "'");
            }
        };
        if (a == "--raypc")
            o.raypc = value();
        else if (a == "--fixture")
            o.fixture = value();
        else if (a == "--dataset")
            o.dataset = value();
        else if (a == "--clients")
            o.clients = int(number());
        else if (a == "--seconds")
            o.seconds = number();
        else if (a == "--interval-ms")
            o.intervalMs = int(number());
        else if (a == "--server-arg")
            o.serverArgs.push_back(value());
        else if (a.rfind("--server-arg=", 0) == 0)
            o.serverArgs.push_back(a.substr(13));
        else if (a == "--max-gap-s")
            o.maxGapSeconds = number();
        else if (a == "--max-info-ms")
            o.maxInfoMs = number();
        else if (a == "--max-rss-mib")
            o.maxRssMiB = number();
        else if (a == "--size") {
            const std::string v = value();
            if (std::sscanf(v.c_str(), "%dx%d", &o.width, &o.height) != 2 || o.width < 1 || o.height < 1)
                usage("--size: expected WIDTHxHEIGHT, found '" + v + "'");
        } else
            usage("unknown option '" + a + "'");
    }
    if (o.raypc.empty() || (o.fixture.empty() == o.dataset.empty()))
        usage("give --raypc and one of --fixture CONTEST_LAYOUT_DIR or --dataset DIR");
    if (o.clients < 1 || o.seconds <= 0)
        usage("--clients and --seconds must be positive");
    return o;
}

double percentile(std::vector<double> v, double p)
{
    if (v.empty())
        return 0;
    std::sort(v.begin(), v.end());
    return v[std::min(v.size() - 1, size_t(p * double(v.size() - 1) + 0.5))];
}

// One browser tab dragging: sends states (interactive, every 25th a still state of 4 passes, as on
// release) and reads frames, on its own io_context and thread.
class Client {
public:
    Client(int index, uint16_t port, const Options& options, json baseState)
        : m_index(index), m_port(port), m_options(options), m_base(std::move(baseState))
    {
    }

    void run(Clock::time_point end)
    {
        try {
            websocket::stream<tcp::socket> ws(m_ioc);
            m_ws = &ws;
            ws.next_layer().connect(tcp::endpoint(net::ip::make_address("127.0.0.1"), m_port));
            ws.read_message_max(256 << 20);
            ws.handshake("127.0.0.1:" + std::to_string(m_port), "/ws");
            ws.text(true);
            ws.write(net::buffer(std::string(R"({"type": "hello", "protocol": 1})")));
            m_start = Clock::now();
            m_end = end;
            net::steady_timer stopTimer(m_ioc, end);
            stopTimer.async_wait([this](beast::error_code) {
                m_stopping = true;
                beast::error_code ignored;
                m_ws->next_layer().close(ignored);
            });
            doRead();
            sendNext();
            m_ioc.run();
        } catch (const std::exception& e) {
            m_failure = e.what();
        }
        m_ws = nullptr;
    }

    int index() const { return m_index; }
    int64_t statesSent() const { return m_nextId; }
    const std::vector<double>& latenciesMs() const { return m_latenciesMs; }
    size_t frames() const { return m_frameTimes.size(); }
    const std::string& failure() const { return m_failure; }
    const std::vector<std::string>& errors() const { return m_errors; }
    // The longest time without a frame, from the first state to the end of the run.
    double longestGapSeconds() const
    {
        Clock::time_point last = m_start;
        double gap = 0;
        for (const auto t : m_frameTimes) {
            gap = std::max(gap, std::chrono::duration<double>(t - last).count());
            last = t;
        }
        return std::max(gap, std::chrono::duration<double>(m_end - last).count());
    }

private:
    void doRead()
    {
        m_ws->async_read(m_buffer, [this](beast::error_code ec, size_t) {
            if (ec) {
                if (!m_stopping)
                    m_failure = "connection lost: " + ec.message();
                return;
            }
            const std::string bytes = beast::buffers_to_string(m_buffer.data());
            m_buffer.consume(m_buffer.size());
            const auto now = Clock::now();
            if (m_ws->got_binary()) {
                const int64_t id = raypc::server::frameHeader(bytes).value("id", int64_t(-1));
                if (id >= 0 && size_t(id) < m_sentAt.size())
                    m_latenciesMs.push_back(std::chrono::duration<double, std::milli>(now - m_sentAt[size_t(id)]).count());
                m_frameTimes.push_back(now);
            } else {
                const json j = json::parse(bytes, nullptr, false);
                if (j.is_object() && j.value("type", "") == "error" && m_errors.size() < 5)
                    m_errors.push_back(j.value("message", ""));
            }
            doRead();
        });
    }

    void sendNext()
    {
        if (m_stopping)
            return;
        const int64_t id = m_nextId++;
        json state = m_base;
        state["camera"]["azimuthDeg"] = std::fmod(double(m_index) * 90.0 + double(id) * 0.5, 360.0);
        const bool still = id % 25 == 24;
        state["passes"] = still ? 4 : 1;
        m_text = json{{"type", "state"}, {"id", id}, {"state", state}, {"interactive", !still}}.dump();
        m_sentAt.push_back(Clock::now());
        m_ws->text(true);
        m_ws->async_write(net::buffer(m_text), [this](beast::error_code ec, size_t) {
            if (ec) {
                if (!m_stopping)
                    m_failure = "write failed: " + ec.message();
                return;
            }
            if (m_options.intervalMs <= 0) {
                net::post(m_ioc, [this] { sendNext(); });
                return;
            }
            m_timer.expires_after(std::chrono::milliseconds(m_options.intervalMs));
            m_timer.async_wait([this](beast::error_code e) {
                if (!e)
                    sendNext();
            });
        });
    }

    int m_index;
    uint16_t m_port;
    const Options& m_options;
    json m_base;
    net::io_context m_ioc;
    net::steady_timer m_timer{m_ioc};
    websocket::stream<tcp::socket>* m_ws = nullptr;
    beast::flat_buffer m_buffer;
    std::string m_text;
    std::atomic<bool> m_stopping{false};
    int64_t m_nextId = 0;
    std::vector<Clock::time_point> m_sentAt, m_frameTimes;
    std::vector<double> m_latenciesMs;
    std::vector<std::string> m_errors;
    std::string m_failure;
    Clock::time_point m_start, m_end;
};

int soak(const Options& options)
{
    // A work directory as the harness expects it: the dataset as ds/ (the fixture preprocessed, or a
    // link to --dataset) and an asset directory.
    char pattern[] = "/tmp/raypc_soak_XXXXXX";
    if (!::mkdtemp(pattern))
        usage("cannot create a temporary directory");
    const fs::path work = pattern;
    fs::path dataset;
    if (!options.fixture.empty()) {
        servertest::prepareWorkDir(work, options.raypc, options.fixture);
        dataset = work / "ds";
    } else {
        dataset = fs::absolute(options.dataset);
        fs::create_symlink(dataset, work / "ds");
        fs::create_directories(work / "assets");
        std::ofstream(work / "assets" / "index.html") << "<html>raypc soak</html>";
    }
    servertest::ServerProcess server(options.raypc, work, options.serverArgs);
    const json info = json::parse(servertest::httpGet(server.port, "/api/info").body);
    json base = info["defaultState"];
    base["image"] = {{"width", options.width}, {"height", options.height}};
    base["level"] = "auto";

    const long startAnonKb = servertest::rssAnonKb(server.pid());
    std::atomic<bool> done{false};
    long peakAnonKb = startAnonKb;
    std::thread memory([&] {
        while (!done) {
            peakAnonKb = std::max(peakAnonKb, servertest::rssAnonKb(server.pid()));
            std::this_thread::sleep_for(std::chrono::milliseconds(100));
        }
    });
    std::vector<double> infoMs;
    int infoFailures = 0;
    std::thread probe([&] {
        while (!done) {
            const auto t0 = Clock::now();
            try {
                if (servertest::httpGet(server.port, "/api/info").status != 200)
                    ++infoFailures;
            } catch (const std::exception&) {
                ++infoFailures;
            }
            infoMs.push_back(std::chrono::duration<double, std::milli>(Clock::now() - t0).count());
            std::this_thread::sleep_for(std::chrono::milliseconds(100));
        }
    });

    const auto end = Clock::now() + std::chrono::duration_cast<Clock::duration>(std::chrono::duration<double>(options.seconds));
    std::vector<std::unique_ptr<Client>> clients;
    std::vector<std::thread> threads;
    for (int i = 0; i < options.clients; ++i)
        clients.push_back(std::make_unique<Client>(i, server.port, options, base));
    for (auto& c : clients)
        threads.emplace_back([&c, end] { c->run(end); });
    for (auto& t : threads)
        t.join();
    done = true;
    memory.join();
    probe.join();
    const bool serverAlive = server.alive();
    const bool cleanStop = server.stop();

    std::printf("soak: %d clients x %.0f s on %s, %dx%d, states %s (interactive; every 25th still, 4 passes)\n",
                options.clients, options.seconds, dataset.string().c_str(), options.width, options.height,
                options.intervalMs > 0 ? ("every " + std::to_string(options.intervalMs) + " ms").c_str()
                                       : "as fast as the connection takes them");
    std::vector<double> all;
    double worstGap = 0;
    size_t minFrames = SIZE_MAX, maxFrames = 0;
    std::vector<std::string> failures;
    for (const auto& c : clients) {
        const auto& l = c->latenciesMs();
        all.insert(all.end(), l.begin(), l.end());
        worstGap = std::max(worstGap, c->longestGapSeconds());
        minFrames = std::min(minFrames, c->frames());
        maxFrames = std::max(maxFrames, c->frames());
        std::printf("  client %d: %zu frames (%.1f/s), %lld states sent, latency p50 %.0f ms p99 %.0f ms, longest "
                    "without a frame %.2f s%s%s\n",
                    c->index(), c->frames(), double(c->frames()) / options.seconds, (long long)c->statesSent(),
                    percentile(l, 0.5), percentile(l, 0.99), c->longestGapSeconds(),
                    c->failure().empty() ? "" : ", FAILED: ", c->failure().c_str());
        for (const auto& e : c->errors())
            std::printf("    error from the server: %s\n", e.c_str());
        if (!c->failure().empty())
            failures.push_back("client " + std::to_string(c->index()) + ": " + c->failure());
    }
    std::printf("  all: frames per client %zu..%zu, latency p50 %.0f ms p99 %.0f ms, longest without a frame %.2f s\n",
                minFrames, maxFrames, percentile(all, 0.5), percentile(all, 0.99), worstGap);
    std::printf("  /api/info: %zu requests, %d failed, p50 %.1f ms p99 %.1f ms max %.1f ms\n", infoMs.size(),
                infoFailures, percentile(infoMs, 0.5), percentile(infoMs, 0.99), percentile(infoMs, 1.0));
    const double peakMiB = double(peakAnonKb) / 1024, startMiB = double(startAnonKb) / 1024;
    std::printf("  server: anonymous memory %.0f MiB at start, peak %.0f MiB; %s\n", startMiB, peakMiB,
                cleanStop ? "stopped cleanly on SIGTERM" : "did NOT stop cleanly on SIGTERM");

    if (!serverAlive)
        failures.push_back("the server died");
    if (!cleanStop)
        failures.push_back("the server did not exit 0 within 5 s of SIGTERM");
    if (infoFailures > 0)
        failures.push_back(std::to_string(infoFailures) + " /api/info requests failed");
    if (options.maxGapSeconds && worstGap > *options.maxGapSeconds)
        failures.push_back("a client went " + std::to_string(worstGap) + " s without a frame (bound " +
                           std::to_string(*options.maxGapSeconds) + " s)");
    if (options.maxInfoMs && percentile(infoMs, 1.0) > *options.maxInfoMs)
        failures.push_back("/api/info took " + std::to_string(percentile(infoMs, 1.0)) + " ms (bound " +
                           std::to_string(*options.maxInfoMs) + " ms)");
    if (options.maxRssMiB && peakMiB > *options.maxRssMiB)
        failures.push_back("peak anonymous memory " + std::to_string(peakMiB) + " MiB (bound " +
                           std::to_string(*options.maxRssMiB) + " MiB)");
    std::error_code ec;
    fs::remove_all(work, ec);  // the link, not what it points to
    for (const auto& f : failures)
        std::printf("soak: FAILED: %s\n", f.c_str());
    return failures.empty() ? 0 : 1;
}

}  // namespace

int main(int argc, char** argv)
{
    try {
        return soak(parseOptions(argc, argv));
    } catch (const std::exception& e) {
        std::fprintf(stderr, "raypc_soak: %s\n", e.what());
        return 1;
    }
}
