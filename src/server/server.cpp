#include "server/server.h"

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
struct Server::Impl {
    ServerContext state;  // first: destroyed after the io_context, whose pending handlers own sessions
    net::io_context ioc{1};
    tcp::acceptor acceptor{ioc};
    net::signal_set signals{ioc};
    uint16_t port = 0;

    void doAccept()
    {
        acceptor.async_accept(net::make_strand(ioc), [this](beast::error_code ec, tcp::socket socket) {
            if (ec) {
                if (ec != net::error::operation_aborted)
                    spdlog::warn("accept: {}", ec.message());
                else
                    return;
            } else {
                startHttpSession(std::move(socket), state);
            }
            doAccept();
        });
    }
};

Server::Server(ServerOptions options) : m_impl(std::make_unique<Impl>())
{
    ServerContext& s = m_impl->state;
    s.options = std::move(options);
    s.dataset = Dataset::open(s.options.dataset);
    s.cache = std::make_unique<StepCache>([dataset = s.dataset](int step, int level) { return dataset->load(step, level); },
                                          s.options.cacheBytes, s.options.cacheEntries);
    s.pathlines = std::make_unique<PathlineCache>(s.options.dataset);
    s.render.dataset = s.dataset;
    s.render.cache = s.cache.get();
    s.render.pathlines = s.pathlines.get();
    s.api.dataset = s.dataset;
    s.api.cache = s.cache.get();
    s.api.pathlines = s.pathlines.get();
    s.api.examples = s.options.examples;
    s.api.infoJson = infoJson(*s.dataset).dump(-1, ' ', false, json::error_handler_t::replace);
    s.assets = s.options.assets;
    if (!isLoopbackHost(s.options.host))
        s.token = makeAccessToken();

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
    stop();
    m_impl->state.workers.join();
    std::lock_guard lock(m_impl->state.sessionsMutex);
    for (const auto& weak : m_impl->state.sessions)
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
                spdlog::info("signal {}: stopping", signal);
                stop();
            }
        });
    }
    m_impl->doAccept();
    m_impl->ioc.run();
}

void Server::stop()
{
    net::post(m_impl->ioc, [impl = m_impl.get()] {
        beast::error_code ec;
        impl->acceptor.close(ec);
        impl->signals.cancel(ec);
    });
    m_impl->ioc.stop();
}

}  // namespace raypc::server
