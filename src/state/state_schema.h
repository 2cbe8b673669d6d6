// The one description of the state document (STATE.json, docs/state.md): every key with its JSON
// type, bounds, default, meaning, cost class and the document version that added it.
// parseRenderState and toJson (render_state.h), the JSON Schema that the web UI validates loaded
// documents against and generates its TypeScript types from (`raypc state-schema`), and the field
// table of docs/state.md are all derived from it (the table in state_schema.cpp), so adding a key
// is one entry there plus the member of RenderState it fills.
#pragma once

#include <nlohmann/json.hpp>

#include <string>

namespace raypc::state {

// JSON Schema (draft-07) of a state document as a file holds it: every key optional except
// `version`, with the bounds, enums and strictness (no unknown keys) of parseRenderState, keys
// newer than the document's version refused, and `default`/`description` annotations. Three checks
// relate several values and are not expressible in JSON Schema, so only parseRenderState makes
// them: min <= max in brushes and pathline filters, min < max in ranges, ascending opacity positions.
nlohmann::json stateJsonSchema();

// The field table of docs/state.md (markdown, one row per key, in document order).
std::string stateFieldTable();

}  // namespace raypc::state
