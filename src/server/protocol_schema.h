// The one description of the protocol's messages (docs/protocol.md) other than the state document
// (state/state_schema.h, which they reference): every HTTP answer, the WebSocket messages both
// ways and the JSON headers of the binary answers, with every key's JSON type and meaning. From it
// come the UI's TypeScript types (`raypc protocol-schema` → web/src/generated/protocol_types.ts,
// web/build.mjs), the key tables of docs/protocol.md (`--markdown`, checked by a test) and the test
// that every answer the server gives matches its description (tests/protocol/messages_test.mjs).
// The server builds its answers where it computes them (api_views.cpp, render_session.cpp, …);
// a key added there without its entry here fails that test.
#pragma once

#include <nlohmann/json.hpp>

#include <string>
#include <string_view>
#include <vector>

namespace raypc::server {

// JSON Schema (draft-07): `definitions` holds every message and its parts, each with a `title`
// (the TypeScript type's name); a message has `x-carrier`, where it travels (e.g. `GET /api/info`,
// `WebSocket server → client`). Objects are closed (no other keys) and list their required keys.
// The keyword `tsType` names the UI's type of a state document or its camera.
nlohmann::json protocolJsonSchema();

// The key tables of docs/protocol.md (markdown, a heading and a table per message).
std::string protocolMessageTables();

// The keys a message of the definition `title` may have (e.g. "ClientState": type, id, state,
// interactive, playback): what the client messages' parser accepts (protocol.cpp). Throws
// raypc::Error for an unknown title.
const std::vector<std::string>& messageKeys(std::string_view title);

}  // namespace raypc::server
