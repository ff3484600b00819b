// ProbeCommand.cpp — `ambience probe`. (Placeholder: registered so the CLI lists it.)
#include <CLI/CLI.hpp>

#include "app/Commands.h"
#include "world/Error.h"

namespace amb {

void addProbeCommand(CLI::App& app) {
    auto* cmd = app.add_subcommand("probe", "(not built yet)");
    cmd->callback([] { throw InputError("probe", "this subcommand is not built yet"); });
}

}  // namespace amb
