#include "server/server.h"

#include "core/spare_blocks.h"

#include "core/error.h"
#include "server/access.h"
#include "server/http_session.h"
#include "server/server_context.h"

#include <boost/asio.hpp>
#include <boost/beast/core.hpp>
#include <nlohmann/json.hpp>
#include <spdlog/spdlog.h>

namespace raypc::server {

namespace beast = boost::beast;
namespace net = boost::asio;
using tcp = net::ip::tcp;
using nlohmann::json;

// ---------------------------------------------------------------------------------------------
// The acceptor: one network thread accepts connections and hands each to an HttpSession.

namespace {

// Out of descriptors or kernel memory: retrying at once would fail again (and spin).
bool outOfResources(const beast::error_code& ec)
{
    return ec == net::error::no_descriptors || ec == net::error::no_buffer_space || ec == net::error::no_memory ||
           (ec.category() == net::error::get_system_category() && ec.value() == ENFILE);
}

const std::string kBusyAnswer = [] {
    const std::string body = R"({"error": "too many open connections (--max-connections); try again later"})";
    return "HTTP/1.1 503 Service Unavailable\r\nContent-Type: application/json\r\nRetry-After: 5\r\n"
           "Connection: close\r\nContent-Length: " +
           std::to_string(body.size()) + "\r\n\r\n" + body;
}();

}  // namespace

struct Server::Impl {
    explicit Impl(ServerOptions options) : state(std::move(options)) {}

    ServerContext state;  // first: destroyed after the io_context, whose pending handlers own sessions
    net::io_context ioc{1};
    tcp::acceptor acceptor{ioc};
    net::signal_set signals{ioc};
    net::steady_timer acceptPause{ioc};
    std::chrono::milliseconds backoff{0};
    uint64_t acceptFailures = 0;
    bool atConnectionLimit = false;
    uint16_t port = 0;

    void doAccept()
    {
        acceptor.async_accept(net::make_strand(ioc), [this](beast::error_code ec, tcp::socket socket) {
            if (ec == net::error::operation_aborted)
                return;
            if (ec && outOfResources(ec)) {
                pauseAccepting(ec);
                return;
            }
            if (ec) {
                spdlog::warn("accept: {}", ec.message());
            } else {
                if (acceptFailures > 0) {
                    spdlog::info("accept: accepting again after {} failed attempts", acceptFailures);
                    acceptFailures = 0;
                    backoff = {};
                }
                admit(std::move(socket));
            }
            doAccept();
        });
    }

    // Logged once per episode; the pending connections wait in the listen backlog meanwhile.
    void pauseAccepting(const beast::error_code& ec)
    {
        const ServerLimits& limits = state.options.limits;
        if (acceptFailures++ == 0)
            spdlog::error("accept: {}; pausing new connections, retrying every {}-{} ms until it works (logged once)",
                          ec.message(), limits.acceptBackoffMin.count(), limits.acceptBackoffMax.count());
        backoff = backoff.count() == 0 ? limits.acceptBackoffMin : std::min(2 * backoff, limits.acceptBackoffMax);
        acceptPause.expires_after(backoff);
        acceptPause.async_wait([this](beast::error_code waitError) {
            if (!waitError)
                doAccept();
        });
    }

