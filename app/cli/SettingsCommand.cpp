// SettingsCommand.cpp — `ambience settings`: the keys of the settings files as the settings
// schema has them (lighting/SettingsSchema.h), and text generated from it.
//
//   ambience settings                      every key: its file, kind, default, range, unit, help
//   ambience settings --markdown           the key tables of docs/TUNING.md
//   ambience settings --json               every key as JSON, for scripts (ambience tune)
//   ambience settings --fuzz-dictionary    the settings part of tests/fuzz/json.dict
//   ambience settings --defaults FILE      a settings file (volume or baseline) of every key at
//                                          its default
//   ambience settings --worst-case FILE    the same with each costly key at its costly end
#include <cstdio>
#include <memory>
#include <string>

#include <CLI/CLI.hpp>
#include <nlohmann/json.hpp>

#include "app/cli/Commands.h"
#include "lighting/JsonFields.h"
#include "lighting/SettingsSchema.h"
#include "world/Error.h"

namespace amb {

namespace {

struct SettingsOptions {
    bool markdown = false;
    bool json = false;
    bool fuzzDictionary = false;
    std::string defaults, worstCase;  // "volume" or "baseline"
};

const char* kindName(SettingSpec::Kind kind) {
    switch (kind) {
        case SettingSpec::Kind::Number:
            return "number";
        case SettingSpec::Kind::Integer:
            return "integer";
        case SettingSpec::Kind::Boolean:
            return "switch";
    }
    return "";
}

template <typename S>
void listKeys(const char* title, const SettingsSchema<S>& schema) {
    std::printf("%s\n", title);
    const S defaults{};
    for (const auto& f : schema.fields()) {
        const double v = schema.value(defaults, f);
        std::string range;
        if (f.kind != SettingSpec::Kind::Boolean)
            range =
                jsonNumber(f.lo) + " to " + jsonNumber(f.hi) + (f.unit.empty() ? "" : " ") + f.unit;
        const std::string value =
            f.kind == SettingSpec::Kind::Boolean ? (v != 0.0 ? "true" : "false") : jsonNumber(v);
        std::printf("  %-34s %-8s %-8s %-26s %s%s\n", f.key.c_str(), kindName(f.kind),
                    value.c_str(), range.c_str(), f.help.c_str(), f.rebuilds ? " (rebuilds)" : "");
    }
}

const char* costName(SettingSpec::Cost cost) {
    switch (cost) {
        case SettingSpec::Cost::AtHigh:
            return "high";
        case SettingSpec::Cost::AtLow:
            return "low";
        case SettingSpec::Cost::None:
            break;
    }
    return "";
}

// One settings file's keys as JSON: for each, what the schema says and the default.
template <typename S>
nlohmann::json keysJson(const SettingsSchema<S>& schema) {
    nlohmann::json keys = nlohmann::json::array();
    const S defaults{};
    for (const auto& f : schema.fields()) {
        const double v = schema.value(defaults, f);
        nlohmann::json k = {{"key", f.key},
                            {"kind", kindName(f.kind)},
                            {"unit", f.unit},
                            {"help", f.help},
                            {"rebuilds", f.rebuilds},
                            {"logarithmic", f.logarithmic},
                            {"costlyEnd", costName(f.cost)}};
        if (f.kind == SettingSpec::Kind::Boolean) {
            k["default"] = v != 0.0;
        } else {
            k["min"] = f.lo;
            k["max"] = f.hi;
            if (f.kind == SettingSpec::Kind::Integer)
                k["default"] = static_cast<long long>(v);
            else
                k["default"] = v;
        }
        keys.push_back(std::move(k));
    }
    return keys;
}

// "volume" or "baseline": the file's text, from `volume` or `baseline` of the schema.
template <typename Volume, typename Baseline>
std::string fileText(const std::string& file, const char* option, Volume volume,
                     Baseline baseline) {
    if (file == "volume") return volume();
    if (file == "baseline") return baseline();
    throw InputError(option, "expected volume or baseline, got '" + file + "'");
}

void runSettings(const SettingsOptions& o) {
    const int outputs = int(o.markdown) + int(o.json) + int(o.fuzzDictionary) + int(!o.defaults.empty()) +
                        int(!o.worstCase.empty());
    if (outputs > 1)
        throw InputError("settings",
                         "one of --markdown, --json, --fuzz-dictionary, --defaults, --worst-case");
    const auto& volume = volumeSettingsSchema();
    const auto& baseline = baselineSettingsSchema();
    std::string text;
    if (o.markdown) {
        text = settingsMarkdown();
    } else if (o.json) {
        const nlohmann::json all = {{"volume", keysJson(volume)}, {"baseline", keysJson(baseline)}};
        text = all.dump(2) + "\n";
    } else if (o.fuzzDictionary) {
        text = settingsFuzzDictionary();
    } else if (!o.defaults.empty()) {
        text = fileText(
            o.defaults, "--defaults", [&] { return volume.write({}); },
            [&] { return baseline.write({}); });
    } else if (!o.worstCase.empty()) {
        text = fileText(
            o.worstCase, "--worst-case", [&] { return volume.write(volume.worstCase()); },
            [&] { return baseline.write(baseline.worstCase()); });
    } else {
        listKeys("The volume's settings file (run, view and compare --config; --set KEY=VALUE):",
                 volume);
        std::printf("\n");
        listKeys("The baselines' settings file (run --baseline-config; --set KEY=VALUE):",
                 baseline);
        return;
    }
    std::fwrite(text.data(), 1, text.size(), stdout);
}

}  // namespace

void addSettingsCommand(CLI::App& app) {
    auto* cmd = app.add_subcommand(
        "settings", "the keys of the settings files: kind, default, range, unit, what they do");
    auto o = std::make_shared<SettingsOptions>();
    cmd->add_flag("--markdown", o->markdown,
                  "print the key tables of docs/TUNING.md (Markdown) instead");
    cmd->add_flag("--json", o->json,
                  "print every key as JSON: {\"volume\": [...], \"baseline\": [...]}, each with "
                  "key, kind, unit, min, max, default, logarithmic, help, rebuilds, costlyEnd");
    cmd->add_flag("--fuzz-dictionary", o->fuzzDictionary,
                  "print the settings names of the fuzz dictionary (tests/fuzz/json.dict)");
    cmd->add_option("--defaults", o->defaults,
                    "print a settings file of every key at its default: volume or baseline");
    cmd->add_option("--worst-case", o->worstCase,
                    "print a settings file with each costly key at its costly end: volume or "
                    "baseline");
    cmd->callback([o] { runSettings(*o); });
}

}  // namespace amb
