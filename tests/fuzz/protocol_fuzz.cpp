// libFuzzer target: the server's WebSocket message decoding (server/protocol.h, docs/protocol.md):
// a client's text message (parseClientMessage) and a binary frame (decodeFrame). Bad input must
// give raypc::Error (the server replies with it and keeps the connection); anything else is a
// finding.
#include "core/error.h"
#include "server/protocol.h"

#include <cstddef>
#include <cstdint>
#include <string_view>

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size)
{
    const std::string_view bytes(reinterpret_cast<const char*>(data), size);
    try {
        raypc::server::parseClientMessage(bytes);
    } catch (const raypc::Error&) {
    }
    try {
        raypc::server::decodeFrame(bytes);
    } catch (const raypc::Error&) {
    }
    return 0;
}
