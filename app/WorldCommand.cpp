// WorldCommand.cpp — `ambience world`. (Placeholder: registered so the CLI lists it.)
#include <CLI/CLI.hpp>

#include "app/Commands.h"
#include "world/Error.h"

namespace amb {

void addWorldCommand(CLI::App& app) {
    auto* cmd = app.add_subcommand("world", "(not built yet)");
    cmd->callback([] { throw InputError("world", "this subcommand is not built yet"); });
}

}  // namespace amb
