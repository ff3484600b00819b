// CliTestUtil.h — run the `ambience` executable from a test and collect exit code and stderr.
#pragma once

#include <sys/wait.h>

#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>

namespace amb::test {

struct CliResult {
    int exitCode = -1;
    std::string err;
};

inline std::string ambienceExe() {
    return std::string(AMBIENCE_BINARY_DIR) + "/bin/ambience";
}

inline std::filesystem::path scratchDir(const std::string& name) {
    const auto dir = std::filesystem::temp_directory_path() / ("ambience-test-" + name);
    std::filesystem::remove_all(dir);
    std::filesystem::create_directories(dir);
    return dir;
}

// Runs `prefix ambience args` with stdout discarded and stderr captured.
inline CliResult runAmbience(const std::string& args, const std::string& prefix = "") {
    const auto errFile = std::filesystem::temp_directory_path() /
                         ("ambience-cli-" + std::to_string(::getpid()) + ".err");
    const std::string cmd =
        prefix + " " + ambienceExe() + " " + args + " >/dev/null 2>" + errFile.string();
    const int status = std::system(cmd.c_str());
    CliResult r;
    r.exitCode = WIFEXITED(status) ? WEXITSTATUS(status) : -1;
    std::ifstream in(errFile);
    std::stringstream ss;
    ss << in.rdbuf();
    r.err = ss.str();
    std::filesystem::remove(errFile);
    return r;
}

inline int lineCount(const std::string& s) {
    int n = 0;
    for (char c : s) n += c == '\n';
    return n;
}

}  // namespace amb::test
