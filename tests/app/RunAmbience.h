// RunAmbience.h — runs the built `ambience` executable with arguments and captures its exit
// code, stdout and stderr, for tests of the command line.
#pragma once

#include <sys/wait.h>
#include <unistd.h>

#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>

#include <gtest/gtest.h>

namespace amb::test {

struct CommandResult {
    int exitCode = -1;
    std::string out, err;
    int errLines() const;
};

inline std::string slurp(const std::string& path) {
    std::ifstream in(path);
    std::ostringstream s;
    s << in.rdbuf();
    return s.str();
}

inline int lineCount(const std::string& s) {
    int n = 0;
    for (char c : s) n += c == '\n';
    return n;
}

inline int CommandResult::errLines() const { return lineCount(err); }

// A fresh, empty scratch folder for one test.
inline std::filesystem::path scratchDir(const std::string& name) {
    const auto dir = std::filesystem::temp_directory_path() / ("ambience-test-" + name);
    std::filesystem::remove_all(dir);
    std::filesystem::create_directories(dir);
    return dir;
}

// Runs `prefix ambience args`: `args` is appended to the command line as is (shell syntax;
// quote what needs quoting); `prefix` is a wrapper such as xvfb-run.
inline CommandResult runAmbience(const std::string& args, const std::string& prefix = "") {
    static int counter = 0;
    // ctest runs tests as parallel processes: the pid keeps their files apart.
    const std::string base = testing::TempDir() + "ambience_cli_" + std::to_string(getpid()) +
                             "_" + std::to_string(++counter);
    const std::string cmd = prefix + " " + std::string(AMBIENCE_BINARY_DIR) + "/bin/ambience " +
                            args + " >" +
                            base + ".out 2>" + base + ".err </dev/null";
    const int status = std::system(cmd.c_str());
    CommandResult r;
    r.exitCode = WIFEXITED(status) ? WEXITSTATUS(status) : 128 + WTERMSIG(status);
    r.out = slurp(base + ".out");
    r.err = slurp(base + ".err");
    return r;
}

inline std::string sourcePath(const std::string& relative) {
    return std::string(AMBIENCE_SOURCE_DIR) + "/" + relative;
}

}  // namespace amb::test
