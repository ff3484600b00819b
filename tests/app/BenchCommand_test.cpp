// BenchCommand_test.cpp — `ambience run --measure-every` and `ambience bench` end to end on
// short runs: results, summary, oracle reuse, a failing run recorded while the sweep goes on,
// bad input; a sweep emitted, run by GNU parallel and collected against the same sweep run
// here; progress lines in a log.
#include <sys/wait.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <set>
#include <sstream>
#include <vector>

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include "RunAmbience.h"
#include "app/bench/BenchEmit.h"

namespace amb::test {
namespace {

namespace fs = std::filesystem;

std::vector<std::vector<std::string>> readCsv(const std::string& path) {
    // Plain CSV with one quoted field at most per row in these tests (error messages).
    std::vector<std::vector<std::string>> rows;
    std::ifstream in(path);
    std::string line;
    while (std::getline(in, line)) {
        std::vector<std::string> row;
        std::string field;
        bool quoted = false;
        for (std::size_t i = 0; i < line.size(); ++i) {
            const char c = line[i];
            if (c == '"') {
                if (quoted && i + 1 < line.size() && line[i + 1] == '"') {
                    field += '"';
                    ++i;
                } else {
                    quoted = !quoted;
                }
            } else if (c == ',' && !quoted) {
                row.push_back(field);
                field.clear();
            } else {
                field += c;
            }
        }
        row.push_back(field);
        rows.push_back(row);
    }
    return rows;
}

std::size_t column(const std::vector<std::string>& header, const std::string& name) {
    for (std::size_t i = 0; i < header.size(); ++i)
        if (header[i] == name) return i;
    ADD_FAILURE() << "no column " << name;
    return 0;
}

nlohmann::json readJson(const fs::path& path) {
    std::ifstream in(path);
    return nlohmann::json::parse(in);
}

// A measured run writes the error block and the per-frame CSV; a second run of the same replay
// reads the saved oracle (no captures) and, the simulation being deterministic, measures the
// very same errors.
TEST(RunMeasure, OracleIsSavedReusedAndTheResultDeterministic) {
    const fs::path dir = scratchDir("run-measure");
    const std::string common = "run --no-frames --max-frames 61 --measure-every 20 --oracle " +
                               (dir / "oracle.json").string();
    const auto a = runAmbience(common + " --out " + (dir / "a").string());
    ASSERT_EQ(a.exitCode, 0) << a.err;
    const auto b = runAmbience(common + " --out " + (dir / "b").string());
    ASSERT_EQ(b.exitCode, 0) << b.err;
    const auto ja = readJson(dir / "a" / "report.json")["measurement"];
    const auto jb = readJson(dir / "b" / "report.json")["measurement"];
    EXPECT_EQ(ja["measuredFrames"], 4);  // frames 0, 20, 40, 60
    EXPECT_GT(ja["oracleCaptures"].get<int>(), 0);
    EXPECT_EQ(jb["oracleCaptures"], 0);
    EXPECT_EQ(ja["error"], jb["error"]);
    EXPECT_EQ(ja["pop"], jb["pop"]);
    const double mean = ja["error"]["mean"].get<double>();
    EXPECT_TRUE(std::isfinite(mean) && mean >= 0.0 && mean < 5.0) << mean;
    EXPECT_EQ(lineCount(slurp((dir / "a" / "measure.csv").string())), 1 + 4);
    // The oracle is refused for another measurement schedule (one line, exit code 2).
    const auto c = runAmbience("run --no-frames --max-frames 61 --measure-every 10 --oracle " +
                               (dir / "oracle.json").string() + " --out " + (dir / "c").string());
    EXPECT_EQ(c.exitCode, 2);
    EXPECT_EQ(c.errLines(), 1) << c.err;
}

// A cache is keyed by what made it: the replay file's bytes (its world and path, not only its
// name) and the hash of the sources that capture and project (cmake/SourceHash.cmake). A replay
// changed under the same name no longer reads the old oracle back as its own.
TEST(RunMeasure, OracleCacheIsKeyedByTheReplaysBytesAndTheCode) {
    const fs::path dir = scratchDir("run-oracle-key");
    fs::copy_file(sourcePath("replays/highway-drive.json"), dir / "r.json");
    const std::string common = "run --no-frames --max-frames 21 --measure-every 20 --replay " +
                               (dir / "r.json").string() + " --oracle " +
                               (dir / "oracle.json").string();
    const auto a = runAmbience(common + " --out " + (dir / "a").string());
    ASSERT_EQ(a.exitCode, 0) << a.err;
    const std::string signature = readJson(dir / "oracle.json")["signature"].get<std::string>();
    const auto code = signature.find(" code=");
    ASSERT_NE(code, std::string::npos) << signature;
    EXPECT_EQ(signature.substr(code + 6, 16).find_first_not_of("0123456789abcdef"),
              std::string::npos)
        << signature;
    EXPECT_NE(signature.find(" replay="), std::string::npos) << signature;
    // The same file name, one more space in it: another replay as far as the cache knows.
    std::ofstream(dir / "r.json", std::ios::app) << " ";
    const auto b = runAmbience(common + " --out " + (dir / "b").string());
    EXPECT_EQ(b.exitCode, 2) << b.err;
    EXPECT_NE(b.err.find("replay="), std::string::npos) << b.err;
    // Asked to, the run captures it anew and replaces the cache (as each bench run does).
    const auto c = runAmbience(common + " --replace-stale-caches --out " + (dir / "c").string());
    ASSERT_EQ(c.exitCode, 0) << c.err;
    EXPECT_GT(readJson(dir / "c" / "report.json")["measurement"]["oracleCaptures"].get<int>(), 0);
    EXPECT_NE(readJson(dir / "oracle.json")["signature"].get<std::string>(), signature);
}

// With the reference, every terrain witness is also graded as the screen shows it: the drawn
// patch's corners at their normals against the reference at the surface and its normal. Each
// ring witness gets a finite error unless the ground it stands on is hidden (a bush, a rock,
// a trunk); those under crowns are counted apart; reference.csv carries the per-witness value.
TEST(RunMeasure, ReferenceGradesTheDrawnNormal) {
    const fs::path dir = scratchDir("run-drawn");
    const auto r = runAmbience(
        "run --no-frames --max-frames 21 --measure-every 10 --oracle-kind reference "
        "--reference-every 1 --no-ideal-volume --reference-light hemisphere --out " +
        (dir / "a").string());
    ASSERT_EQ(r.exitCode, 0) << r.err;
    const auto ref = readJson(dir / "a" / "report.json")["measurement"]["reference"];
    const auto drawn = ref["drawn"];
    const int graded = drawn["error"]["count"].get<int>();
    const int hidden = drawn["hidden"].get<int>();
    EXPECT_GT(graded, 0);
    EXPECT_LE(drawn["underCrown"]["count"].get<int>(), graded);
    EXPECT_EQ(drawn["open"]["count"].get<int>() + drawn["underCrown"]["count"].get<int>(), graded);
    const double mean = drawn["error"]["mean"].get<double>();
    EXPECT_TRUE(std::isfinite(mean) && mean > 0.0 && mean < 5.0) << mean;
    // reference.csv: one row per witness; the terrain rows' drawn column filled unless hidden.
    const auto split = [](const std::string& text) {
        std::vector<std::string> fields;
        std::stringstream in(text);
        std::string f;
        while (std::getline(in, f, ',')) fields.push_back(f);
        if (!text.empty() && text.back() == ',') fields.push_back("");
        return fields;
    };
    std::ifstream csv(dir / "a" / "reference.csv");
    std::string line;
    std::getline(csv, line);
    const std::vector<std::string> header = split(line);
    const auto column = [&](const char* name) {
        const auto it = std::find(header.begin(), header.end(), name);
        EXPECT_NE(it, header.end()) << name;
        return std::size_t(it - header.begin());
    };
    const std::size_t drawnAt = column("drawn"), coverAt = column("cover"),
                      placedAt = column("placed"), freshAt = column("drawn_fresh_far");
    int terrain = 0, filled = 0, hiddenRows = 0, aside = 0, lifted = 0;
    while (std::getline(csv, line)) {
        if (line.find(",ring_") == std::string::npos) continue;
        ++terrain;
        const std::vector<std::string> f = split(line);
        ASSERT_EQ(f.size(), header.size()) << line;
        const std::string& placed = f[placedAt];
        EXPECT_TRUE(placed == "point" || placed == "aside" || placed == "lifted") << line;
        aside += placed == "aside", lifted += placed == "lifted";
        const std::string& cover = f[coverAt];
        const std::string& value = f[drawnAt];
        EXPECT_TRUE(f[freshAt].empty()) << line;  // --no-ideal-volume: no fresh captures
        if (cover == "hidden") {
            ++hiddenRows;
            EXPECT_TRUE(value.empty()) << line;
        } else {
            EXPECT_TRUE(cover == "open" || cover == "crown") << line;
            filled += !value.empty();
        }
    }
    EXPECT_EQ(filled, graded);
    EXPECT_EQ(hiddenRows, hidden);
    EXPECT_EQ(terrain, graded + hidden);  // every terrain witness has a drawn patch
    EXPECT_EQ(drawn["movedAside"].get<int>(), aside);
    EXPECT_EQ(drawn["lifted"].get<int>(), lifted);
    EXPECT_EQ(drawn["terrainWitnesses"].get<int>(), terrain);
    EXPECT_EQ(ref["light"], "hemisphere");
    EXPECT_FALSE(ref.contains("bounce"));
}

// With the ideal volume the drawn-normal error comes with its budget: every graded witness
// gets the fresh-capture steps, the terms add up to the drawn mean, the truncation is a small
// non-negative part, and reference.csv carries the steps per witness.
TEST(RunMeasure, DrawnBudgetClosesOnTheWorld) {
    const fs::path dir = scratchDir("run-drawn-budget");
    const auto r = runAmbience(
        "run --no-frames --max-frames 21 --measure-every 10 --oracle-kind reference "
        "--reference-every 1 --reference-trees 0 --reference-size 16 "
        "--reference-light hemisphere --out " +
        (dir / "a").string());
    ASSERT_EQ(r.exitCode, 0) << r.err;
    EXPECT_NE(r.out.find("error at the drawn normal (mean over"), std::string::npos) << r.out;
    const auto drawn = readJson(dir / "a" / "report.json")["measurement"]["reference"]["drawn"];
    const auto b = drawn["budget"];
    ASSERT_GT(b["count"].get<int>(), 0);
    EXPECT_EQ(b["count"].get<int>(), drawn["error"]["count"].get<int>());
    EXPECT_NEAR(b["drawn"].get<double>(), drawn["error"]["mean"].get<double>(), 1e-9);
    const double sum = b["farField"].get<double>() + b["patch"].get<double>() +
                       b["model"].get<double>() + b["truncation"].get<double>();
    EXPECT_NEAR(sum, b["drawn"].get<double>(), 1e-9);
    EXPECT_NEAR(b["closure"].get<double>(), 1.0, 1e-9);
    EXPECT_GE(b["truncation"].get<double>(), 0.0);
    EXPECT_LT(b["truncation"].get<double>(), b["drawn"].get<double>());
    EXPECT_EQ(drawn["budgetOpen"]["count"].get<int>() + drawn["budgetUnderCrown"]["count"].get<int>(),
              b["count"].get<int>());
    std::ifstream csv(dir / "a" / "reference.csv");
    std::string header;
    std::getline(csv, header);
    EXPECT_NE(header.find(",drawn_fresh_far,drawn_at_point,drawn_truncation,drawn_per_point"),
              std::string::npos);
    // The method at the point, beside the chain: a finite error of its own.
    const double perPoint = b["perPoint"].get<double>();
    EXPECT_TRUE(std::isfinite(perPoint) && perPoint >= 0.0 && perPoint < 5.0) << perPoint;
}

// The reference lit by its own bounce field (the default): the report names the light and how
// the field converged, and the reference cache's key names it, so a cache lit by the bounce
// field is refused for a hemisphere run (and made again with --replace-stale-caches).
TEST(RunMeasure, ReferenceLightIsReportedAndKeysTheCache) {
    const fs::path dir = scratchDir("run-light");
    const std::string base =
        "run --no-frames --max-frames 11 --measure-every 10 --oracle-kind reference "
        "--reference-every 1 --no-ideal-volume --reference-trees 0 --reference-size 16 "
        "--bounce-spacing 256 --bounce-reach 100 --bounce-face 8 --reference " +
        (dir / "ref.json").string();
    const auto r = runAmbience(base + " --out " + (dir / "a").string());
    ASSERT_EQ(r.exitCode, 0) << r.err;
    const auto ref = readJson(dir / "a" / "report.json")["measurement"]["reference"];
    EXPECT_EQ(ref["light"], "bounce");
    ASSERT_EQ(ref["bounce"]["solves"].size(), 1u);
    const auto solve = ref["bounce"]["solves"][0];
    EXPECT_TRUE(solve["converged"].get<bool>());
    EXPECT_GE(solve["bounces"].get<int>(), 2);
    EXPECT_LT(solve["changes"].back().get<double>(), 0.01);
    EXPECT_DOUBLE_EQ(ref["bounce"]["spacing_m"].get<double>(), 256.0);
    // Read back with the same light: no capture, no solve.
    const auto again = runAmbience(base + " --out " + (dir / "b").string());
    ASSERT_EQ(again.exitCode, 0) << again.err;
    const auto refB = readJson(dir / "b" / "report.json")["measurement"]["reference"];
    EXPECT_EQ(refB["referenceCaptures"].get<int>(), 0);
    EXPECT_EQ(refB["bounce"]["solves"].size(), 0u);
    // The hemisphere is another reference: refused, or made again when asked.
    const auto other =
        runAmbience(base + " --reference-light hemisphere --out " + (dir / "c").string());
    EXPECT_EQ(other.exitCode, 2);
    EXPECT_NE(other.err.find("light=bounce"), std::string::npos) << other.err;
    const auto replaced = runAmbience(base + " --reference-light hemisphere "
                                             "--replace-stale-caches --out " +
                                      (dir / "d").string());
    ASSERT_EQ(replaced.exitCode, 0) << replaced.err;
    EXPECT_GT(readJson(dir / "d" / "report.json")["measurement"]["reference"]["referenceCaptures"]
                  .get<int>(),
              0);
}

// A settings file's facesPerFrame (the tuning panel's Save writes it) was reset to 1 by the
// command line's default: --faces-per-frame now applies only when given.
TEST(RunMeasure, ConfigFacesPerFrameStandsUnlessTheFlagIsGiven) {
    const fs::path dir = scratchDir("run-faces");
    std::ofstream(dir / "v.json") << R"({"facesPerFrame": 6})";
    const std::string common = "run --no-frames --max-frames 31 --config " +
                               (dir / "v.json").string();
    const auto a = runAmbience(common + " --out " + (dir / "a").string());
    ASSERT_EQ(a.exitCode, 0) << a.err;
    const auto b = runAmbience(common + " --faces-per-frame 2 --out " + (dir / "b").string());
    ASSERT_EQ(b.exitCode, 0) << b.err;
    // The budget's faces: all but the first frame's prime (lighting/CaptureCore.h), which is the
    // same whatever the budget.
    const auto facesOf = [&](const char* run) {
        const auto a = readJson(dir / run / "report.json")["ambience"];
        EXPECT_EQ(a["primeFaces"].get<int>(), 24) << run;
        return a["facesCaptured"].get<double>() - a["primeFaces"].get<double>();
    };
    // 31 frames: the config's 6 faces a frame capture about 3 times what the flag's 2 do.
    EXPECT_GT(facesOf("a"), 2.5 * facesOf("b")) << facesOf("a") << " vs " << facesOf("b");
    EXPECT_GT(facesOf("b"), 31.0);  // more than one face a frame
}

// Stress, a million metres from the origin: the volume captures, stores anchors and measures a
// finite error; nothing is rejected (float positions would have collapsed the lattice there).
TEST(RunMeasure, FarFromTheOriginStaysFinite) {
    const fs::path dir = scratchDir("run-far");
    const auto r =
        runAmbience("run --replay " + sourcePath("replays/far-flight.json") +
                    " --no-frames --max-frames 150 --measure-every 30 --out " + dir.string());
    ASSERT_EQ(r.exitCode, 0) << r.err;
    const auto report = readJson(dir / "report.json");
    const auto& m = report["measurement"];
    EXPECT_EQ(m["measuredFrames"], 5);
    const double maxError = m["error"]["max"].get<double>();
    EXPECT_TRUE(std::isfinite(maxError) && maxError < 5.0) << maxError;
    EXPECT_GT(report["ambience"]["anchorsMax"].get<int>(), 10);  // 25 probes in 150 frames
    EXPECT_EQ(report["ambience"]["rejectedProbes"], 0);
}

// Three methods on one short replay, plus a sweep point that cannot run (an unknown settings
// key): the failure is recorded with its error, every other run is ok, and the outputs exist.
TEST(BenchCommand, SweepRecordsAFailureAndGoesOn) {
    const fs::path dir = scratchDir("bench");
    {
        std::ofstream sweep(dir / "sweep.json");
        sweep << R"({"points": [
            {"label": "blend1", "methods": ["volume"], "volume": {"store": {"blendTime_s": 1.0}}},
            {"label": "broken", "methods": ["volume"], "volume": {"noSuchSetting": 1}}]})";
    }
    const auto r = runAmbience(
        "bench --replays highway-drive --methods volume,constant,grid "
        "--max-frames 60 --measure-every 20 --jobs 2 --sweep " +
        (dir / "sweep.json").string() + " --out " + (dir / "out").string());
    ASSERT_EQ(r.exitCode, 0) << r.err;
    const auto rows = readCsv((dir / "out" / "results.csv").string());
    ASSERT_EQ(rows.size(), 1u + 5u);  // header + volume x 3 points + constant + grid
    const auto& h = rows[0];
    int ok = 0, failed = 0;
    for (std::size_t i = 1; i < rows.size(); ++i) {
        const auto& row = rows[i];
        ASSERT_EQ(row.size(), h.size());
        EXPECT_EQ(row[column(h, "replay")], "highway-drive");
        if (row[column(h, "status")] == "ok") {
            ++ok;
            const double e = std::stod(row[column(h, "error_mean")]);
            EXPECT_TRUE(e >= 0.0 && e < 5.0) << e;
            EXPECT_EQ(row[column(h, "measured_frames")], "3");
            EXPECT_TRUE(fs::exists(dir / "out" / row[column(h, "run_dir")] / "report.json"));
        } else {
            ++failed;
            EXPECT_EQ(row[column(h, "point")], "broken");
            EXPECT_NE(row[column(h, "error_message")].find("noSuchSetting"), std::string::npos)
                << row[column(h, "error_message")];
        }
    }
    EXPECT_EQ(ok, 4);
    EXPECT_EQ(failed, 1);
    const std::string summary = slurp((dir / "out" / "summary.md").string());
    EXPECT_NE(summary.find("volume (ours)"), std::string::npos);
    // Our error against each other method's, the grid's among them, with its interval.
    EXPECT_NE(summary.find("/ each other method's"), std::string::npos);
    EXPECT_NE(summary.find("grid **"), std::string::npos);
    EXPECT_TRUE(fs::exists(dir / "out" / "oracle" / "highway-drive.json"));
}

