// SettingsFlags.h — the settings on the command line of run, compare and view: `--set KEY=VALUE`
// (repeatable), a key of the settings files (lighting/SettingsSchema.h, `ambience settings`
// lists them) with a value as the file would hold it. The assignments apply after `--config`
// and after the flags that set a key (`--faces-per-frame`), in the order given, and go through
// the readers' checks: a bad key or value is one InputError("--set", ...) naming the key.
#pragma once

#include <string>
#include <vector>

namespace CLI {
class App;
}

namespace amb {

struct AmbienceVolumeSettings;
struct BaselineSettings;

// Adds `--set KEY=VALUE` to `cmd`, collected in `assignments` (which must outlive the parse).
void addSetOption(CLI::App& cmd, std::vector<std::string>& assignments);

// Applies `assignments`: a key of the volume's file to `volume`, a key of the baselines' file to
// `baselines` (the capture and near-field keys, in both files, to both); then the checks that
// bind keys together. `baselines` null: the command runs the volume's settings alone, and a
// baselines' key is an error.
void applySettingAssignments(const std::vector<std::string>& assignments,
                             AmbienceVolumeSettings& volume, BaselineSettings* baselines);

}  // namespace amb
