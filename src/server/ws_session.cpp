#include "server/ws_session.h"

#include "core/error.h"
#include "state/render_state.h"
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
using Clock = std::chrono::steady_clock;

namespace {

constexpr size_t kMiB = size_t(1) << 20;

// A WebSocket session in two halves. The network half (network thread) reads one message at a time
// and writes a bounded queue; the control half (a strand on the message pool) parses each message,
// answers hello and ping, and decides when a state goes to the RenderSession, so that neither JSON nor
// state validation ever runs on the network thread. The next message is read only when the control
// half is done with the last one: a client that sends faster than that is slowed by TCP, not queued.
class WsSession : public std::enable_shared_from_this<WsSession> {
public:
    WsSession(tcp::socket&& socket, ServerContext& server, int dataset)
        : m_ws(std::move(socket)),
          m_server(server),
          m_dataset(dataset),
          m_limits(server.options.limits),
          m_stallTimer(m_ws.get_executor()),
          m_control(net::make_strand(server.messages))
    {
        m_name = fmt::format("session {}", ++server.sessionCounter);
        ++server.openSessions;
        ++server.openConnections;
    }
    ~WsSession()
    {
        m_server.link.removeSession(m_linkKey.exchange(0));
        if (m_render)
            m_render->stop();
        m_server.frameBudget.release(m_frameBytes);
        --m_server.openSessions;
        --m_server.openConnections;
    }

    void run(http::request<http::string_body> request)
    {
        m_ws.set_option(websocket::stream_base::timeout::suggested(beast::role_type::server));
        m_ws.read_message_max(kHardMessageLimit);
        m_ws.async_accept(request, beast::bind_front_handler(&WsSession::onAccept, shared_from_this()));
    }

private:
    // ---- network half ------------------------------------------------------------------------

    void onAccept(beast::error_code ec)
    {
        if (ec) {
            spdlog::warn("{}: WebSocket handshake: {}", m_name, ec.message());
            return;
        }
        spdlog::info("{}: connected", m_name);
        // The render thread hands its output to the network thread (to write) and tells the control
        // half which state it served (for pacing); a closed session ignores both.
        auto sink = [weak = weak_from_this(), executor = m_ws.get_executor(), control = m_control](bool binary) {
            return [weak, executor, control, binary](std::string bytes, int64_t stateId) {
                const std::optional<int64_t> id = stateId;
                net::post(control, [weak, id] {
                    if (auto self = weak.lock())
                        self->onStateServed(id);
                });
                net::post(executor, [weak, binary, bytes = std::move(bytes)]() mutable {
                    if (auto self = weak.lock())
                        self->enqueue(binary, std::move(bytes));
                });
            };
        };
        try {
            m_render = std::make_shared<RenderSession>(m_server.renderOf(m_dataset), SessionSink{sink(false), sink(true)}, m_name);
        } catch (const std::exception& e) {
            // No render thread (e.g. the process is out of threads or memory): refuse this session, keep
            // the server and the others.
            spdlog::error("{}: cannot start its render thread: {}", m_name, e.what());
            enqueue(false, errorReply(fmt::format("the server cannot start a session now ({}); try again later", e.what())));
            closeAfterWrites(websocket::close_code::try_again_later);
            doRead();
            return;
        }
        {
            std::lock_guard lock(m_server.sessionsMutex);
            std::erase_if(m_server.sessions, [](const auto& w) { return w.expired(); });
            m_server.sessions.push_back(m_render);
        }
        doRead();
    }

    void doRead()
    {
        m_ws.async_read(m_buffer, beast::bind_front_handler(&WsSession::onRead, shared_from_this()));
    }

    void onRead(beast::error_code ec, size_t)
    {
        if (ec) {
            // Closed tab or broken connection: stop the render work at once.
            if (ec == websocket::error::message_too_big)
                spdlog::warn("{}: message over {} bytes, closing", m_name, kHardMessageLimit);
            spdlog::info("{}: closed ({})", m_name, ec.message());
            end();
            return;
        }
        const bool text = m_ws.got_text();
        std::string message = beast::buffers_to_string(m_buffer.data());
        m_buffer.consume(m_buffer.size());
        if (!m_render) {
            doRead();  // refused at the start: only the close handshake is left
            return;
        }
        net::post(m_control, [self = shared_from_this(), text, message = std::move(message)] {
            // Catch at the edge of the worker: an unexpected failure (e.g. out of memory) is this
            // message's error, not the pool's end.
            try {
                if (text)
                    self->handleText(message);
                else
                    self->reject("binary messages are not accepted; send JSON text", std::nullopt);
            } catch (const std::exception& e) {
                self->reject(fmt::format("internal error: {}", e.what()), std::nullopt);
            }
            // Also while closing: the close handshake completes through a read.
            net::post(self->m_ws.get_executor(), [self] { self->doRead(); });
        });
    }

