#include "server/ws_session.h"

#include "core/error.h"
#include "server/protocol.h"

#include <boost/asio.hpp>
#include <boost/beast/core.hpp>
#include <boost/beast/websocket.hpp>
#include <spdlog/spdlog.h>

#include <deque>

namespace raypc::server {

namespace beast = boost::beast;
namespace http = beast::http;
namespace websocket = beast::websocket;
namespace net = boost::asio;
using tcp = net::ip::tcp;

namespace {

// Beyond this a WebSocket message closes the connection (code 1009); between kMaxClientMessageBytes
// and this it gets an error reply and the connection stays.
constexpr size_t kHardMessageLimit = 4 * 1024 * 1024;

// WebSocket session: parses messages, replies to hello/ping, hands states to its RenderSession and
// writes what it produces. All members are used on the network thread only.
class WsSession : public std::enable_shared_from_this<WsSession> {
public:
    WsSession(tcp::socket&& socket, ServerContext& server) : m_ws(std::move(socket)), m_server(server)
    {
        m_name = fmt::format("session {}", ++server.sessionCounter);
    }
    ~WsSession()
    {
        if (m_render)
            m_render->stop();
    }

    void run(http::request<http::string_body> request)
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
    ServerContext& m_server;
    std::string m_name;
    std::shared_ptr<RenderSession> m_render;
    std::deque<std::pair<bool, std::string>> m_queue;  // (binary, bytes); front is being written
    bool m_writing = false, m_helloDone = false, m_closing = false, m_closed = false;
};

}  // namespace

void startWsSession(tcp::socket&& socket, ServerContext& server, http::request<http::string_body> upgrade)
{
    std::make_shared<WsSession>(std::move(socket), server)->run(std::move(upgrade));
}

}  // namespace raypc::server
