// libFuzzer target: the render state document parser (state::parseRenderState, docs/state.md).
//
// Any JSON document must parse or give raypc::Error; a parsed state must survive toJson and a
// second parse unchanged (so a state the server or the UI saves loads back as it was), and
// resolve against a catalog or give raypc::Error. Anything else is a finding.
#include "core/error.h"
#include "render/resolve_state.h"
#include "state/render_state.h"

#include <cstddef>
#include <cstdint>
#include <cstdlib>
#include <cstdio>
#include <string>

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size)
{
    using namespace raypc;
    const auto document = nlohmann::json::parse(data, data + size, nullptr, /*allow_exceptions=*/false);
    if (document.is_discarded())
        return 0;
    state::RenderState state;
    try {
        state = state::parseRenderState(document);
    } catch (const Error&) {
        return 0;
    }
    const nlohmann::json saved = state::toJson(state);
    state::RenderState reloaded;
    try {
        reloaded = state::parseRenderState(saved);
    } catch (const Error& e) {
        std::fprintf(stderr, "a state's own toJson does not parse: %s\n%s\n", e.what(), saved.dump().c_str());
        std::abort();
    }
    if (state::toJson(reloaded) != saved) {
        std::fprintf(stderr, "toJson(parse(toJson(s))) != toJson(s):\n%s\n%s\n", saved.dump().c_str(),
                     state::toJson(reloaded).dump().c_str());
        std::abort();
    }
    // The contest's variables with plausible global ranges.
    render::VariableCatalog catalog;
    for (const char* name : {"temperature", "vx", "vy", "vz", "temperature anomaly", "radial velocity"}) {
        catalog.names.push_back(name);
        catalog.ranges.push_back({-100.0f, 3000.0f});
    }
    try {
        render::resolveParams(state, catalog);
    } catch (const Error&) {
    }
    return 0;
}