    void admit(tcp::socket socket)
    {
        // Without TCP_NODELAY the kernel holds the tail of a frame until the browser acknowledges the
        // data before it, and the browser delays that acknowledgement (Nagle's algorithm meeting
        // delayed ACKs): tens of ms added to every frame of a playback (measured in docs/ui.md, Time).
        beast::error_code ignored;
        socket.set_option(tcp::no_delay(true), ignored);
        const size_t limit = state.options.limits.maxConnections;
        if (state.openConnections < limit) {
            atConnectionLimit = false;
            startHttpSession(std::move(socket), state);
            return;
        }
        if (!atConnectionLimit)
            spdlog::warn("connections: {} are open, the limit (--max-connections); answering 503 to new ones", limit);
        atConnectionLimit = true;
        auto s = std::make_shared<tcp::socket>(std::move(socket));
        net::async_write(*s, net::buffer(kBusyAnswer), [s](beast::error_code, size_t) {
            beast::error_code ignored;
            s->shutdown(tcp::socket::shutdown_both, ignored);
            s->close(ignored);
        });
    }
};

Server::Server(ServerOptions options) : m_impl(std::make_unique<Impl>(std::move(options)))
{
    ServerContext& s = m_impl->state;
    // A pair shares the cache bound: each dataset gets half (docs/compare.md, "Side by side").
    const size_t cacheBytes = s.options.second ? s.options.cacheBytes / 2 : s.options.cacheBytes;
    // A step change waits for a new step's decoded variable and shading gradient: their memory is
    // made ready in the background (core/spare_blocks.h).
    keepSpareBlocks(true);
    DatasetCaches caches = openDatasetCaches(s.options.dataset, cacheBytes, s.options.cacheEntries);
    s.dataset = std::move(caches.dataset);
    s.cache = std::move(caches.volumes);
    s.pathlines = std::move(caches.pathlines);
    s.persistence = std::make_unique<PersistenceCache>(s.cache.get());
    s.render.dataset = s.dataset;
    s.render.cache = s.cache.get();
    s.render.pathlines = s.pathlines.get();
    s.render.ranks = s.options.ranks;
    s.render.frameCacheBytes = s.options.limits.frameCacheBytes;
    s.render.frameBudget = &s.frameBudget;
    s.api.dataset = s.dataset;
    s.api.cache = s.cache.get();
    s.api.pathlines = s.pathlines.get();
    s.api.persistence = s.persistence.get();
    s.api.selections = &s.selections;
    s.api.featureSeries = &s.featureSeries;
    s.api.featureLabels = &s.featureLabels;
    s.render.featureLabels = &s.featureLabels;
    s.api.examples = s.options.examples;
    s.api.infoJson = infoJson(*s.dataset, s.options.limits).dump(-1, ' ', false, json::error_handler_t::replace);
    s.api.limits = s.options.limits;
    s.api.series = s.options.series;
    s.api.link = &s.link;
    s.api.jobs = &s.jobProgress;
    s.api.ranks = s.options.ranks;
    if (s.options.second) {
        auto second = std::make_unique<SecondDataset>();
        DatasetCaches c = openDatasetCaches(*s.options.second, cacheBytes, s.options.cacheEntries);
        second->dataset = std::move(c.dataset);
        second->cache = std::move(c.volumes);
        second->pathlines = std::move(c.pathlines);
        second->persistence = std::make_unique<PersistenceCache>(second->cache.get());
        second->render.dataset = second->dataset;
        second->render.cache = second->cache.get();
        second->render.pathlines = second->pathlines.get();
        second->render.ranks = s.options.ranks;
        second->render.frameCacheBytes = s.options.limits.frameCacheBytes;
        second->render.frameBudget = &s.frameBudget;
        second->render.pairFirst = s.dataset;
        ApiContext& api = second->api;
        api = s.api;
        api.dataset = second->dataset;
        api.cache = second->cache.get();
        api.pathlines = second->pathlines.get();
        api.persistence = second->persistence.get();
        api.selections = &second->selections;
        api.featureSeries = &second->featureSeries;
        api.featureLabels = &second->featureLabels;
        second->render.featureLabels = &second->featureLabels;
        api.series = nullptr;
        api.ranks = nullptr;  // the ranks map the first dataset only
        api.pairFirst = s.dataset;
        // Each info is its own dataset's, with the pair's key (pairJson) added.
        for (int index : {0, 1}) {
            ApiContext& a = index == 0 ? s.api : api;
            json info = infoJson(*a.dataset, s.options.limits);
            info["pair"] = pairJson(index, *s.dataset, *second->dataset);
            a.infoJson = info.dump(-1, ' ', false, json::error_handler_t::replace);
        }
        s.second = std::move(second);
        s.api.pairSecond = &s.second->api;
    }
    s.assets = s.options.assets;
    s.site.loopback = isLoopbackHost(s.options.host);
    for (const auto& origin : s.options.allowedOrigins)
        s.site.allowedOrigins.push_back(normaliseOrigin(origin, "--allow-origin"));
    if (!isTokenFreeListenAddress(s.options.host))
        s.token = s.options.token.empty() ? makeAccessToken() : s.options.token;

    const std::string host = s.options.host == "localhost" ? "127.0.0.1" : s.options.host;
    beast::error_code ec;
    const auto address = net::ip::make_address(host, ec);
    if (ec)
        fail("--host '{}': not an IP address ({})", s.options.host, ec.message());
    const tcp::endpoint endpoint(address, s.options.port);
    auto& acceptor = m_impl->acceptor;
    acceptor.open(endpoint.protocol(), ec);
    if (!ec)
        acceptor.set_option(net::socket_base::reuse_address(true), ec);
    if (!ec)
        acceptor.bind(endpoint, ec);
    if (!ec)
        acceptor.listen(net::socket_base::max_listen_connections, ec);
    if (ec)
        fail("cannot listen on {}:{}: {}", s.options.host, s.options.port, ec.message());
    m_impl->port = acceptor.local_endpoint().port();
}

Server::~Server()
{
    // Stop the work first (screenshots and statistics check their cancel flag between tiles and steps),
    // then wait for the threads: shutdown takes about one tile, not one screenshot.
    stop();
    ServerContext& s = m_impl->state;
    s.jobs.cancelAll();
    {
        std::lock_guard lock(s.sessionsMutex);
        for (const auto& weak : s.sessions)
            if (auto session = weak.lock())
                session->cancel();
    }
    for (JobLane* lane : {&s.workers, &s.screenshots, &s.statistics, &s.slices})
        lane->pool().join();
    s.messages.join();
    std::lock_guard lock(s.sessionsMutex);
    for (const auto& weak : s.sessions)
        if (auto session = weak.lock())
            session->stop();
}

uint16_t Server::port() const
{
    return m_impl->port;
}

const std::string& Server::token() const
{
    return m_impl->state.token;
}

std::string Server::url() const
{
    const std::string& host = m_impl->state.options.host;
    const std::string shown = host.find(':') != std::string::npos ? "[" + host + "]" : host;
    std::string url = fmt::format("http://{}:{}/", shown, m_impl->port);
    if (!token().empty())
        url += "?token=" + token();
    return url;
}

void Server::run()
{
    if (m_impl->state.options.handleSignals) {
        m_impl->signals.add(SIGINT);
        m_impl->signals.add(SIGTERM);
        m_impl->signals.async_wait([this](beast::error_code ec, int signal) {
            if (!ec) {
                if (m_impl->state.options.ranks)  // mpirun sends SIGTERM to every rank when one of them dies
                    spdlog::info("signal {}: stopping (under mpirun: the job is stopping; if a rank died, mpirun "
                                 "names it)",
                                 signal);
                else
                    spdlog::info("signal {}: stopping", signal);
                stop();
            }
        });
    }
    m_impl->doAccept();
    // An exception out of one connection's handler must not end the server: log it and serve on.
    for (;;) {
        try {
            m_impl->ioc.run();
            return;
        } catch (const std::exception& e) {
            spdlog::error("server: a connection failed: {}; serving on", e.what());
        }
    }
}

void Server::stop()
{
    net::post(m_impl->ioc, [impl = m_impl.get()] {
        beast::error_code ec;
        impl->acceptor.close(ec);
        impl->signals.cancel(ec);
        impl->acceptPause.cancel();
    });
    m_impl->ioc.stop();
    m_impl->state.jobs.cancelAll();
}

}  // namespace raypc::server
