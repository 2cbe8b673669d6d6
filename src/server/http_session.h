// One HTTP connection of docs/protocol.md (keep-alive): checks access, dispatches /api/ requests on
// the route table (dataset_api.h), serves static files and hands WebSocket upgrades of /ws to
// ws_session.h. Internal to the server library.
//
// Thread safety: startHttpSession is called on the network thread; the connection lives there, its
// handlers run on their route's lane.
#pragma once

#include "server/server_context.h"

#include <boost/asio/ip/tcp.hpp>

namespace raypc::server {

void startHttpSession(boost::asio::ip::tcp::socket&& socket, ServerContext& server);

}  // namespace raypc::server