// Two budgets: every method runs at both, and the summary gives error against cost per budget
// with ours against the best other method and the Pareto front.
TEST(BenchCommand, BudgetsAddPointsAndTheirSection) {
    const fs::path dir = scratchDir("bench-budgets");
    const auto r = runAmbience(
        "bench --replays highway-drive --methods volume,constant --max-frames 60 "
        "--measure-every 20 --jobs 2 --budgets 2,1 --out " + (dir / "out").string());
    ASSERT_EQ(r.exitCode, 0) << r.err;
    const auto rows = readCsv((dir / "out" / "results.csv").string());
    ASSERT_EQ(rows.size(), 1u + 4u);
    const auto& h = rows[0];
    std::multiset<std::string> labels;
    for (std::size_t i = 1; i < rows.size(); ++i) {
        EXPECT_EQ(rows[i][column(h, "status")], "ok");
        labels.insert(rows[i][column(h, "point")]);
    }
    EXPECT_EQ(labels, (std::multiset<std::string>{"default", "default", "default-f2", "default-f2"}));
    const std::string summary = slurp((dir / "out" / "summary.md").string());
    EXPECT_NE(summary.find("## Budget: error against cost"), std::string::npos);
    EXPECT_NE(summary.find("| 2 |"), std::string::npos);
    EXPECT_NE(summary.find("Pareto front"), std::string::npos);
    // Every ours-against-other ratio carries its paired bootstrap interval: "r [lo, hi]", with
    // lo <= r <= hi (app/bench/BenchStats.h).
    const auto ratio = summary.find("constant **");
    ASSERT_NE(ratio, std::string::npos) << summary;
    double r0 = 0, lo = 0, hi = 0;
    ASSERT_EQ(std::sscanf(summary.c_str() + ratio, "constant **%lf [%lf, %lf]", &r0, &lo, &hi), 3)
        << summary.substr(ratio, 60);
    EXPECT_LE(lo, r0);
    EXPECT_LE(r0, hi);
    EXPECT_LT(hi, 1.0);  // the volume is far better than a constant ambient
    EXPECT_NE(summary.find("paired bootstrap 95 % interval"), std::string::npos);
}

