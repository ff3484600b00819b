// Commands.h — the `ambience` subcommands. Each registers itself on the root CLI11 app;
// its callback does the work and throws amb::InputError for bad input (exit code 2).
#pragma once

namespace CLI {
class App;
}

namespace amb {

void addWorldCommand(CLI::App& app);   // world map and heightmap
void addReplayCommand(CLI::App& app);  // replay info | make
void addRunCommand(CLI::App& app);     // render a replay to frames, video and report
void addViewCommand(CLI::App& app);    // interactive window
void addProbeCommand(CLI::App& app);   // capture one cube map
void addShCommand(CLI::App& app);      // SH tools: project

}  // namespace amb
