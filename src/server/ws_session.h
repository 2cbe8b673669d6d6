// One WebSocket connection of docs/protocol.md (GET /ws): reads client messages, answers hello and
// ping, hands states to the connection's RenderSession and writes what it produces. Internal to the
// server library.
//
// Thread safety: startWsSession is called on the network thread; the session lives there (its render
// work on its own thread) until the connection closes.
#pragma once

#include "server/server_context.h"

#include <boost/asio/ip/tcp.hpp>
#include <boost/beast/http/message.hpp>
#include <boost/beast/http/string_body.hpp>

namespace raypc::server {

// Completes the WebSocket handshake of `upgrade` on `socket` and serves the connection.
void startWsSession(boost::asio::ip::tcp::socket&& socket, ServerContext& server,
                    boost::beast::http::request<boost::beast::http::string_body> upgrade);

}  // namespace raypc::server
