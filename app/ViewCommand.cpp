// ViewCommand.cpp — `ambience view`. (Placeholder: registered so the CLI lists it.)
#include <CLI/CLI.hpp>

#include "app/Commands.h"
#include "world/Error.h"

namespace amb {

void addViewCommand(CLI::App& app) {
    auto* cmd = app.add_subcommand("view", "(not built yet)");
    cmd->callback([] { throw InputError("view", "this subcommand is not built yet"); });
}

}  // namespace amb