    // The connection is over: no more work, no more writes.
    void end()
    {
        m_ended = true;
        m_closed = true;
        m_server.link.removeSession(m_linkKey.exchange(0));
        m_queue.clear();
        m_queuedTextBytes = 0;
        m_stallTimer.cancel();
        if (m_render)
            m_render->cancel();  // the render thread is joined when the session goes away
    }

    // Closes the TCP connection at once (the client does not read, so a close frame would not get
    // through either).
    void abort(const std::string& why)
    {
        if (m_closed)
            return;
        spdlog::warn("{}: {}; closing the connection", m_name, why);
        end();
        beast::error_code ignored;
        beast::get_lowest_layer(m_ws).socket().shutdown(tcp::socket::shutdown_both, ignored);
        beast::get_lowest_layer(m_ws).close();
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
        } else {
            if (m_queuedTextBytes + bytes.size() > m_limits.maxQueuedTextBytes) {
                abort(fmt::format("{} KiB of replies wait for a client that does not read (limit {} KiB)",
                                  (m_queuedTextBytes + bytes.size()) / 1024, m_limits.maxQueuedTextBytes / 1024));
                return;
            }
            m_queuedTextBytes += bytes.size();
        }
        m_queue.emplace_back(binary, std::move(bytes));
        if (!m_writing)
            doWrite();
    }

    void doWrite()
    {
        m_writing = true;
        m_ws.binary(m_queue.front().first);
        // A write the client does not take within the bound closes the connection.
        const uint64_t write = ++m_writes;
        m_stallTimer.expires_after(m_limits.writeStall);
        m_stallTimer.async_wait([weak = weak_from_this(), write](beast::error_code ec) {
            if (auto self = weak.lock(); !ec && self && self->m_writing && self->m_writes == write)
                self->abort(fmt::format("a message of {} bytes was not taken within {} s",
                                        self->m_queue.front().second.size(),
                                        std::chrono::duration<double>(self->m_limits.writeStall).count()));
        });
        m_ws.async_write(net::buffer(m_queue.front().second),
                         beast::bind_front_handler(&WsSession::onWrite, shared_from_this()));
    }

    void onWrite(beast::error_code ec, size_t)
    {
        m_writing = false;
        m_stallTimer.cancel();
        if (ec) {
            end();
            return;
        }
        if (m_closed)
            return;
        if (!m_queue.front().first)
            m_queuedTextBytes -= m_queue.front().second.size();
        m_queue.pop_front();
        if (!m_queue.empty())
            doWrite();
        else if (m_closeCode)
            startClose();
    }

    // After the queued messages are written, close with `code` (a refused hello or session).
    void closeAfterWrites(websocket::close_code code)
    {
        m_closeCode = code;
        if (!m_writing && m_queue.empty())
            startClose();
    }

    void startClose()
    {
        if (m_closed)
            return;
        end();
        m_ws.async_close(*m_closeCode, [self = shared_from_this()](beast::error_code) {});
    }

    // ---- control half (m_control) ------------------------------------------------------------

    void send(std::string text)
    {
        net::post(m_ws.get_executor(), [self = shared_from_this(), text = std::move(text)]() mutable {
            self->enqueue(false, std::move(text));
        });
    }

    void reject(const std::string& message, std::optional<int64_t> id)
    {
        spdlog::warn("{}: {}", m_name, message.substr(0, 300));
        send(errorReply(message, id));
    }

