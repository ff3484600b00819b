// SettingsFlags.cpp — `--set KEY=VALUE` of run, compare and view (see SettingsFlags.h).
#include "app/cli/SettingsFlags.h"

#include <CLI/CLI.hpp>

#include "lighting/SettingsSchema.h"
#include "world/Error.h"

namespace amb {

void addSetOption(CLI::App& cmd, std::vector<std::string>& assignments) {
    cmd.add_option("--set", assignments,
                   "set one key of the settings files after --config, KEY=VALUE as the file "
                   "holds it (store.blendTime_s=2, nearField.enabled=false); repeatable; "
                   "`ambience settings` lists the keys and their ranges")
        ->take_all()
        ->allow_extra_args(false);
}

void applySettingAssignments(const std::vector<std::string>& assignments,
                             AmbienceVolumeSettings& volume, BaselineSettings* baselines) {
    const char* where = "--set";
    for (const std::string& a : assignments) {
        bool known = volumeSettingsSchema().assignIfKnown(volume, a, where);
        BaselineSettings scratch;
        known |= baselineSettingsSchema().assignIfKnown(baselines ? *baselines : scratch, a, where);
        if (!known) {
            throw InputError(where, "unknown setting '" + assignmentKey(a) +
                                        "' (`ambience settings` lists them)");
        }
        if (!baselines && !volumeSettingsSchema().find(assignmentKey(a))) {
            throw InputError(where, "'" + assignmentKey(a) +
                                        "' is a key of the baselines' settings file; this command "
                                        "runs the volume's settings");
        }
    }
    volumeSettingsSchema().check(volume, where);
    if (baselines) baselineSettingsSchema().check(*baselines, where);
}

}  // namespace amb