TEST(BenchCommand, BadInputIsOneLineAndExitCode2) {
    const fs::path dir = scratchDir("bench-bad");
    for (const std::string& args :
         {std::string("bench --methods volume,nonsense"), std::string("bench --replays nowhere"),
          std::string("bench --sweep ") + (dir / "missing.json").string(),
          std::string("bench --measure-every 0"), std::string("bench --jobs -1"),
          std::string("bench --budgets 0,3"), std::string("bench --budgets 3,x"),
          std::string("run --oracle x.json"), std::string("run --ambient nonsense")}) {
        const auto r = runAmbience(args + " --out " + (dir / "o").string());
        EXPECT_EQ(r.exitCode, 2) << args;
        EXPECT_EQ(r.errLines(), 1) << args << ": " << r.err;
    }
    std::ofstream(dir / "bad.json") << R"({"points": [{"label": "x", "volume": 3}]})";
    const auto r = runAmbience("bench --sweep " + (dir / "bad.json").string());
    EXPECT_EQ(r.exitCode, 2);
    EXPECT_NE(r.err.find("points[0]"), std::string::npos) << r.err;
}

// Columns that time the run (wall clock or CPU): they differ from one run to the next.
bool timingColumn(const std::string& name) {
    auto endsWith = [&](const std::string& end) {
        return name.size() >= end.size() &&
               name.compare(name.size() - end.size(), end.size(), end) == 0;
    };
    return name == "wall_s" || name == "oracle_s" || name == "reference_s" ||
           name == "share_of_frame" || endsWith("_ms_median") || endsWith("_ms_p95");
}

