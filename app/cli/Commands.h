// Commands.h — the `ambience` subcommands. Each registers itself on the root CLI11 app;
// its callback does the work and throws amb::InputError for bad input (exit code 2).
#pragma once

#include <string>

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
void addBenchCommand(CLI::App& app);   // replays x methods x parameter points: speed vs error
void addCompareCommand(CLI::App& app);  // one frame: method, reference and ambient error
void addSettingsCommand(CLI::App& app);  // the keys of the settings files
void addTuneCommand(CLI::App& app);      // a multi-objective Optuna study of the settings

// The folder of the shipped replays (beside the executable's tree, or ./replays); "" if none.
std::string shippedReplayDir();

}  // namespace amb
