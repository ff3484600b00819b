// ShCommand.cpp — `ambience sh`. (Placeholder: registered so the CLI lists it.)
#include <CLI/CLI.hpp>

#include "app/Commands.h"
#include "world/Error.h"

namespace amb {

void addShCommand(CLI::App& app) {
    auto* cmd = app.add_subcommand("sh", "(not built yet)");
    cmd->callback([] { throw InputError("sh", "this subcommand is not built yet"); });
}

}  // namespace amb