// A sweep (one short replay, two methods, a point that fails) emitted into a folder whose path
// has a space and quotes, run by GNU parallel from elsewhere, and collected, gives the same
// results.csv as the same sweep run by a local bench: the same rows, every column but the
// timing ones equal (the simulation is deterministic), the failure with the same error.
TEST(BenchCommand, EmittedSweepRunByParallelCollectsAsALocalBench) {
    ASSERT_TRUE(test::onPath("parallel")) << "needs GNU parallel (Debian package parallel)";
    const fs::path dir = scratchDir("bench-emit") / "it's a \"sweep\"";
    fs::create_directories(dir);
    const fs::path replays = dir / "my replays";
    fs::create_directories(replays);
    fs::copy_file(sourcePath("replays/highway-drive.json"), replays / "highway-drive.json");
    std::ofstream(dir / "sweep points.json")
        << R"({"points": [{"label": "broken", "methods": ["volume"], "volume": {"noSuchSetting": 1}}]})";
    const std::string sweep = "--replays " + shellQuote((replays / "highway-drive.json").string()) +
                              " --methods volume,constant --max-frames 60 --measure-every 20 "
                              "--sweep " +
                              shellQuote((dir / "sweep points.json").string());
    const auto local =
        runAmbience("bench " + sweep + " --jobs 2 --out " + shellQuote((dir / "local").string()));
    ASSERT_EQ(local.exitCode, 0) << local.err;

    const fs::path emitted = dir / "emit'ted";
    const auto emit = runAmbience("bench " + sweep + " --emit " + shellQuote(emitted.string()));
    ASSERT_EQ(emit.exitCode, 0) << emit.err;
    EXPECT_EQ(lineCount(slurp((emitted / "commands.txt").string())), 3);
    EXPECT_TRUE(fs::exists(emitted / "slurm.sh") && fs::exists(emitted / "README.txt"));
    EXPECT_FALSE(fs::exists(emitted / "results.csv"));  // nothing ran
    // The job file is shell lines by design: GNU parallel runs each through a shell, from /.
    const auto parallel = runCommand({"parallel", "--will-cite", "--jobs", "2"},
                                     (emitted / "jobs.txt").string(), "/");
    EXPECT_EQ(parallel.exitCode, 1) << parallel.out << parallel.err;  // the number of failed runs
    const auto collect = runAmbience("bench --collect " + shellQuote(emitted.string()));
    ASSERT_EQ(collect.exitCode, 0) << collect.err;
    EXPECT_NE(collect.out.find("3 runs (1 failed)"), std::string::npos) << collect.out;

    const auto a = readCsv((dir / "local" / "results.csv").string());
    const auto b = readCsv((emitted / "results.csv").string());
    ASSERT_EQ(a.size(), 1u + 3u);
    ASSERT_EQ(b.size(), a.size());
    ASSERT_EQ(b[0], a[0]);
    const auto& h = a[0];
    // An error names the file it is about: the same one in each bench's own folder.
    auto inOut = [](std::string text, const fs::path& out) {
        for (std::size_t at; (at = text.find(out.string())) != std::string::npos;)
            text.replace(at, out.string().size(), "<out>");
        return text;
    };
    int compared = 0;
    for (std::size_t r = 1; r < a.size(); ++r) {
        ASSERT_EQ(b[r].size(), h.size());
        for (std::size_t c = 0; c < h.size(); ++c) {
            if (timingColumn(h[c])) continue;
            EXPECT_EQ(inOut(b[r][c], emitted), inOut(a[r][c], dir / "local"))
                << "row " << r << ", column " << h[c];
            compared += !a[r][c].empty();
        }
        const bool broken = a[r][column(h, "point")] == "broken";
        EXPECT_EQ(a[r][column(h, "status")], broken ? "failed" : "ok");
        if (broken) {
            EXPECT_NE(a[r][column(h, "error_message")].find("exit code 2: "), std::string::npos);
            EXPECT_NE(a[r][column(h, "error_message")].find("noSuchSetting"), std::string::npos);
        } else {
            EXPECT_FALSE(a[r][column(h, "error_mean")].empty());
        }
        EXPECT_FALSE(b[r][column(h, "wall_s")].empty());
    }
    EXPECT_GT(compared, 2 * 30);  // the two runs that ran fill most columns
    const std::string summary = slurp((emitted / "summary.md").string());
    EXPECT_NE(summary.find("--collect"), std::string::npos);
    EXPECT_NE(summary.find("volume (ours)"), std::string::npos);
}

