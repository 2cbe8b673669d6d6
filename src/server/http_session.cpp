#include "server/http_session.h"

#include "core/error.h"
#include "server/access.h"
#include "server/protocol.h"
#include "server/ws_session.h"

#include <boost/asio.hpp>
#include <boost/beast/core.hpp>
#include <boost/beast/http.hpp>
#include <boost/beast/websocket.hpp>
#include <nlohmann/json.hpp>
#include <spdlog/spdlog.h>

#include <algorithm>
#include <array>
#include <chrono>
#include <cstdlib>
#include <fstream>
#include <sstream>
#include <sys/socket.h>

namespace raypc::server {

namespace fs = std::filesystem;
namespace beast = boost::beast;
namespace http = beast::http;
namespace websocket = beast::websocket;
namespace net = boost::asio;
using tcp = net::ip::tcp;
using nlohmann::json;
using Request = http::request<http::string_body>;
using Response = http::response<http::string_body>;

namespace {

constexpr auto kHttpTimeout = std::chrono::seconds(60);

const char* kNoUiPage = R"(<!doctype html>
<html><head><meta charset="utf-8"><title>RayPC</title></head>
<body style="font-family: sans-serif; max-width: 40em; margin: 3em auto">
<h1>RayPC server</h1>
<p>The browser UI is not built, so there is nothing to show here yet. Build it (<code>web/</code>,
see its README) or pass <code>--assets DIR</code> / set <code>RAYPC_ASSETS</code>.</p>
<p>The API works: <a href="api/info">api/info</a>, WebSocket <code>/ws</code> (docs/protocol.md).</p>
</body></html>
)";

// A 4xx/5xx answer {"error": message}.
Response errorResponse(http::status status, const std::string& message, unsigned version, bool keepAlive)
{
    Response res{status, version};
    res.set(http::field::content_type, "application/json");
    res.set(http::field::cache_control, "no-store");
    res.body() = json{{"error", message}}.dump(-1, ' ', false, json::error_handler_t::replace);
    res.keep_alive(keepAlive);
    res.prepare_payload();
    return res;
}

Response bodyResponse(std::string body, std::string_view contentType, unsigned version, bool keepAlive)
{
    Response res{http::status::ok, version};
    res.set(http::field::content_type, std::string(contentType));
    res.set(http::field::cache_control, "no-store");
    res.body() = std::move(body);
    res.keep_alive(keepAlive);
    res.prepare_payload();
    return res;
}

Response answerResponse(ApiAnswer answer, unsigned version, bool keepAlive)
{
    return bodyResponse(std::move(answer.body), answer.contentType, version, keepAlive);
}

// One HTTP connection (keep-alive): routes requests, upgrades /ws to a WsSession. At most one request
// is in flight: the next is read after the answer is written.
class HttpSession : public std::enable_shared_from_this<HttpSession> {
public:
    HttpSession(tcp::socket&& socket, ServerContext& server) : m_stream(std::move(socket)), m_server(server)
    {
        ++m_server.openConnections;
    }
    ~HttpSession() { --m_server.openConnections; }

    void run()
    {
        net::dispatch(m_stream.get_executor(), beast::bind_front_handler(&HttpSession::doRead, shared_from_this()));
    }

private:
    void doRead()
    {
        m_parser.emplace();
        m_parser->body_limit(kMaxHttpBodyBytes);
        m_parser->header_limit(64 * 1024);
        m_stream.expires_after(kHttpTimeout);
        http::async_read(m_stream, m_buffer, *m_parser,
                         beast::bind_front_handler(&HttpSession::onRead, shared_from_this()));
    }

