// raypc state-schema and raypc protocol-schema [-o FILE] [--markdown]: the JSON Schema of the
// state document (STATE.json) or of the server protocol's other messages, or the docs tables
// derived with them (docs/state.md, docs/protocol.md), from their one descriptions in
// render/state_schema.cpp and server/protocol_schema.cpp. The build writes both schemas into
// web/src/generated/ for the UI (web/CMakeLists.txt).
#include "app/command.h"
#include "core/atomic_file.h"
#include "state/state_schema.h"
#include "server/protocol_schema.h"

#include <fmt/format.h>

namespace raypc::app {
namespace {

struct SchemaArgs {
    std::string output;
    bool markdown = false;
};

// A command that writes `schema()`, or with --markdown `tables()` (`tablesFor`: the doc they are in).
CommandSetup schemaCommand(nlohmann::json (*schema)(), std::string (*tables)(), std::string tablesFor)
{
    return [=](CLI::App& cmd) {
        auto args = std::make_shared<SchemaArgs>();
        cmd.add_option("-o,--output", args->output, "Output file (written atomically); default: standard output");
        cmd.add_flag("--markdown", args->markdown, fmt::format("Write the table(s) of {} instead", tablesFor));
        cmd.callback([args, schema, tables] {
            const std::string text = args->markdown ? tables() : schema().dump(2) + "\n";
            if (args->output.empty())
                fmt::print("{}", text);
            else
                writeFileAtomic(args->output, text);
        });
    };
}

const CommandRegistration kStateSchemaCommand(
    "state-schema", "Write the JSON Schema of the state document (STATE.json), or its docs table",
    schemaCommand(state::stateJsonSchema, state::stateFieldTable, "docs/state.md"), 90);

const CommandRegistration kProtocolSchemaCommand(
    "protocol-schema", "Write the JSON Schema of the server protocol's messages, or their docs tables",
    schemaCommand(server::protocolJsonSchema, server::protocolMessageTables, "docs/protocol.md"), 91);

}  // namespace
}  // namespace raypc::app