// Runs that never ran are reported as failed, as a local bench reports a failed run; the
// collector takes nothing but the folder, and --emit refuses what it cannot write out.
TEST(BenchCommand, CollectReportsRunsThatDidNotRun) {
    const fs::path dir = scratchDir("bench-collect");
    const auto emit = runAmbience(
        "bench --replays highway-drive --methods constant,hemisphere "
        "--max-frames 30 --emit " +
        (dir / "e").string());
    ASSERT_EQ(emit.exitCode, 0) << emit.err;
    // The first line only (the oracle run), from commands.txt.
    const std::string first = slurp((dir / "e" / "commands.txt").string());
    ASSERT_EQ(lineCount(first), 2);
    // A line of commands.txt is a shell command by design: run as `/bin/sh -c LINE`.
    const auto line = runCommand({"/bin/sh", "-c", first.substr(0, first.find('\n'))});
    EXPECT_EQ(line.exitCode, 0) << line.err;
    const auto collect = runAmbience("bench --collect " + (dir / "e").string());
    ASSERT_EQ(collect.exitCode, 0) << collect.err;
    const auto rows = readCsv((dir / "e" / "results.csv").string());
    ASSERT_EQ(rows.size(), 3u);
    const auto& h = rows[0];
    EXPECT_EQ(rows[1][column(h, "method")], "constant");
    EXPECT_EQ(rows[1][column(h, "status")], "ok");
    EXPECT_EQ(rows[2][column(h, "method")], "hemisphere");
    EXPECT_EQ(rows[2][column(h, "status")], "failed");
    EXPECT_EQ(rows[2][column(h, "error_message")],
              "not run: no runs/highway-drive__hemisphere__default/exit-status.txt");
    // Nothing ran at all: every run failed, exit code 1, as a local bench in which nothing ran.
    const auto again = runAmbience(
        "bench --replays highway-drive --methods constant "
        "--emit " +
        (dir / "f").string());
    ASSERT_EQ(again.exitCode, 0) << again.err;
    const auto none = runAmbience("bench --collect " + (dir / "f").string());
    EXPECT_EQ(none.exitCode, 1) << none.err;
    for (const std::string& args :
         {"bench --collect " + (dir / "e").string() + " --jobs 2",
          "bench --collect " + (dir / "nowhere").string(),
          "bench --tune --emit " + (dir / "g").string(),
          "bench --emit " + (dir / "g").string() + " --out " + (dir / "h").string()}) {
        const auto r = runAmbience(args);
        EXPECT_EQ(r.exitCode, 2) << args;
        EXPECT_EQ(r.errLines(), 1) << args << ": " << r.err;
    }
}

