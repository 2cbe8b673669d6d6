// The C++ side of the state schema tests (ui_state_test.mjs): what raypc itself makes of state
// documents, for comparison with the UI's loader and the generated JSON Schema.
//   state_cases default DATASET   toJson(defaultState(dataset)): the state the server hands the UI
//   state_cases parse FILE        FILE holds a JSON array of documents; prints one result per
//                                 document: {"ok": true, "json": toJson(parsed)} or {"ok": false, "error": ...}
#include "core/atomic_file.h"
#include "core/error.h"
#include "dataset/dataset.h"
#include "state/render_state.h"
#include "render/state_renderer.h"

#include <fmt/format.h>
#include <nlohmann/json.hpp>

#include <string>

int main(int argc, char** argv)
{
    using nlohmann::json;
    using namespace raypc;
    const std::string what = argc == 3 ? argv[1] : "";
    try {
        if (what == "default") {
            const auto dataset = dataset::Dataset::open(argv[2]);
            fmt::print("{}\n", state::toJson(render::defaultState(*dataset)).dump());
            return 0;
        }
        if (what == "parse") {
            json results = json::array();
            for (const json& doc : json::parse(readFile(argv[2]))) {
                try {
                    results.push_back({{"ok", true}, {"json", state::toJson(state::parseRenderState(doc, "state"))}});
                } catch (const Error& e) {
                    results.push_back({{"ok", false}, {"error", e.what()}});
                }
            }
            fmt::print("{}\n", results.dump());
            return 0;
        }
    } catch (const std::exception& e) {
        fmt::print(stderr, "state_cases: {}\n", e.what());
        return 1;
    }
    fmt::print(stderr, "usage: state_cases default DATASET | parse FILE\n");
    return 2;
}
