#include "server/server.h"

#include "core/error.h"
#include "core/spherical.h"
#include "data/selection.h"
#include "render/color_map.h"
#include "render/pathline_scene.h"
#include "render/state_renderer.h"
#include "server/access.h"
#include "server/dataset_api.h"
#include "server/image_codec.h"
#include "server/protocol.h"
#include "server/render_session.h"
#include "server/step_cache.h"

#include <boost/asio.hpp>
#include <boost/beast/core.hpp>
#include <boost/beast/http.hpp>
#include <boost/beast/websocket.hpp>
#include <nlohmann/json.hpp>
#include <spdlog/spdlog.h>

#include <array>
#include <chrono>
#include <cstdlib>
#include <deque>
#include <fstream>
#include <sstream>
#include <unistd.h>

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

// Beyond this a WebSocket message closes the connection (code 1009); between kMaxClientMessageBytes
// and this it gets an error reply and the connection stays.
constexpr size_t kHardMessageLimit = 4 * 1024 * 1024;
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

}  // namespace

std::optional<fs::path> findAssetDir(const std::optional<fs::path>& explicitDir)
{
    if (explicitDir) {
        if (!fs::is_directory(*explicitDir))
            fail("--assets {}: not a directory", explicitDir->string());
        return fs::weakly_canonical(*explicitDir);
    }
    std::vector<fs::path> candidates;
    if (const char* env = std::getenv("RAYPC_ASSETS"); env && *env)
        candidates.emplace_back(env);
#ifdef RAYPC_WEB_DIST_DIR
    candidates.emplace_back(RAYPC_WEB_DIST_DIR);
#endif
    std::error_code ec;
    const fs::path exe = fs::read_symlink("/proc/self/exe", ec);
    if (!ec) {
        candidates.push_back(exe.parent_path() / "web");
        candidates.push_back(exe.parent_path() / ".." / "web" / "dist");
    }
    for (const auto& dir : candidates)
        if (fs::is_regular_file(dir / "index.html", ec))
            return fs::weakly_canonical(dir, ec);
    return std::nullopt;
}

// Everything the connections share.
struct ServerState {
    ServerOptions options;
    std::shared_ptr<const Dataset> dataset;
    std::unique_ptr<StepCache> cache;
    std::unique_ptr<PathlineCache> pathlines;
    RenderContext render;
    std::string token;
    std::optional<fs::path> assets;
    std::string infoJson;
    net::thread_pool workers{1};  // screenshots, selections, samples, statistics, pathlines
    std::atomic<uint64_t> sessionCounter{0};
    // Every session's render work, so that shutdown can stop it before the io_context goes away.
    std::mutex sessionsMutex;
    std::vector<std::weak_ptr<RenderSession>> sessions;
};