// The drawn budget's floor line: ours with its far-field term taken out, over the best other
// method's drawn mean, from two run folders whose budgets are known (0.10 - 0.02 over 0.09).
TEST(BenchCommand, DrawnBudgetStatesTheFarFieldsFloor) {
    const fs::path dir = scratchDir("bench-floor");
    const auto writeRun = [&](const std::string& method, double drawn, double farField) {
        const fs::path run = dir / "runs" / ("highway-drive__" + method + "__default");
        fs::create_directories(run);
        std::ofstream(run / "exit-status.txt") << "0 1.0\n";
        nlohmann::json report;
        report["measurement"]["reference"]["drawn"]["budget"] = {
            {"count", 40},       {"drawn", drawn},       {"farField", farField},
            {"patch", 0.0},      {"model", drawn - farField - 0.01},
            {"truncation", 0.01}, {"closure", 1.0},      {"perPoint", drawn}};
        std::ofstream(run / "report.json") << report.dump();
    };
    writeRun("volume", 0.10, 0.02);
    writeRun("grid", 0.09, 0.01);
    writeRun("reactive", 0.12, 0.04);
    const auto r = runAmbience("bench --from-runs --replays highway-drive --methods "
                               "volume,grid,reactive --oracle reference --out " +
                               dir.string());
    ASSERT_EQ(r.exitCode, 0) << r.err;
    const std::string summary = slurp((dir / "summary.md").string());
    // The command as given: a flag stands alone (no value after it).
    EXPECT_NE(summary.find("--oracle reference --out " + dir.string() + " --from-runs`"),
              std::string::npos)
        << summary.substr(0, 400);
    const std::string lead = "ours would read ";
    const std::size_t at = summary.find(lead);
    ASSERT_NE(at, std::string::npos) << summary;
    const double floorValue = std::stod(summary.substr(at + lead.size()));
    EXPECT_NEAR(floorValue, 0.08, 5e-5);
    const std::size_t ratioAt = summary.find("**", at);
    ASSERT_NE(ratioAt, std::string::npos);
    EXPECT_NEAR(std::stod(summary.substr(ratioAt + 2)), 0.08 / 0.09, 5e-4);
    EXPECT_NE(summary.find("the best other here (grid, 0.0900)", at), std::string::npos)
        << summary.substr(at, 300);
}