    void onRead(beast::error_code ec, size_t)
    {
        if (ec == http::error::end_of_stream) {
            m_stream.socket().shutdown(tcp::socket::shutdown_send, ec);
            return;
        }
        if (ec == http::error::body_limit) {
            send(errorResponse(http::status::payload_too_large,
                               fmt::format("body over the limit of {} bytes", kMaxHttpBodyBytes), 11, false));
            return;
        }
        if (ec && ec.category() == http::make_error_code(http::error::bad_target).category() &&
            ec != http::error::partial_message) {
            spdlog::warn("http: malformed request: {}", ec.message());
            send(errorResponse(http::status::bad_request, fmt::format("malformed request: {}", ec.message()), 11, false));
            return;
        }
        if (ec) {
            if (ec != beast::error::timeout && ec != net::error::connection_reset)
                spdlog::debug("http: read: {}", ec.message());
            return;
        }
        Request request = m_parser->release();
        const std::string target(request.target());
        auto header = [&](http::field f) -> std::optional<std::string_view> {
            const auto it = request.find(f);
            if (it == request.end())
                return std::nullopt;
            return std::string_view(it->value().data(), it->value().size());
        };
        // Two Host (or Origin) headers are ambiguous: which one a check reads and which one a proxy
        // or browser meant differ. RFC 7230, 5.4: a request with more than one Host gets 400.
        for (const http::field f : {http::field::host, http::field::origin})
            if (request.count(f) > 1) {
                const std::string why = fmt::format("{} {} headers, expected at most one",
                                                    request.count(f), std::string(http::to_string(f)));
                spdlog::warn("http: {} {}: 400 {}", std::string(request.method_string()),
                             std::string(targetPath(target)).substr(0, 200), why);
                send(errorResponse(http::status::bad_request, why, request.version(), false));
                return;
            }
        if (const auto why = crossSiteRefusal(m_server.site, header(http::field::host), header(http::field::origin))) {
            spdlog::warn("http: {} {}: 403 {}", std::string(request.method_string()),
                         std::string(targetPath(target)).substr(0, 200), *why);
            send(errorResponse(http::status::forbidden, *why, request.version(), false));
            return;
        }
        const Credentials credentials{target, std::string(request[http::field::authorization]),
                                      std::string(request[http::field::cookie])};
        if (!tokenAccepted(credentials, m_server.token)) {
            spdlog::warn("http: {} {}: no valid token, 401", std::string(request.method_string()),
                         std::string(targetPath(target)).substr(0, 200));
            send(errorResponse(http::status::unauthorized, "missing or wrong access token (see the URL printed at start)",
                               request.version(), request.keep_alive()));
            return;
        }
        if (websocket::is_upgrade(request)) {
            if (targetPath(target) != "/ws") {
                send(errorResponse(http::status::not_found, "WebSocket endpoint is /ws", request.version(), false));
                return;
            }
            const size_t maxSessions = m_server.options.limits.maxSessions;
            if (m_server.openSessions >= maxSessions) {
                const std::string why =
                    fmt::format("too many sessions: {} are open, the limit is {} (--max-sessions); close another tab "
                                "or try again later",
                                m_server.openSessions.load(), maxSessions);
                spdlog::warn("http: /ws: 503 {}", why);
                send(errorResponse(http::status::service_unavailable, why, request.version(), false));
                return;
            }
            int dataset = 0;
            try {
                dataset = datasetOfQuery(nullptr, targetQuery(target), m_server.datasetCount());
            } catch (const Error& e) {
                spdlog::warn("http: /ws: 400 {}", e.what());
                send(errorResponse(http::status::bad_request, e.what(), request.version(), false));
                return;
            }
            m_stream.expires_never();
            startWsSession(m_stream.release_socket(), m_server, std::move(request), dataset);
            return;
        }
        route(std::move(request));
    }

