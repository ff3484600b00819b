// BenchEmit_test.cpp — the shell lines of `ambience bench --emit`: quoting that a POSIX shell
// reads back word for word, a run line that records its exit status and waits for its oracle
// run, and slurm.sh running the line of its array task.
#include <sys/wait.h>

#include <chrono>
#include <cstdlib>
#include <fstream>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "RunAmbience.h"
#include "app/bench/BenchEmit.h"

namespace amb {
namespace {

namespace fs = std::filesystem;

// Runs `command` as `/bin/sh -c command` (the shell is what these tests are about); its
// stdout, and its exit code in `code`.
std::string shell(const std::string& command, int* code = nullptr) {
    const test::CommandResult r = test::runCommand({"/bin/sh", "-c", command});
    if (code) *code = r.exitCode;
    return r.out;
}

const std::vector<std::string> kHostileWords = {
    "",           "plain",     "a b",   "it's",    "'",           "''",
    "\"quoted\"", "$HOME",     "`id`",  "$(id)",   "back\\slash", "tab\there",
    "new\nline",  "*",         "~",     "a;b|c&d", "!x",          "#not a comment",
    "-n",         "x'\"'\"'y", "{a,b}", "%s %d",   "ünïcode",     "=",
};

// Every word comes back from sh as it went in: printf gets exactly one argument per word.
TEST(BenchEmit, ShellQuoteRoundTripsThroughSh) {
    for (const std::string& word : kHostileWords) {
        int code = -1;
        EXPECT_EQ(shell("printf '%s' " + shellQuote(word), &code), word) << shellQuote(word);
        EXPECT_EQ(code, 0);
    }
    std::string expected;
    for (const std::string& word : kHostileWords) expected += "[" + word + "]";
    std::vector<std::string> args = {"printf", "[%s]"};
    args.insert(args.end(), kHostileWords.begin(), kHostileWords.end());
    EXPECT_EQ(shell(shellCommand(args)), expected);
}

TEST(BenchEmit, PlainWordsStayAsTheyAre) {
    EXPECT_EQ(shellQuote("--faces-per-frame"), "--faces-per-frame");
    EXPECT_EQ(shellQuote("/a/b_c/d.json"), "/a/b_c/d.json");
    EXPECT_EQ(shellQuote(""), "''");
    EXPECT_EQ(shellQuote("a b"), "'a b'");
    EXPECT_EQ(shellQuote("it's"), "'it'\\''s'");
    EXPECT_EQ(shellCommand({"a", "b c"}), "a 'b c'");
}

// A folder with a space and a quote in its name, for the runs of the tests below.
fs::path awkwardDir(const std::string& name) {
    const fs::path dir = test::scratchDir(name) / "a b'c \"d\"";
    fs::create_directories(dir);
    return dir;
}

std::string statusOf(const fs::path& dir) {
    return test::slurp((dir / kExitStatusFile).string());
}

// The line runs from any working directory: output into <dir>/log.txt, the exit status and
// whole seconds into exit-status.txt, and the line exits with the run's code.
TEST(BenchEmit, RunLineRecordsLogAndExitStatus) {
    const fs::path dir = awkwardDir("emit-line");
    const EmittedRun run{
        {"/bin/sh", "-c", "echo \"out $0\"; echo err >&2; exit 3", "x'y z"}, dir.string(), ""};
    int code = -1;
    shell("cd / && " + runLine(run, true), &code);
    EXPECT_EQ(code, 3);
    EXPECT_EQ(test::slurp((dir / "log.txt").string()), "out x'y z\nerr\n");
    const std::string status = statusOf(dir);
    EXPECT_EQ(status.rfind("3 ", 0), 0u) << status;
    const int seconds = std::atoi(status.c_str() + 2);
    EXPECT_TRUE(seconds >= 0 && seconds <= 5) << status;
    EXPECT_FALSE(fs::exists(dir / (std::string(kExitStatusFile) + ".tmp")));
    // A run that succeeds, and one that is killed (128 + signal, as the shell reports it).
    shell(runLine({{"/bin/true"}, dir.string(), ""}, true), &code);
    EXPECT_EQ(code, 0);
    EXPECT_EQ(statusOf(dir).rfind("0 ", 0), 0u);
    shell(runLine({{"/bin/sh", "-c", "kill -9 $$"}, dir.string(), ""}, true), &code);
    EXPECT_EQ(code, 137);
    EXPECT_EQ(statusOf(dir).rfind("137 ", 0), 0u) << statusOf(dir);
}

// A line with an oracle run to wait for does not start before that run's exit status exists
// (jobs.txt); the same line from commands.txt does not wait.
TEST(BenchEmit, RunLineWaitsForItsOracleRun) {
    const fs::path dir = awkwardDir("emit-wait");
    const fs::path oracleRun = dir / "oracle run", run = dir / "run";
    fs::create_directories(oracleRun);
    fs::create_directories(run);
    const EmittedRun line{{"/bin/true"}, run.string(), oracleRun.string()};
    int code = -1;
    shell("timeout 3 /bin/sh -c " + shellQuote(runLine(line, true)), &code);
    EXPECT_EQ(code, 124);  // still waiting when timeout stopped it
    EXPECT_FALSE(fs::exists(run / kExitStatusFile));
    std::ofstream(oracleRun / kExitStatusFile) << "0 1\n";
    const auto start = std::chrono::steady_clock::now();
    shell("timeout 10 /bin/sh -c " + shellQuote(runLine(line, true)), &code);
    EXPECT_EQ(code, 0);
    EXPECT_LT(std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count(), 5.0);
    EXPECT_EQ(statusOf(run).rfind("0 ", 0), 0u);
    fs::remove(oracleRun / kExitStatusFile);
    shell("timeout 3 /bin/sh -c " + shellQuote(runLine(line, false)), &code);
    EXPECT_EQ(code, 0);
}

// The job files: one line per run in each list, the first stage without waits in jobs.txt,
// and slurm.sh running line task + 1 of jobs.txt.
TEST(BenchEmit, JobFilesAndTheSlurmScript) {
    const fs::path dir = awkwardDir("emit-files");
    std::vector<EmittedRun> runs;
    for (int i = 0; i < 3; ++i) {
        const fs::path d = dir / ("run " + std::to_string(i));
        fs::create_directories(d);
        runs.push_back({{"/bin/sh", "-c", "echo run " + std::to_string(i)},
                        d.string(),
                        i == 0 ? "" : runs.front().dir});
    }
    writeJobFiles(dir.string(), runs, 1, "/opt/x y/ambience");
    const std::string commands = test::slurp((dir / "commands.txt").string());
    const std::string jobs = test::slurp((dir / "jobs.txt").string());
    EXPECT_EQ(test::lineCount(commands), 3);
    EXPECT_EQ(test::lineCount(jobs), 3);
    EXPECT_EQ(commands.find("while"), std::string::npos);
    EXPECT_EQ(jobs.substr(0, jobs.find('\n')).find("while"), std::string::npos);
    EXPECT_EQ(jobs.substr(jobs.find('\n') + 1).rfind("while [ ! -e ", 0), 0u);
    const std::string readme = test::slurp((dir / "README.txt").string());
    EXPECT_NE(readme.find("sbatch --array=0-2 "), std::string::npos);
    EXPECT_NE(readme.find("--sshloginfile"), std::string::npos);
    EXPECT_NE(readme.find("'/opt/x y/ambience' bench --collect "), std::string::npos);
    // Task 0 first (the oracle run), then task 2 (waits for task 0's status, which exists).
    const std::string slurm = shellQuote((dir / "slurm.sh").string());
    int code = -1;
    shell("SLURM_ARRAY_TASK_ID=0 timeout 10 " + slurm, &code);
    EXPECT_EQ(code, 0);
    shell("SLURM_ARRAY_TASK_ID=2 timeout 10 " + slurm, &code);
    EXPECT_EQ(code, 0);
    EXPECT_EQ(test::slurp((fs::path(runs[2].dir) / "log.txt").string()), "run 2\n");
    EXPECT_FALSE(fs::exists(fs::path(runs[1].dir) / "log.txt"));
    shell("SLURM_ARRAY_TASK_ID=3 " + slurm + " 2>/dev/null", &code);
    EXPECT_EQ(code, 2);  // no such line
    shell("env -u SLURM_ARRAY_TASK_ID " + slurm + " 2>/dev/null", &code);
    EXPECT_NE(code, 0);
}

}  // namespace
}  // namespace amb