namespace {

json buildInfo(const Dataset& dataset)
{
    json variables = json::array();
    for (const auto& v : dataset.variables())
        variables.push_back({{"name", v.name},
                             {"units", v.units},
                             {"derived", v.derived},
                             {"min", v.global.range.min},
                             {"max", v.global.range.max},
                             {"mean", v.global.mean},
                             {"histogram", v.global.histogram}});
    json coordinates = json::array();
    for (const auto& c : coordinateInfos()) {
        const CoordinateRange r = coordinateRange(dataset.levels().front().grid, c.id);
        coordinates.push_back({{"name", c.name}, {"units", c.units}, {"min", r.min}, {"max", r.max}});
    }
    json steps = json::array();
    for (const auto& s : dataset.steps())
        steps.push_back({{"index", s.index}, {"timeMyr", s.timeMyr}, {"source", s.source}});
    json levels = json::array();
    for (size_t l = 0; l < dataset.levels().size(); ++l) {
        const auto& lg = dataset.levels()[l].grid;
        levels.push_back({{"level", l}, {"nLat", lg.nLat()}, {"nR", lg.nR()}, {"nLon", lg.nLon()}});
    }
    // The sample's shape without reading it: coordinates then variables.
    json columns = json::array(), units = json::array();
    for (const auto& c : coordinateInfos())
        columns.push_back(c.name), units.push_back(c.units);
    for (const auto& v : dataset.variables())
        columns.push_back(v.name), units.push_back(v.units);
    const SampleTable sample = dataset.loadSample(0);
    json maps = json::array();
    for (const auto m : render::allColorMaps())
        maps.push_back(std::string(render::colorMapName(m)));
    return {{"protocol", kProtocolVersion},
            {"variables", variables},
            {"coordinates", coordinates},
            {"steps", steps},
            {"levels", levels},
            {"sample", {{"rows", sample.rows}, {"columns", sample.columns}, {"units", sample.units}}},
            {"colorMaps", maps},
            {"defaultState", render::toJson(render::defaultState(dataset))}};
}

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

int parseIntParameter(std::string_view query, const char* name)
{
    const auto text = queryParameter(query, name);
    if (!text)
        fail("missing parameter '{}'", name);
    try {
        size_t used = 0;
        const int v = std::stoi(*text, &used);
        if (used == text->size())
            return v;
    } catch (const std::exception&) {
    }
    fail("{}: expected an integer, found '{}'", name, text->substr(0, 40));
}

int checkedStep(const Dataset& dataset, std::string_view query)
{
    const int step = parseIntParameter(query, "step");
    dataset.checkStep(step);
    return step;
}

json parseBody(const std::string& body)
{
    try {
        return json::parse(body);
    } catch (const json::parse_error& e) {
        fail("body: not valid JSON: {}", e.what());
    }
}

// ---------------------------------------------------------------------------------------------
// WebSocket session: parses messages, replies to hello/ping, hands states to its RenderSession and
// writes what it produces. All members are used on the network thread only.
class WsSession : public std::enable_shared_from_this<WsSession> {
public:
    WsSession(tcp::socket&& socket, ServerState& server) : m_ws(std::move(socket)), m_server(server)
    {
        m_name = fmt::format("session {}", ++server.sessionCounter);
    }
    ~WsSession()
    {
        if (m_render)
            m_render->stop();
    }

    void run(Request request)
    {
        m_ws.set_option(websocket::stream_base::timeout::suggested(beast::role_type::server));
        m_ws.read_message_max(kHardMessageLimit);
        m_ws.async_accept(request, beast::bind_front_handler(&WsSession::onAccept, shared_from_this()));
    }

private:
    void onAccept(beast::error_code ec)
    {
        if (ec) {
            spdlog::warn("{}: WebSocket handshake: {}", m_name, ec.message());
            return;
        }
        spdlog::info("{}: connected", m_name);
        // The render thread hands its output to the network thread; a closed session ignores it.
        auto post = [weak = weak_from_this(), executor = m_ws.get_executor()](bool binary) {
            return [weak, executor, binary](std::string bytes) {
                net::post(executor, [weak, binary, bytes = std::move(bytes)]() mutable {
                    if (auto self = weak.lock())
                        self->enqueue(binary, std::move(bytes));
                });
            };
        };
        m_render = std::make_shared<RenderSession>(m_server.render, SessionSink{post(false), post(true)}, m_name);
        std::lock_guard lock(m_server.sessionsMutex);
        std::erase_if(m_server.sessions, [](const auto& w) { return w.expired(); });
        m_server.sessions.push_back(m_render);
        doRead();
    }

    void doRead()
    {
        m_ws.async_read(m_buffer, beast::bind_front_handler(&WsSession::onRead, shared_from_this()));
    }

    void onRead(beast::error_code ec, size_t bytes)
    {
        if (ec) {
            // Closed tab or broken connection: stop the render work at once.
            if (ec == websocket::error::message_too_big)
                spdlog::warn("{}: message over {} bytes, closing", m_name, kHardMessageLimit);
            spdlog::info("{}: closed ({})", m_name, ec.message());
            if (m_render)
                m_render->stop();
            return;
        }
        const std::string text = beast::buffers_to_string(m_buffer.data());
        m_buffer.consume(m_buffer.size());
        if (!m_ws.got_text()) {
            reject("binary messages are not accepted; send JSON text", std::nullopt);
        } else {
            handleText(text);
        }
        doRead();  // also while closing: the close handshake completes through a read
    }