// The reference's layers reach every run: `run` defaults to two, so one layer is said
// explicitly, and the emitted manifest keeps the choice for --collect.
TEST(BenchCommand, BounceCanopyIsPassedToEveryRun) {
    const fs::path dir = scratchDir("bench-canopy");
    for (const std::string canopy : {"0", "10"}) {
        const fs::path emitted = dir / ("e" + canopy);
        const auto emit = runAmbience(
            "bench --replays highway-drive --methods constant --oracle reference --max-frames 30 "
            "--bounce-canopy " + canopy + " --emit " + emitted.string());
        ASSERT_EQ(emit.exitCode, 0) << emit.err;
        const std::string commands = slurp((emitted / "commands.txt").string());
        EXPECT_NE(commands.find("--bounce-canopy " + canopy + " "), std::string::npos) << commands;
        EXPECT_EQ(readJson(emitted / "bench.json")["bounceCanopy_m"].get<int>(), std::stoi(canopy));
    }
    const auto bad = runAmbience("bench --replays highway-drive --oracle reference "
                                 "--bounce-canopy 0.5 --out " + (dir / "bad").string());
    EXPECT_EQ(bad.exitCode, 2);
    EXPECT_NE(bad.err.find("--bounce-canopy"), std::string::npos) << bad.err;
}

