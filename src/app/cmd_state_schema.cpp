// raypc state-schema [-o FILE] [--markdown]: the state document's JSON Schema (or the field table
// of docs/state.md), derived from its one description in render/state_schema.cpp. The build writes
// the schema into web/src/generated/ for the UI (web/CMakeLists.txt).
#include "app/command.h"
#include "core/atomic_file.h"
#include "render/state_schema.h"

#include <fmt/format.h>

namespace raypc::app {
namespace {

struct StateSchemaArgs {
    std::string output;
    bool markdown = false;
};

const CommandRegistration kStateSchemaCommand(
    "state-schema", "Write the JSON Schema of the state document (STATE.json), or its docs table",
    [](CLI::App& cmd) {
        auto args = std::make_shared<StateSchemaArgs>();
        cmd.add_option("-o,--output", args->output, "Output file (written atomically); default: standard output");
        cmd.add_flag("--markdown", args->markdown, "Write the field table of docs/state.md instead");
        cmd.callback([args] {
            const std::string text =
                args->markdown ? render::stateFieldTable() : render::stateJsonSchema().dump(2) + "\n";
            if (args->output.empty())
                fmt::print("{}", text);
            else
                writeFileAtomic(args->output, text);
        });
    },
    90);

}  // namespace
}  // namespace raypc::app