    void handleText(const std::string& text)
    {
        if (m_ended)
            return;
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
                net::post(m_ws.get_executor(), [self = shared_from_this()] {
                    self->closeAfterWrites(websocket::close_code::policy_error);
                });
                return;
            }
            m_helloDone = true;
            std::string reply = helloReply(m_name.substr(m_name.find(' ') + 1));
            // From now on the session gets the states a program sets (POST /api/link), in order after
            // the hello reply (both are posted to the network thread); the reply is posted once the
            // session counts, so a client that has it finds itself among GET /api/link's sessions.
            if (m_linkKey == 0 && m_dataset == 0) {
                auto sink = [weak = weak_from_this(), executor = m_ws.get_executor()](std::string text) {
                    net::post(executor, [weak, text = std::move(text)]() mutable {
                        if (auto self = weak.lock())
                            self->enqueue(false, std::move(text));
                    });
                };
                m_linkKey = m_server.link.addSession(std::move(sink), [&] { send(std::move(reply)); });
            } else {
                send(std::move(reply));
            }
            return;
        }
        if (!m_helloDone) {
            reject("send {\"type\": \"hello\", \"protocol\": 1} first", std::nullopt);
            return;
        }
        if (auto* state = std::get_if<StateMessage>(&message)) {
            onState(std::move(*state));
        } else if (std::holds_alternative<CancelMessage>(message)) {
            m_held.reset();
            m_awaiting.reset();
            m_render->cancel();
        } else if (auto* ping = std::get_if<PingMessage>(&message)) {
            send(pongReply(ping->id));
        }
    }

    // A state message with its document parsed (once: the render session resolves the parsed state).
    struct ParsedState {
        StateMessage message;
        state::RenderState state;
    };

    void onState(StateMessage message)
    {
        // Frame memory: the session's newest state counts against the server's budget.
        const size_t previous = m_frameBytes;
        ParsedState state{std::move(message), {}};
        try {
            state.state = state::parseRenderState(state.message.state, "state");
            const state::RenderState& s = state.state;
            // A stereo pair holds two eyes' frames.
            const size_t wanted =
                size_t(render::stereoLayout(s.stereo.mode, s.width, s.height).renderedPixels()) * kFrameBytesPerPixel;
            size_t others = 0;
            // The kept frames (server/frame_budget.h) make room for an image: they are only copies.
            if (!m_server.frameBudget.replace(m_frameBytes, wanted, others) &&
                (m_server.frameBudget.reclaimKeptFrames() == 0 ||
                 !m_server.frameBudget.replace(m_frameBytes, wanted, others)))
                fail("image: {}x{}{} needs {} MiB of frame memory, over the limit of the sessions' frame memory: "
                     "{} MiB, of which other sessions hold {} MiB (--session-memory); use a smaller image",
                     s.width, s.height, s.stereo.enabled() ? " (stereo: two eyes)" : "", (wanted + kMiB - 1) / kMiB,
                     m_server.frameBudget.limit() / kMiB,
                     (others + kMiB - 1) / kMiB);
        } catch (const Error& e) {
            reject(e.what(), state.message.id);
            return;
        }
        // Fairness: once the work in flight has gone frameGuarantee without a frame, a newer state no
        // longer cancels it but waits for its frame (only the newest waiting state is kept).
        if (m_awaiting && Clock::now() - m_busySince >= m_limits.frameGuarantee) {
            m_held = std::move(state);
            return;
        }
        submit(std::move(state), previous);
    }

    void submit(ParsedState state, size_t previousFrameBytes)
    {
        const StateMessage& message = state.message;
        try {
            m_render->submit(message.id, std::move(state.state), message.mode);
        } catch (const Error& e) {
            size_t others = 0;
            m_server.frameBudget.replace(m_frameBytes, previousFrameBytes, others);
            reject(e.what(), message.id);
            return;
        }
        if (!m_awaiting)
            m_busySince = Clock::now();
        m_awaiting = message.id;
        // A settled state that goes to rendering is what the UI shows: the linked state (GET /api/link);
        // the steps of playback and dragging are not settled.
        if (message.mode == FrameMode::still && m_dataset == 0)
            m_server.link.commitFromUi(message.state);
    }

    // The render thread sent a frame of state `id`, or an error about it.
    void onStateServed(std::optional<int64_t> id)
    {
        if (m_ended || !m_awaiting || id != m_awaiting)
            return;
        m_awaiting.reset();
        if (m_held) {
            ParsedState next = std::move(*m_held);
            m_held.reset();
            submit(std::move(next), m_frameBytes);
        }
    }

    // Network half (network thread only).
    websocket::stream<beast::tcp_stream> m_ws;
    beast::flat_buffer m_buffer;
    ServerContext& m_server;
    const int m_dataset;  // which dataset this session renders: 0, or a pair's 1
    const ServerLimits& m_limits;
    std::string m_name;
    std::deque<std::pair<bool, std::string>> m_queue;  // (binary, bytes); front is being written
    size_t m_queuedTextBytes = 0;
    net::steady_timer m_stallTimer;
    uint64_t m_writes = 0;
    bool m_writing = false, m_closed = false;
    std::optional<websocket::close_code> m_closeCode;

    // Shared: set on the network thread before the first message, then only read.
    std::shared_ptr<RenderSession> m_render;
    std::atomic<bool> m_ended{false};
    std::atomic<uint64_t> m_linkKey{0};  // in the linked state's sessions (set on hello; 0: not there)

    // Control half (m_control only).
    net::strand<net::thread_pool::executor_type> m_control;
    bool m_helloDone = false;
    std::optional<int64_t> m_awaiting;  // the submitted state whose first frame has not come yet
    Clock::time_point m_busySince;      // since when the session has been without a frame
    std::optional<ParsedState> m_held;
    size_t m_frameBytes = 0;  // this session's share of the frame budget (also released on destruction)
};

}  // namespace

void startWsSession(tcp::socket&& socket, ServerContext& server, http::request<http::string_body> upgrade, int dataset)
{
    std::make_shared<WsSession>(std::move(socket), server, dataset)->run(std::move(upgrade));
}

}  // namespace raypc::server