    void reject(const std::string& message, std::optional<int64_t> id)
    {
        spdlog::warn("{}: {}", m_name, message.substr(0, 300));
        enqueue(false, errorReply(message, id));
    }

    void handleText(const std::string& text)
    {
        ClientMessage message;
        try {
            message = parseClientMessage(text);
        } catch (const Error& e) {
            reject(e.what(), std::nullopt);
            return;
        }
        if (auto* hello = std::get_if<HelloMessage>(&message)) {
            if (hello->protocol != kProtocolVersion) {
                reject(fmt::format("hello: protocol {} is not supported; this server speaks protocol {}",
                                   hello->protocol, kProtocolVersion),
                       std::nullopt);
                m_closing = true;
                return;
            }
            m_helloDone = true;
            enqueue(false, helloReply(m_name.substr(m_name.find(' ') + 1)));
            return;
        }
        if (!m_helloDone) {
            reject("send {\"type\": \"hello\", \"protocol\": 1} first", std::nullopt);
            return;
        }
        if (auto* state = std::get_if<StateMessage>(&message)) {
            try {
                m_render->submit(*state);
            } catch (const Error& e) {
                reject(e.what(), state->id);
            }
        } else if (std::holds_alternative<CancelMessage>(message)) {
            m_render->cancel();
        } else if (auto* ping = std::get_if<PingMessage>(&message)) {
            enqueue(false, pongReply(ping->id));
        }
    }

    void enqueue(bool binary, std::string bytes)
    {
        if (m_closed)
            return;
        if (binary) {
            // The newest frame wins: drop frames still waiting behind a slow connection (never the one
            // being written, never text messages).
            for (size_t i = m_writing ? 1 : 0; i < m_queue.size();)
                if (m_queue[i].first)
                    m_queue.erase(m_queue.begin() + std::ptrdiff_t(i));
                else
                    ++i;
        }
        m_queue.emplace_back(binary, std::move(bytes));
        if (!m_writing)
            doWrite();
    }

    void doWrite()
    {
        m_writing = true;
        m_ws.binary(m_queue.front().first);
        m_ws.async_write(net::buffer(m_queue.front().second),
                         beast::bind_front_handler(&WsSession::onWrite, shared_from_this()));
    }

    void onWrite(beast::error_code ec, size_t)
    {
        m_writing = false;
        if (ec) {
            m_closed = true;
            m_queue.clear();
            if (m_render)
                m_render->stop();
            return;
        }
        m_queue.pop_front();
        if (!m_queue.empty()) {
            doWrite();
        } else if (m_closing && !m_closed) {
            m_closed = true;
            if (m_render)
                m_render->stop();
            m_ws.async_close(websocket::close_code::policy_error,
                             [self = shared_from_this()](beast::error_code) {});
        }
    }

