// RunCommand.cpp — `ambience run`. (Placeholder: registered so the CLI lists it.)
#include <CLI/CLI.hpp>

#include "app/Commands.h"
#include "world/Error.h"

namespace amb {

void addRunCommand(CLI::App& app) {
    auto* cmd = app.add_subcommand("run", "(not built yet)");
    cmd->callback([] { throw InputError("run", "this subcommand is not built yet"); });
}

}  // namespace amb
