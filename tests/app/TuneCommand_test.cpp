// TuneCommand_test.cpp — `ambience tune` (app/cli/TuneCommand.cpp, scripts/ambience-tune.py):
// a bad option is one line naming it, exit code 2; a tiny study (real runs of a few frames with
// the self-oracle) writes its front as settings files that `ambience run --config` reads, its
// CSV files, plots and summary; the same command again adds trials to the same study, and one
// that would change what the study measures is refused naming the option.
#include <unistd.h>

#include <algorithm>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <set>
#include <string>
#include <vector>

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include "RunAmbience.h"
#include "lighting/SettingsSchema.h"

namespace amb {
namespace {

namespace fs = std::filesystem;
using test::runAmbience;

void expectBadOption(const std::string& args, const std::string& option) {
    const test::CommandResult r = runAmbience("tune " + args);
    EXPECT_EQ(r.exitCode, 2) << args << "\nstderr: " << r.err;
    EXPECT_EQ(r.errLines(), 1) << args << "\nstderr: " << r.err;
    EXPECT_EQ(r.err.rfind("ambience: error: " + option + ":", 0), 0u)
        << args << "\nstderr: " << r.err;
    EXPECT_TRUE(r.out.empty()) << args << "\nstdout: " << r.out;
}

TEST(TuneCommand, BadOptionsAreOneLineNamingTheOption) {
    const fs::path dir = test::scratchDir("tune-bad");
    const std::string out = " --out " + (dir / "t").string();
    expectBadOption("--params nearField.radius" + out, "--params");
    expectBadOption("--params scheduler.horizon_s=4:2" + out, "--params");
    expectBadOption("--params scheduler.horizon_s=0:11" + out, "--params");
    expectBadOption("--params scheduler.horizon_s=a:b" + out, "--params");
    expectBadOption("--params store.reachCells=1:2.5" + out, "--params");
    expectBadOption("--params store.smoothInterpolation=0:1" + out, "--params");
    expectBadOption("--params facesPerFrame" + out, "--params");
    expectBadOption("--params scheduler.horizon_s,scheduler.horizon_s" + out, "--params");
    expectBadOption("--params ," + out, "--params");
    expectBadOption("--replays dusk-mountain-held-out" + out, "--replays");
    expectBadOption("--replays highway-drive,hairpin-flight-held-out" + out, "--replays");
    expectBadOption("--replays no-such-replay" + out, "--replays");
    expectBadOption("--eval-replays highway-drive" + out, "--eval-replays");
    expectBadOption("--oracle best" + out, "--oracle");
    expectBadOption("--sampler random" + out, "--sampler");
    expectBadOption("--trials -1" + out, "--trials");
    expectBadOption("--jobs 0" + out, "--jobs");
    expectBadOption("--max-frames 0" + out, "--max-frames");
    expectBadOption("--eval-max-frames 0" + out, "--eval-max-frames");
    expectBadOption("--study 'a b'" + out, "--study");
    expectBadOption("--backend glfw" + out, "--backend");
    expectBadOption("--out ''", "--out");
    expectBadOption("--replays ''" + out, "--replays");
    // Not an option of tune at all: CLI11's line, exit code 2.
    const auto r = runAmbience("tune --tune-rounds 2" + out);
    EXPECT_EQ(r.exitCode, 2) << r.err;
    EXPECT_EQ(r.errLines(), 1) << r.err;
    EXPECT_NE(r.err.find("--tune-rounds"), std::string::npos) << r.err;
}

// The coordinate descent `bench --tune` gave way to the study (docs/TUNING.md "Optuna against
// the coordinate descent"): whoever still types it is sent to `ambience tune`, before any work.
TEST(TuneCommand, BenchTuneIsGoneAndSaysWhere) {
    const fs::path dir = fs::temp_directory_path() / "ambience-bench-tune-gone";
    fs::remove_all(dir);
    const auto r = runAmbience("bench --tune --out " + dir.string());
    EXPECT_EQ(r.exitCode, 2) << r.err;
    EXPECT_EQ(r.errLines(), 1) << r.err;
    EXPECT_NE(r.err.find("ambience tune"), std::string::npos) << r.err;
    EXPECT_FALSE(fs::exists(dir)) << "refused after making its folder";
    for (const char* gone : {"--tune-rounds 2", "--tune-budget 1", "--tune-replays highway-drive",
                             "--tune-min-gain 0.01"}) {
        const auto o = runAmbience(std::string("bench ") + gone + " --out " + dir.string());
        EXPECT_EQ(o.exitCode, 2) << gone << ": " << o.err;
    }
}

int csvRows(const fs::path& file) {
    std::ifstream in(file);
    std::string line;
    int rows = -1;  // the header
    while (std::getline(in, line))
        if (!line.empty()) ++rows;
    return rows;
}

std::vector<fs::path> frontFiles(const fs::path& out) {
    std::vector<fs::path> files;
    for (const auto& e : fs::directory_iterator(out / "front")) files.push_back(e.path());
    std::sort(files.begin(), files.end());
    return files;
}

TEST(TuneCommand, TinyStudyWritesItsFrontAndResumes) {
    if (::access("/usr/bin/python3", X_OK) != 0 ||
        test::runCommand({"/usr/bin/python3", "-c", "import optuna, matplotlib"}).exitCode != 0)
        GTEST_SKIP() << "python3-optuna or python3-matplotlib missing";
    const fs::path dir = test::scratchDir("tune-study");
    const fs::path out = dir / "study";
    // Two keys, a few frames of one replay, the quick self-oracle; the held-out replay of the
    // evaluation at the same few frames.
    const std::string study =
        "tune --params scheduler.horizon_s=1:6,store.reachCells --replays highway-drive "
        "--eval-replays hairpin-flight-held-out --oracle self --max-frames 20 --seed 3 --out " +
        out.string();
    const auto first = runAmbience(study + " --trials 2");
    ASSERT_EQ(first.exitCode, 0) << first.err;
    // The defaults are a trial of the study, and two were added.
    EXPECT_EQ(csvRows(out / "trials.csv"), 3);
    for (const char* f : {"front.csv", "front.png", "summary.md", "eval.csv", "study.db"})
        EXPECT_TRUE(fs::is_regular_file(out / f)) << f;
    const auto files = frontFiles(out);
    ASSERT_FALSE(files.empty());
    EXPECT_EQ(int(files.size()), csvRows(out / "front.csv"));
    // The defaults and each front point, measured again on the held-out replay.
    EXPECT_EQ(csvRows(out / "eval.csv"), int(files.size()) + 1);
    for (std::size_t i = 0; i < files.size(); ++i) {
        EXPECT_EQ(files[i].filename().string(),
                  (i < 10 ? "0" : "") + std::to_string(i) + ".json");
        // Only the tuned keys, within their ranges, as the settings reader takes them.
        const auto j = nlohmann::json::parse(test::slurp(files[i].string()));
        const double horizon = j.at("scheduler").at("horizon_s").get<double>();
        EXPECT_GE(horizon, 1.0);
        EXPECT_LE(horizon, 6.0);
        EXPECT_TRUE(j.at("store").at("reachCells").is_number_integer());
        volumeSettingsSchema().read(test::slurp(files[i].string()), files[i].string());
    }
    // `ambience run --config` reads a front file (the first and the last).
    for (const fs::path& f : {files.front(), files.back()}) {
        const auto run = runAmbience("run --replay " + test::sourcePath("replays/low-flight.json") +
                                     " --config " + f.string() +
                                     " --max-frames 2 --no-frames --out " +
                                     (dir / ("run-" + f.stem().string())).string());
        EXPECT_EQ(run.exitCode, 0) << f << "\n" << run.err;
    }
    const std::string summary = test::slurp((out / "summary.md").string());
    EXPECT_NE(summary.find("## Pareto front"), std::string::npos);
    EXPECT_NE(summary.find("hairpin-flight-held-out"), std::string::npos);

    // The same command again resumes the study: one more trial, the same storage.
    const auto again = runAmbience(study + " --trials 1");
    ASSERT_EQ(again.exitCode, 0) << again.err;
    EXPECT_EQ(csvRows(out / "trials.csv"), 4);
    std::set<std::string> numbers;
    std::ifstream trials(out / "trials.csv");
    std::string line;
    std::getline(trials, line);
    while (std::getline(trials, line)) numbers.insert(line.substr(0, line.find(',')));
    EXPECT_EQ(numbers, (std::set<std::string>{"0", "1", "2", "3"}));
    // What the study measures stays: other frames are refused, naming the option.
    const auto other = runAmbience(
        "tune --params scheduler.horizon_s=1:6,store.reachCells --replays highway-drive "
        "--eval-replays hairpin-flight-held-out --oracle self --max-frames 30 --trials 1 --out " +
        out.string());
    EXPECT_EQ(other.exitCode, 2) << other.err;
    EXPECT_EQ(other.errLines(), 1) << other.err;
    EXPECT_EQ(other.err.rfind("ambience: error: --max-frames:", 0), 0u) << other.err;
    EXPECT_EQ(csvRows(out / "trials.csv"), 4);
    fs::remove_all(dir);
}

}  // namespace
}  // namespace amb