// A bench with stderr in a file (not a terminal) writes plain progress lines at the interval
// set, the run count rising to the total, with no carriage returns.
TEST(BenchCommand, ProgressLinesWhenStderrIsAFile) {
    const fs::path dir = scratchDir("bench-progress");
    setenv("AMBIENCE_PROGRESS_S", "0.2", 1);
    const auto r = runAmbience(
        "bench --replays highway-drive --methods constant,hemisphere "
        "--max-frames 60 --measure-every 20 --jobs 1 --out " +
        dir.string());
    unsetenv("AMBIENCE_PROGRESS_S");
    ASSERT_EQ(r.exitCode, 0) << r.err;
    EXPECT_EQ(r.err.find('\r'), std::string::npos);
    std::vector<std::string> progress;
    std::istringstream in(r.err);
    for (std::string line; std::getline(in, line);)
        if (line.rfind("bench: run ", 0) == 0) progress.push_back(line);
    ASSERT_GE(progress.size(), 3u) << r.err;  // two runs of several seconds each
    EXPECT_EQ(progress.front().rfind("bench: run 0/2 (0 %), ", 0), 0u) << progress.front();
    EXPECT_EQ(progress.back().rfind("bench: run 2/2 (100 %), ", 0), 0u) << progress.back();
    EXPECT_NE(progress.back().find("last highway-drive/hemisphere/default"), std::string::npos);
}

}  // namespace
}  // namespace amb::test
