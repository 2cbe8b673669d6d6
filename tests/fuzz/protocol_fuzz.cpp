// libFuzzer target: the server's decoding of a client's WebSocket text message
// (server::parseClientMessage, docs/protocol.md). Bad input must give raypc::Error (the server
// replies with it and keeps the connection); anything else is a finding: before the fix, a
// number out of double's range ({"type": "ping", "id": 1e999}, seed ping-id-overflow.json)
// threw json::out_of_range past the session's handler and ended `raypc serve`.
// decodeFrame reads frames the server wrote (the test client's side), not untrusted input.
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
    return 0;
}
