// BenchHostile_test.cpp — `ambience bench --emit` and `--collect` against a hostile user or a
// folder that was in other hands: no text runs as a command through an emitted line, the
// collector neither crashes nor hangs on what it reads, reads and writes nothing outside its
// folder, and one line with exit code 2 for each thing it refuses.
#include <sys/stat.h>
#include <unistd.h>

#include <filesystem>
#include <fstream>
#include <string>

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include "RunAmbience.h"
#include "app/bench/BenchEmit.h"

namespace amb {
namespace {

namespace fs = std::filesystem;
using test::runAmbience;
using test::scratchDir;
using test::slurp;
using test::sourcePath;

// Commands the tests run get this wrapper: a collector that hangs fails the test in a minute
// (exit code 124) instead of holding the suite.
const char* const kTimeout = "timeout 60";

void expectInputError(const std::string& args, std::initializer_list<const char*> fragments) {
    const test::CommandResult r = runAmbience(args, kTimeout);
    EXPECT_EQ(r.exitCode, 2) << args << "\nstderr: " << r.err;
    EXPECT_EQ(r.errLines(), 1) << args << "\nstderr: " << r.err;
    for (const char* f : fragments)
        EXPECT_NE(r.err.find(f), std::string::npos) << "'" << f << "' not in: " << r.err;
}

std::string q(const fs::path& p) {
    return shellQuote(p.string());
}

// An emitted bench of two cheap runs (nothing run): constant and hemisphere on the highway.
fs::path emitTwoRuns(const fs::path& dir) {
    const auto r = runAmbience(
        "bench --replays highway-drive --methods constant,hemisphere "
        "--max-frames 30 --emit " +
        q(dir));
    EXPECT_EQ(r.exitCode, 0) << r.err;
    return dir;
}

const char* const kRunA = "runs/highway-drive__constant__default";
const char* const kRunB = "runs/highway-drive__hemisphere__default";

// A run folder made to look as if its run ended with `status` and wrote `report`.
void fakeRun(const fs::path& run, const std::string& status, const std::string& report) {
    std::ofstream(run / "exit-status.txt") << status;
    std::ofstream(run / "report.json") << report;
}

std::string column(const fs::path& csv, int row, const std::string& name) {
    std::ifstream in(csv);
    std::string header, line;
    std::getline(in, header);
    for (int i = 0; i < row && std::getline(in, line);) ++i;
    // The columns before error_message hold no commas; error_message may be quoted.
    std::size_t index = 0;
    for (std::size_t at = 0, next; (next = header.find(',', at)) != std::string::npos;
         at = next + 1) {
        if (header.substr(at, next - at) == name) break;
        ++index;
    }
    std::vector<std::string> cells;
    std::string cell;
    bool quoted = false;
    for (char c : line) {
        if (c == '"')
            quoted = !quoted;
        else if (c == ',' && !quoted)
            cells.push_back(cell), cell.clear();
        else
            cell += c;
    }
    cells.push_back(cell);
    return index < cells.size() ? cells[index] : "";
}

// 1. A newline in a replay's file name, a sweep label or the --emit folder would end a line of
// jobs.txt and start another command: each is refused, nothing is emitted, nothing runs.
TEST(BenchHostile, NewlinesNeverReachAnEmittedLine) {
    const fs::path dir = scratchDir("bench-newline");
    fs::create_directories(dir / "rp");
    const fs::path evil = dir / "rp" / "a\ntouch PWNED\nb.json";
    fs::copy_file(sourcePath("replays/highway-drive.json"), evil);
    expectInputError("bench --replays " + q(evil) + " --methods constant --emit " + q(dir / "em"),
                     {"--replays", "control character", "a\\ntouch PWNED\\nb.json"});
    EXPECT_FALSE(fs::exists(dir / "em" / "jobs.txt"));

    std::ofstream(dir / "sweep.json")
        << R"({"points": [{"label": "x\ntouch\tPWNED\ny", "methods": ["constant"]}]})";
    expectInputError("bench --replays highway-drive --methods constant --sweep " +
                         q(dir / "sweep.json") + " --emit " + q(dir / "em2"),
                     {"label", "control character"});
    EXPECT_FALSE(fs::exists(dir / "em2" / "jobs.txt"));

    expectInputError(
        "bench --replays highway-drive --methods constant --emit " + q(dir / "e\ntouch PWNED\nm"),
        {"--emit", "control character"});
    EXPECT_FALSE(fs::exists(dir / "PWNED"));
    EXPECT_FALSE(fs::exists("PWNED"));
}

// 2, 3. A report nested a million levels deep, and FIFOs or devices in place of the files a
// run folder holds: the collector neither crashes nor blocks; the run is reported failed.
TEST(BenchHostile, CollectNeitherCrashesNorHangs) {
    const fs::path d = emitTwoRuns(scratchDir("bench-deep") / "e");
    std::string deep = "{\"measurement\": ";
    deep += std::string(1000000, '[') + std::string(1000000, ']') + "}";
    fakeRun(d / kRunA, "0 1\n", deep);
    fakeRun(d / kRunB, "0 1\n", R"({"frameCount": 30})");
    const auto deepRun = runAmbience("bench --collect " + q(d), kTimeout);
    EXPECT_EQ(deepRun.exitCode, 0) << deepRun.err;
    EXPECT_NE(column(d / "results.csv", 1, "error_message").find("nested deeper"),
              std::string::npos);
    EXPECT_EQ(column(d / "results.csv", 2, "status"), "ok");

    // FIFOs in place of the report, the exit status and the log (no writer: opening one for
    // reading used to wait forever), and the log a link to /dev/zero (read without end).
    fs::remove(d / kRunA / "report.json");
    ASSERT_EQ(::mkfifo((d / kRunA / "report.json").c_str(), 0644), 0);
    fs::remove(d / kRunB / "exit-status.txt");
    ASSERT_EQ(::mkfifo((d / kRunB / "exit-status.txt").c_str(), 0644), 0);
    const auto fifo = runAmbience("bench --collect " + q(d), kTimeout);
    EXPECT_EQ(fifo.exitCode, 1) << fifo.err;  // both runs failed, as a bench where none ran
    EXPECT_NE(column(d / "results.csv", 1, "error_message").find("not a regular file"),
              std::string::npos);
    EXPECT_NE(column(d / "results.csv", 2, "error_message").find("not a regular file"),
              std::string::npos);
    fs::remove(d / kRunA / "report.json");
    std::ofstream(d / kRunA / "exit-status.txt") << "1 3\n";
    ASSERT_EQ(::mkfifo((d / kRunA / "log.txt").c_str(), 0644), 0);
    fs::remove(d / kRunB / "exit-status.txt");
    std::ofstream(d / kRunB / "exit-status.txt") << "1 3\n";
    fs::create_symlink("/dev/zero", d / kRunB / "log.txt");
    const auto logs = runAmbience("bench --collect " + q(d), kTimeout);
    EXPECT_EQ(logs.exitCode, 1) << logs.err;
    EXPECT_NE(column(d / "results.csv", 1, "error_message").find("exit code 1"), std::string::npos);
    EXPECT_LT(fs::file_size(d / "results.csv"), 100000u);

    // bench.json itself a FIFO, a folder, or 300 MB: one line, exit code 2.
    fs::rename(d / "bench.json", d / "bench.saved");
    ASSERT_EQ(::mkfifo((d / "bench.json").c_str(), 0644), 0);
    expectInputError("bench --collect " + q(d), {"bench.json", "not a regular file"});
    fs::remove(d / "bench.json");
    fs::create_directory(d / "bench.json");
    expectInputError("bench --collect " + q(d), {"bench.json", "not a regular file"});
    fs::remove(d / "bench.json");
    { std::ofstream big(d / "bench.json"); }
    fs::resize_file(d / "bench.json", std::uintmax_t(300) << 20);  // sparse: no disk used
    expectInputError("bench --collect " + q(d), {"bench.json", "too large"});
}

// 4. Outputs: --emit does not overwrite its own input, and results, summary and job files
// planted as links to files outside the folder replace the link, not the file.
TEST(BenchHostile, OutputsNeitherOverwriteInputsNorFollowLinks) {
    const fs::path dir = scratchDir("bench-links");
    const fs::path d = dir / "e";
    fs::create_directories(d);
    const std::string sweep = R"({"points": [{"label": "p1", "methods": ["constant"]}]})";
    std::ofstream(d / "commands.txt") << sweep;
    expectInputError("bench --replays highway-drive --methods constant --sweep " +
                         q(d / "commands.txt") + " --emit " + q(d),
                     {"commands.txt", "also the input --sweep"});
    EXPECT_EQ(slurp((d / "commands.txt").string()), sweep);

    fs::remove(d / "commands.txt");
    std::ofstream(dir / "victim.txt") << "precious";
    fs::create_symlink(dir / "victim.txt", d / "jobs.txt");
    emitTwoRuns(d);
    fs::create_symlink(dir / "victim.txt", d / "results.csv");
    fs::create_symlink(dir / "victim.txt", d / "summary.md");
    const auto collect = runAmbience("bench --collect " + q(d), kTimeout);
    EXPECT_EQ(collect.exitCode, 1) << collect.err;  // nothing ran: every run failed
    EXPECT_EQ(slurp((dir / "victim.txt").string()), "precious");
    for (const char* file : {"jobs.txt", "results.csv", "summary.md"})
        EXPECT_FALSE(fs::is_symlink(d / file)) << file;
    EXPECT_NE(slurp((d / "results.csv").string()).find("not run"), std::string::npos);
}

// 5. Nothing named in the folder leads outside it: replay names with "..", a sweep elsewhere,
// a log linked to a file outside.
TEST(BenchHostile, CollectReadsNothingOutsideItsFolder) {
    const fs::path dir = scratchDir("bench-outside");
    const fs::path d = emitTwoRuns(dir / "e");
    const std::string manifest = slurp((d / "bench.json").string());
    auto edit = [&](const std::function<void(nlohmann::json&)>& change) {
        nlohmann::json j = nlohmann::json::parse(manifest);
        change(j);
        std::ofstream(d / "bench.json") << j.dump(2);
    };
    edit([](nlohmann::json& j) { j["replays"][0]["name"] = "../../../outside/r1"; });
    expectInputError("bench --collect " + q(d), {"bench.json", "not a plain file stem"});
    edit([](nlohmann::json& j) { j["sweep"] = "/etc/passwd"; });
    expectInputError("bench --collect " + q(d), {"bench.json", "'sweep'"});
    edit([](nlohmann::json& j) { j["oracle"] = 5; });
    expectInputError("bench --collect " + q(d), {"bench.json", "'oracle'"});
    edit([](nlohmann::json&) {});

    std::ofstream(dir / "secret.txt") << "line one\nSECRET-MARKER\n";
    std::ofstream(d / kRunA / "exit-status.txt") << "1 2\n";
    fs::create_symlink(dir / "secret.txt", d / kRunA / "log.txt");
    // A run folder that is itself a link to a folder outside, with a report there.
    fs::create_directories(dir / "elsewhere");
    fakeRun(dir / "elsewhere", "0 1\n", R"({"frameCount": 30})");
    fs::remove_all(d / kRunB);
    fs::create_directory_symlink(dir / "elsewhere", d / kRunB);
    const auto collect = runAmbience("bench --collect " + q(d), kTimeout);
    EXPECT_EQ(collect.exitCode, 1) << collect.err;
    EXPECT_EQ(collect.err.find("SECRET-MARKER"), std::string::npos) << collect.err;
    const std::string results = slurp((d / "results.csv").string());
    EXPECT_EQ(results.find("SECRET-MARKER"), std::string::npos) << results;
    EXPECT_NE(column(d / "results.csv", 1, "error_message").find("symbolic link"),
              std::string::npos);
    EXPECT_NE(column(d / "results.csv", 2, "error_message").find("symbolic link is refused"),
              std::string::npos);
}

// 6, 7, 9. Empty values, replays that would share run folders, reports of the wrong shape,
// garbage exit statuses, and the folder named by its own option.
TEST(BenchHostile, NonsenseIsRefusedOrReportedPerRun) {
    const fs::path dir = scratchDir("bench-nonsense");
    expectInputError("bench --collect ''", {"--collect", "empty value"});
    expectInputError("bench --emit ''", {"--emit", "empty value"});
    expectInputError("bench --replays '' --emit " + q(dir / "x"), {"--replays", "empty value"});
    expectInputError("bench --methods constant --emit /proc/self", {"--emit"});

    fs::create_directories(dir / "dupA");
    fs::create_directories(dir / "dupB");
    fs::copy_file(sourcePath("replays/highway-drive.json"), dir / "dupA" / "r.json");
    fs::copy_file(sourcePath("replays/low-flight.json"), dir / "dupB" / "r.json");
    expectInputError("bench --replays " + q(dir / "dupA" / "r.json") + "," +
                         q(dir / "dupB" / "r.json") + " --methods constant --emit " + q(dir / "d"),
                     {"--replays", "two replays named 'r'"});

    // A report that is a list, or whose fields have the wrong types: that run is failed (or
    // read with the field left blank); the other run is collected.
    const fs::path d = emitTwoRuns(dir / "e");
    fakeRun(d / kRunA, "0 1\n", "[]");
    fakeRun(d / kRunB, "0 1\n", R"({"frameCount": 30, "measurement": {"oracle": 5, "error": []}})");
    const auto shapes = runAmbience("bench --collect " + q(d), kTimeout);
    EXPECT_EQ(shapes.exitCode, 0) << shapes.err;
    EXPECT_NE(column(d / "results.csv", 1, "error_message").find("expected a JSON object"),
              std::string::npos);
    EXPECT_EQ(column(d / "results.csv", 2, "status"), "ok");
    EXPECT_EQ(column(d / "results.csv", 2, "frames"), "30");

    // An exit status that is no exit status is not trusted.
    std::ofstream(d / kRunA / "exit-status.txt") << "2147483647 1\n";
    const auto garbage = runAmbience("bench --collect " + q(d), kTimeout);
    EXPECT_EQ(garbage.exitCode, 0) << garbage.err;
    const std::string message = column(d / "results.csv", 1, "error_message");
    EXPECT_NE(message.find("exit-status.txt: expected"), std::string::npos) << message;
    EXPECT_EQ(message.find("signal"), std::string::npos) << message;
}

}  // namespace
}  // namespace amb