    void route(Request request)
    {
        const std::string target(request.target());
        const std::string path(targetPath(target));
        const unsigned version = request.version();
        const bool keepAlive = request.keep_alive();
        auto bad = [&](http::status status, const std::string& message) {
            spdlog::warn("http: {} {}: {} {}", std::string(request.method_string()), path.substr(0, 200),
                         int(status), message.substr(0, 300));
            send(errorResponse(status, message, version, keepAlive));
        };
        try {
            if (path.starts_with("/api/")) {
                const auto routes = apiRoutes();
                const auto method = request.method() == http::verb::get    ? std::optional(HttpMethod::Get)
                                    : request.method() == http::verb::post ? std::optional(HttpMethod::Post)
                                                                           : std::nullopt;
                const auto found = std::find_if(routes.begin(), routes.end(),
                                                [&](const Route& r) { return r.path == path && r.method == method; });
                if (found != routes.end()) {
                    checkQueryParameters(*found, targetQuery(target));
                    const ApiContext& api = m_server.apiOf(datasetOfQuery(&*found, targetQuery(target), m_server.datasetCount()));
                    if (found->lane == Lane::Network)
                        send(answerResponse(found->handler(api, {targetQuery(target), request.body(), nullptr}),
                                            version, keepAlive));
                    else
                        offload(*found, api, std::move(request));
                } else if (std::any_of(routes.begin(), routes.end(), [&](const Route& r) { return r.path == path; })) {
                    bad(http::status::method_not_allowed, fmt::format("{}: method not allowed", path));
                } else {
                    bad(http::status::not_found, fmt::format("unknown endpoint {}", path.substr(0, 100)));
                }
                return;
            }
            if (path == "/ws") {
                bad(http::status::upgrade_required, "/ws needs a WebSocket upgrade");
                return;
            }
            if (request.method() != http::verb::get && request.method() != http::verb::head) {
                bad(http::status::method_not_allowed, "static files: GET or HEAD only");
                return;
            }
            serveStatic(request, path, std::string(targetQuery(target)), version, keepAlive);
        } catch (const Error& e) {
            bad(http::status::bad_request, e.what());
        } catch (const std::exception& e) {
            bad(http::status::internal_server_error, e.what());
        }
    }

    void serveStatic(const Request& request, const std::string& path, const std::string& query, unsigned version,
                     bool keepAlive)
    {
        Response res;
        if (!m_server.assets) {
            if (path != "/" && path != "/index.html") {
                send(errorResponse(http::status::not_found, "not found", version, keepAlive));
                return;
            }
            res = bodyResponse(kNoUiPage, "text/html; charset=utf-8", version, keepAlive);
        } else {
            const auto file = resolveStaticPath(*m_server.assets, path);
            if (!file) {
                spdlog::info("http: GET {}: 404", path.substr(0, 200));
                send(errorResponse(http::status::not_found, "not found", version, keepAlive));
                return;
            }
            std::ifstream in(*file, std::ios::binary);
            std::ostringstream content;
            content << in.rdbuf();
            res = bodyResponse(content.str(), mimeType(*file), version, keepAlive);
        }
        // A page opened with a valid ?token= keeps it as a cookie for its later requests.
        if (!m_server.token.empty() && queryParameter(query, "token"))
            res.set(http::field::set_cookie, fmt::format("raypc_token={}; Path=/; HttpOnly; SameSite=Strict", m_server.token));
        if (request.method() == http::verb::head) {
            const auto length = res.body().size();
            res.body().clear();
            res.content_length(length);
        }
        send(std::move(res));
    }

    JobLane& laneOf(Lane lane)
    {
        switch (lane) {
        case Lane::Screenshot: return m_server.screenshots;
        case Lane::Statistics: return m_server.statistics;
        case Lane::Slice: return m_server.slices;
        default: return m_server.workers;
        }
    }

