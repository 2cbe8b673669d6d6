// State documents in tests (header-only; not used by the renderer).
#pragma once

#include "core/error.h"
#include "state/render_state.h"

#include <nlohmann/json.hpp>

#include <string>

namespace raypc::state::testing {

// The message with which parseRenderState refuses `document` (named STATE.json), or "accepted".
inline std::string refusalOf(const nlohmann::json& document)
{
    try {
        parseRenderState(document, "STATE.json");
    } catch (const Error& e) {
        return e.what();
    }
    return "accepted";
}

}  // namespace raypc::state::testing
