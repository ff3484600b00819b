// ReplayCommand.cpp — `ambience replay`. (Placeholder: registered so the CLI lists it.)
#include <CLI/CLI.hpp>

#include "app/Commands.h"
#include "world/Error.h"

namespace amb {

void addReplayCommand(CLI::App& app) {
    auto* cmd = app.add_subcommand("replay", "(not built yet)");
    cmd->callback([] { throw InputError("replay", "this subcommand is not built yet"); });
}

}  // namespace amb
