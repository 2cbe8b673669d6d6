// One WebSocket connection of docs/protocol.md (GET /ws): reads client messages, answers hello and
// ping, hands states to the connection's RenderSession and writes what it produces. Internal to the
// server library.
//
// Thread safety: startWsSession is called on the network thread; the session reads and writes there,
// parses and hands over its messages on the server's message thread (one at a time), and renders on a
// thread of its own, until the connection closes. Its bounds are those of limits.h.
#pragma once

#include "server/server_context.h"

#include <boost/asio/ip/tcp.hpp>
#include <boost/beast/http/message.hpp>
#include <boost/beast/http/string_body.hpp>

namespace raypc::server {

// Completes the WebSocket handshake of `upgrade` on `socket` and serves the connection, rendering
// dataset `dataset` (0, or a pair's 1: `/ws?dataset=1`; checked by datasetOfQuery). Only the
// sessions of dataset 0 take part in the linked state (GET/POST /api/link).
void startWsSession(boost::asio::ip::tcp::socket&& socket, ServerContext& server,
                    boost::beast::http::request<boost::beast::http::string_body> upgrade, int dataset = 0);

}  // namespace raypc::server