    websocket::stream<beast::tcp_stream> m_ws;
    beast::flat_buffer m_buffer;
    ServerState& m_server;
    std::string m_name;
    std::shared_ptr<RenderSession> m_render;
    std::deque<std::pair<bool, std::string>> m_queue;  // (binary, bytes); front is being written
    bool m_writing = false, m_helloDone = false, m_closing = false, m_closed = false;
};

// ---------------------------------------------------------------------------------------------
// One HTTP connection (keep-alive): routes requests, upgrades /ws to a WsSession.
class HttpSession : public std::enable_shared_from_this<HttpSession> {
public:
    HttpSession(tcp::socket&& socket, ServerState& server) : m_stream(std::move(socket)), m_server(server) {}

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
            m_stream.expires_never();
            std::make_shared<WsSession>(m_stream.release_socket(), m_server)->run(std::move(request));
            return;
        }
        route(std::move(request));
    }

    void route(Request request)
    {
        const std::string target(request.target());
        const std::string path(targetPath(target));
        const std::string query(targetQuery(target));
        const unsigned version = request.version();
        const bool keepAlive = request.keep_alive();
        const auto method = request.method();
        const Dataset& dataset = *m_server.dataset;
        auto bad = [&](http::status status, const std::string& message) {
            spdlog::warn("http: {} {}: {} {}", std::string(request.method_string()), path.substr(0, 200),
                         int(status), message.substr(0, 300));
            send(errorResponse(status, message, version, keepAlive));
        };
        try {
            if (path.starts_with("/api/")) {
                if (path == "/api/info" && method == http::verb::get) {
                    send(bodyResponse(m_server.infoJson, "application/json", version, keepAlive));
                } else if (path == "/api/histogram" && method == http::verb::get) {
                    const int step = checkedStep(dataset, query);
                    const auto name = queryParameter(query, "var");
                    if (!name)
                        fail("missing parameter 'var'");
                    const int var = dataset.variableIndex(*name);
                    if (var < 0)
                        fail("var: unknown variable '{}'", name->substr(0, 80));
                    const VariableStats& s = dataset.steps()[size_t(step)].stats[size_t(var)];
                    const auto& info = dataset.variables()[size_t(var)];
                    send(bodyResponse(json{{"name", info.name},
                                           {"units", info.units},
                                           {"min", s.range.min},
                                           {"max", s.range.max},
                                           {"histogram", s.histogram}}
                                          .dump(),
                                      "application/json", version, keepAlive));
                } else if (path == "/api/sample" && method == http::verb::get) {
                    const int step = checkedStep(dataset, query);
                    offload(version, keepAlive, [this, step] {
                        const SampleTable t = m_server.dataset->loadSample(step);
                        std::string bytes(reinterpret_cast<const char*>(t.values.data()), t.values.size() * sizeof(float));
                        return std::pair<std::string, std::string>(std::move(bytes), "application/octet-stream");
                    });
                } else if (path == "/api/selection" && method == http::verb::post) {
                    auto resolved = std::make_shared<render::ResolvedState>(render::resolveState(parseBody(request.body()), dataset));
                    offload(version, keepAlive, [this, resolved] {
                        const auto volume = m_server.cache->get(resolved->state.step, 0);
                        const auto s = selectedVolume(*volume, resolved->params.brushes);
                        return std::pair<std::string, std::string>(json{{"fractionOfMantle", s.fractionOfMantle},
                                                                        {"volumeKm3", s.volumeKm3},
                                                                        {"step", resolved->state.step}}
                                                                       .dump(),
                                                                   "application/json");
                    });
                } else if (path == "/api/screenshot" && method == http::verb::post) {
                    auto resolved = std::make_shared<render::ResolvedState>(render::resolveState(parseBody(request.body()), dataset));
                    offload(version, keepAlive, [this, resolved] {
                        const auto start = std::chrono::steady_clock::now();
                        render::StateRenderer renderer(m_server.dataset, m_server.render.sources());
                        const auto still = renderer.renderStill(*resolved);
                        const render::FrameBuffer& frame = still.frame;
                        std::string png = encodePng(renderer.picture(frame, *resolved, true), frame.width(),
                                                    frame.height());
                        spdlog::info("screenshot: step {} {}x{} {} passes at level 0 in {:.0f} ms", resolved->state.step,
                                     frame.width(), frame.height(), frame.passes(),
                                     std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start)
                                         .count());
                        return std::pair<std::string, std::string>(std::move(png), "image/png");
                    });
                } else if (path == "/api/presets" && method == http::verb::get) {
                    offload(version, keepAlive, [this] {
                        return std::pair<std::string, std::string>(
                            presetsJson(m_server.options.examples).dump(-1, ' ', false, json::error_handler_t::replace),
                            "application/json");
                    });
                } else if (path == "/api/stats" && method == http::verb::post) {
                    // Level 1 by default (quick); 0 is exact on the full grid.
                    const int levels = int(dataset.levels().size());
                    const int level = queryParameter(query, "level") ? parseIntParameter(query, "level") : std::min(1, levels - 1);
                    dataset.checkLevel(level);
                    auto resolved = std::make_shared<render::ResolvedState>(render::resolveState(parseBody(request.body()), dataset));
                    offload(version, keepAlive, [this, resolved, level] {
                        const auto start = std::chrono::steady_clock::now();
                        const auto& filters = resolved->params.brushes;
                        json stats = selectionStatsJson(*m_server.dataset, *m_server.cache, filters, level, resolved->state.step);
                        spdlog::info("stats: {} steps at level {} in {:.0f} ms", stats["steps"].size(), level,
                                     std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start).count());
                        return std::pair<std::string, std::string>(stats.dump(), "application/json");
                    });
                } else if (path == "/api/pathlines" && method == http::verb::get) {
                    const int step = checkedStep(dataset, query);
                    const int window = queryParameter(query, "window") ? parseIntParameter(query, "window") : 10;
                    if (window < 1 || window > 1000)
                        fail("window: {} out of range 1..1000", window);
                    offload(version, keepAlive, [this, step, window] {
                        const auto sets = m_server.pathlines->get(step, window);
                        return std::pair<std::string, std::string>(pathlineAttributesPayload(*sets, step, window),
                                                                   "application/octet-stream");
                    });
                } else if (path == "/api/info" || path == "/api/histogram" || path == "/api/sample" ||
                           path == "/api/selection" || path == "/api/screenshot" || path == "/api/presets" ||
                           path == "/api/stats" || path == "/api/pathlines") {
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
            if (method != http::verb::get && method != http::verb::head) {
                bad(http::status::method_not_allowed, "static files: GET or HEAD only");
                return;
            }
            serveStatic(request, path, query, version, keepAlive);
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

    // Runs `work` (returning body and content type) on the worker pool; the answer is written back on
    // the network thread. A raypc::Error becomes 400.
    template <typename Work>
    void offload(unsigned version, bool keepAlive, Work work)
    {
        net::post(m_server.workers, [self = shared_from_this(), version, keepAlive, work = std::move(work)]() mutable {
            Response res;
            try {
                auto [body, type] = work();
                res = bodyResponse(std::move(body), type, version, keepAlive);
            } catch (const Error& e) {
                spdlog::warn("http: {}", e.what());
                res = errorResponse(http::status::bad_request, e.what(), version, keepAlive);
            } catch (const std::exception& e) {
                spdlog::error("http: {}", e.what());
                res = errorResponse(http::status::internal_server_error, e.what(), version, keepAlive);
            }
            net::post(self->m_stream.get_executor(),
                      [self, res = std::move(res)]() mutable { self->send(std::move(res)); });
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
    ServerState& m_server;
    std::optional<http::request_parser<http::string_body>> m_parser;
};

}  // namespace

// ---------------------------------------------------------------------------------------------
struct Server::Impl {
    ServerState state;  // first: destroyed after the io_context, whose pending handlers own sessions
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
                std::make_shared<HttpSession>(std::move(socket), state)->run();
            }
            doAccept();
        });
    }
};

Server::Server(ServerOptions options) : m_impl(std::make_unique<Impl>())
{
    ServerState& s = m_impl->state;
    s.options = std::move(options);
    s.dataset = Dataset::open(s.options.dataset);
    s.cache = std::make_unique<StepCache>([dataset = s.dataset](int step, int level) { return dataset->load(step, level); },
                                          s.options.cacheBytes, s.options.cacheEntries);
    s.pathlines = std::make_unique<PathlineCache>(s.options.dataset);
    s.render.dataset = s.dataset;
    s.render.cache = s.cache.get();
    s.render.pathlines = s.pathlines.get();
    s.assets = s.options.assets;
    s.infoJson = buildInfo(*s.dataset).dump(-1, ' ', false, json::error_handler_t::replace);
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
