// SettingsCommand_test.cpp — settings on the command line: `ambience settings` prints what the
// settings schema says (lighting/SettingsSchema.h); run and compare keep a settings file's
// capture budget unless --faces-per-frame is given; `--set KEY=VALUE` of run, compare and view
// applies after --config through the readers' checks, and a bad key or value is one line naming
// it, exit code 2.
#include <filesystem>
#include <fstream>
#include <string>

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include "GlTestContext.h"
#include "RunAmbience.h"
#include "lighting/JsonFields.h"
#include "lighting/SettingsSchema.h"

namespace amb {
namespace {

namespace fs = std::filesystem;
using test::runAmbience;

const std::string kReplay = std::string(AMBIENCE_SOURCE_DIR) + "/replays/highway-drive.json";

void expectInputError(const std::string& args, const std::string& line) {
    const test::CommandResult r = runAmbience(args);
    EXPECT_EQ(r.exitCode, 2) << args << "\nstderr: " << r.err;
    EXPECT_EQ(r.errLines(), 1) << args << "\nstderr: " << r.err;
    EXPECT_EQ(r.err, "ambience: error: " + line + "\n") << args;
}

TEST(SettingsCommand, PrintsWhatTheSchemaSays) {
    const auto md = runAmbience("settings --markdown");
    ASSERT_EQ(md.exitCode, 0) << md.err;
    EXPECT_EQ(md.out, settingsMarkdown());
    const auto dict = runAmbience("settings --fuzz-dictionary");
    ASSERT_EQ(dict.exitCode, 0) << dict.err;
    EXPECT_EQ(dict.out, settingsFuzzDictionary());
    // Every key is listed.
    const auto list = runAmbience("settings");
    ASSERT_EQ(list.exitCode, 0) << list.err;
    for (const auto& f : volumeSettingsSchema().fields())
        EXPECT_NE(list.out.find("  " + f.key + " "), std::string::npos) << f.key;
    for (const auto& f : baselineSettingsSchema().fields())
        EXPECT_NE(list.out.find("  " + f.key + " "), std::string::npos) << f.key;
    // The settings files it writes are what the readers take.
    for (const char* file : {"volume", "baseline"}) {
        for (const char* what : {"--defaults", "--worst-case"}) {
            const auto r = runAmbience(std::string("settings ") + what + " " + file);
            ASSERT_EQ(r.exitCode, 0) << r.err;
            if (std::string(file) == "volume") {
                const AmbienceVolumeSettings s = volumeSettingsSchema().read(r.out, what);
                EXPECT_EQ(volumeSettingsSchema().equal(s, volumeSettingsSchema().worstCase()),
                          std::string(what) == "--worst-case");
            } else {
                const BaselineSettings s = baselineSettingsSchema().read(r.out, what);
                EXPECT_EQ(baselineSettingsSchema().equal(s, baselineSettingsSchema().worstCase()),
                          std::string(what) == "--worst-case");
            }
        }
    }
    expectInputError("settings --defaults lamp",
                     "--defaults: expected volume or baseline, got 'lamp'");
    expectInputError("settings --markdown --fuzz-dictionary",
                     "settings: one of --markdown, --json, --fuzz-dictionary, --defaults, "
                     "--worst-case");
}

// `settings --json` (what `ambience tune` takes its ranges from) lists every key of both files
// in the schema's order, with the schema's kind, unit, range, default, help and flags.
template <typename S>
void expectJsonAgrees(const nlohmann::json& keys, const SettingsSchema<S>& schema) {
    const auto& fields = schema.fields();
    ASSERT_TRUE(keys.is_array());
    ASSERT_EQ(keys.size(), fields.size());
    const S defaults{};
    for (std::size_t i = 0; i < fields.size(); ++i) {
        const auto& f = fields[i];
        const nlohmann::json& k = keys[i];
        EXPECT_EQ(k.at("key"), f.key);
        EXPECT_EQ(k.at("unit"), f.unit) << f.key;
        EXPECT_EQ(k.at("help"), f.help) << f.key;
        EXPECT_EQ(k.at("rebuilds"), f.rebuilds) << f.key;
        EXPECT_EQ(k.at("logarithmic"), f.logarithmic) << f.key;
        EXPECT_EQ(k.at("costlyEnd"), f.cost == SettingSpec::Cost::AtHigh  ? "high"
                                     : f.cost == SettingSpec::Cost::AtLow ? "low"
                                                                          : "")
            << f.key;
        const double v = schema.value(defaults, f);
        if (f.kind == SettingSpec::Kind::Boolean) {
            EXPECT_EQ(k.at("kind"), "switch") << f.key;
            EXPECT_EQ(k.at("default"), v != 0.0) << f.key;
            EXPECT_FALSE(k.contains("min")) << f.key;
        } else {
            EXPECT_EQ(k.at("kind"), f.kind == SettingSpec::Kind::Integer ? "integer" : "number")
                << f.key;
            // Exact: the JSON carries the doubles at full precision.
            EXPECT_EQ(k.at("min").get<double>(), f.lo) << f.key;
            EXPECT_EQ(k.at("max").get<double>(), f.hi) << f.key;
            EXPECT_EQ(k.at("default").get<double>(), v) << f.key;
            if (f.kind == SettingSpec::Kind::Integer) {
                EXPECT_TRUE(k.at("default").is_number_integer()) << f.key;
            }
        }
    }
}

TEST(SettingsCommand, JsonListsEveryKeyAsTheSchemaHasIt) {
    const auto r = runAmbience("settings --json");
    ASSERT_EQ(r.exitCode, 0) << r.err;
    const nlohmann::json all = nlohmann::json::parse(r.out);
    ASSERT_TRUE(all.is_object());
    EXPECT_EQ(all.size(), 2u);
    expectJsonAgrees(all.at("volume"), volumeSettingsSchema());
    expectJsonAgrees(all.at("baseline"), baselineSettingsSchema());
    expectInputError("settings --json --markdown",
                     "settings: one of --markdown, --json, --fuzz-dictionary, --defaults, "
                     "--worst-case");
}

TEST(SettingsCommand, BadSetsAreOneLineNamingTheKey) {
    const fs::path dir = test::scratchDir("settings-set");
    const std::string run = "run --replay " + kReplay + " --max-frames 1 --no-frames --out " +
                            (dir / "run").string() + " ";
    expectInputError(run + "--set store.levels=9", "--set: 'store.levels' must be in [1, 8]");
    expectInputError(run + "--set store.levels=3 --set nearField.radius=3",
                     "--set: unknown setting 'nearField.radius' (`ambience settings` lists them)");
    expectInputError(run + "--set nearField.enabled=yes",
                     "--set: 'nearField.enabled' must be true or false");
    expectInputError(run + "--set gridSize=1", "--set: 'gridSize' must be in [2, 256]");
    expectInputError(run + "--set store.maxLifetime_s=1",
                     "--set: 'store': minLifetime_s exceeds maxLifetime_s");
    expectInputError(run + "--set facesPerFrame", "--set: expected KEY=VALUE, got 'facesPerFrame'");
    // After --config: its keys are checked together with the file's.
    const fs::path config = dir / "lifetimes.json";
    std::ofstream(config) << R"({"store": {"minLifetime_s": 100}})";
    expectInputError(run + "--config " + config.string() + " --set store.maxLifetime_s=50",
                     "--set: 'store': minLifetime_s exceeds maxLifetime_s");
    expectInputError("compare --replay " + kReplay + " --out " + (dir / "compare").string() +
                         " --set scheduler.maxWiden=-1",
                     "--set: 'scheduler.maxWiden' must be in [0, " +
                         jsonNumber(volumeSettingsSchema().find("scheduler.maxWiden")->hi) + "]");
    // view checks before it opens a window (so no display is needed here); it runs the
    // volume's settings alone.
    expectInputError("view --frames 1 --set store.blendTime_s=-1",
                     "--set: 'store.blendTime_s' must be in [0, 3600]");
    expectInputError("view --frames 1 --set gridSize=8",
                     "--set: 'gridSize' is a key of the baselines' settings file; this command "
                     "runs the volume's settings");
}

// The faces the volume captured in a short run within its budget (the first frame's prime,
// lighting/CaptureCore.h, left out).
int facesCaptured(const fs::path& dir, const std::string& args) {
    const auto r = runAmbience("run --replay " + kReplay + " --max-frames 6 --no-frames --out " +
                               dir.string() + " " + args);
    EXPECT_EQ(r.exitCode, 0) << args << "\n" << r.err;
    std::ifstream in(dir / "report.json");
    if (!in) return -1;
    const nlohmann::json a = nlohmann::json::parse(in)["ambience"];
    return a["facesCaptured"].get<int>() - a["primeFaces"].get<int>();
}

// A settings file's budget (the tuning panel's Save writes one) is the run's unless the command
// line names another: --faces-per-frame, then --set, override it only when given.
TEST(SettingsCommand, TheCommandLineOverridesTheFileOnlyWhereGiven) {
    AMB_REQUIRE_PLATFORM(platform, Backend::Auto, 16, 16);
    platform.reset();
    const fs::path dir = test::scratchDir("settings-budget");
    const fs::path config = dir / "three.json";
    std::ofstream(config) << R"({"facesPerFrame": 3})";
    EXPECT_EQ(facesCaptured(dir / "a", ""), 6);
    EXPECT_EQ(facesCaptured(dir / "b", "--config " + config.string()), 18);
    EXPECT_EQ(facesCaptured(dir / "c", "--config " + config.string() + " --faces-per-frame 2"), 12);
    EXPECT_EQ(facesCaptured(dir / "d", "--config " + config.string() + " --set facesPerFrame=4"),
              24);
    EXPECT_EQ(facesCaptured(dir / "e", "--faces-per-frame 2 --set facesPerFrame=5"), 30);
}

}  // namespace
}  // namespace amb