    // Runs the route's handler on its lane; the answer is written back on the network thread. A
    // raypc::Error becomes 400; a full lane 503. While the handler runs, the connection is watched:
    // when the client goes away, the handler's cancel flag is set.
    void offload(const Route& route, const ApiContext& api, Request request)
    {
        JobLane& lane = laneOf(route.lane);
        if (!lane.tryEnter()) {
            const std::string why = fmt::format("busy: {} requests of {} are running or waiting (at most {}); try again later",
                                                lane.maxJobs(), route.path, lane.maxJobs());
            spdlog::warn("http: {}: 503 {}", route.path, why);
            Response res = errorResponse(http::status::service_unavailable, why, request.version(), request.keep_alive());
            res.set(http::field::retry_after, "5");
            send(std::move(res));
            return;
        }
        m_job = m_server.jobs.add();
        watchForDisconnect();
        net::post(lane.pool(), [self = shared_from_this(), &route, &api, &lane, cancel = m_job, request = std::move(request)]() {
            const unsigned version = request.version();
            const bool keepAlive = request.keep_alive();
            const std::string target(request.target());
            Response res;
            try {
                // A request whose client left (or a server that is stopping) while it waited is not started.
                if (*cancel)
                    fail("cancelled before it started (the client went away or the server is stopping)");
                res = answerResponse(route.handler(api, {targetQuery(target), request.body(), cancel.get()}),
                                     version, keepAlive);
            } catch (const Error& e) {
                if (*cancel)
                    spdlog::info("http: {}: {}", route.path, e.what());
                else
                    spdlog::warn("http: {}: {}", route.path, e.what());
                res = errorResponse(http::status::bad_request, e.what(), version, keepAlive);
            } catch (const std::exception& e) {
                spdlog::error("http: {}: {}", route.path, e.what());
                res = errorResponse(http::status::internal_server_error, e.what(), version, keepAlive);
            }
            lane.leave();
            net::post(self->m_stream.get_executor(), [self, res = std::move(res)]() mutable {
                self->m_job.reset();
                beast::error_code ignored;
                self->m_stream.socket().cancel(ignored);  // the watch
                self->send(std::move(res));
            });
        });
    }

    // Waits until the connection becomes readable while a job runs: end of stream or an error means
    // the client has gone, so the job is cancelled; data means a pipelined request (the client is
    // still there, and the watch ends).
    void watchForDisconnect()
    {
        m_stream.socket().async_wait(tcp::socket::wait_read, [self = shared_from_this()](beast::error_code ec) {
            if (ec || !self->m_job)
                return;
            char byte;
            const ssize_t n = ::recv(self->m_stream.socket().native_handle(), &byte, 1, MSG_PEEK | MSG_DONTWAIT);
            if (n > 0)
                return;
            if (n < 0 && (errno == EAGAIN || errno == EWOULDBLOCK || errno == EINTR)) {
                self->watchForDisconnect();
                return;
            }
            spdlog::info("http: the client closed the connection; cancelling its request");
            self->m_job->store(true);
        });
    }

    void send(Response res)
    {
        auto message = std::make_shared<Response>(std::move(res));
        http::async_write(m_stream, *message,
                          [self = shared_from_this(), message](beast::error_code ec, size_t) {
                              if (ec)
                                  return;
                              if (message->need_eof()) {
                                  beast::error_code ignored;
                                  self->m_stream.socket().shutdown(tcp::socket::shutdown_send, ignored);
                                  self->drainThenClose();
                                  return;
                              }
                              self->doRead();
                          });
    }

    // A lingering close: after answering early (413, 400) the client may still be sending; closing
    // with unread input would reset the connection and could destroy the answer in flight, so read
    // and discard until the client is done (or 2 s pass), then close.
    void drainThenClose()
    {
        m_stream.expires_after(std::chrono::seconds(2));
        m_stream.async_read_some(net::buffer(m_drain), [self = shared_from_this()](beast::error_code ec, size_t) {
            if (!ec)
                self->drainThenClose();
        });
    }

    beast::tcp_stream m_stream;
    beast::flat_buffer m_buffer;
    std::array<char, 16384> m_drain{};
    ServerContext& m_server;
    std::optional<http::request_parser<http::string_body>> m_parser;
    std::shared_ptr<std::atomic<bool>> m_job;  // the cancel flag of the request in flight on a lane
};

}  // namespace

void startHttpSession(tcp::socket&& socket, ServerContext& server)
{
    std::make_shared<HttpSession>(std::move(socket), server)->run();
}

}  // namespace raypc::server
