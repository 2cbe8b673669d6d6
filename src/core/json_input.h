// JSON that comes from outside the program: state files, HTTP bodies, WebSocket messages, dataset
// manifests, colour-map files. nlohmann's parser and its dump() recurse once per level of nesting,
// so a small document nested 100 000 deep (200 KB: [[[[…]]]]) would exhaust the stack; every such
// text is parsed here, after one linear pass that refuses nesting deeper than kMaxJsonDepth.
#pragma once

#include <nlohmann/json.hpp>

#include <string>
#include <string_view>

namespace raypc {

// No document RayPC reads nests deeper than 6 levels; 64 leaves room and stays far from the stack.
inline constexpr int kMaxJsonDepth = 64;

// Parses `text`. Throws raypc::Error "<what>: not valid JSON: …" (with the parser's position) or
// "<what>: JSON nested deeper than 64 levels (at byte N)"; `what` names the source (a file, "message").
nlohmann::json parseJsonInput(std::string_view text, const std::string& what);

// A value as it may appear in an error message: its JSON text, cut to about `maxChars` characters
// with "…" when longer, so that a message quotes at most a short excerpt of what it refuses.
std::string jsonExcerpt(const nlohmann::json& value, size_t maxChars = 60);

}  // namespace raypc
