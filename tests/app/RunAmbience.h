// RunAmbience.h — runs the built `ambience` executable with arguments and captures its exit
// code, stdout and stderr, for tests of the command line. No shell is involved: the argument
// text is split into words (with the shell's quoting rules, nothing expanded) and the child is
// started from an argument vector.
#pragma once

#include <fcntl.h>
#include <spawn.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <stdexcept>
#include <string>
#include <vector>

extern char** environ;

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

// A fresh, empty scratch folder for one test. ctest runs each test in its own process, two at
// a time, and tests of one fixture share a name: the process id keeps them apart.
inline std::filesystem::path scratchDir(const std::string& name) {
    const auto dir = std::filesystem::temp_directory_path() /
                     ("ambience-test-" + name + "-" + std::to_string(::getpid()));
    std::filesystem::remove_all(dir);
    std::filesystem::create_directories(dir);
    return dir;
}

// The words of `text` as a POSIX shell would split them, with no expansion: blanks separate
// words; '...' keeps everything literally; "..." keeps everything but \" \\ \$ \` (the
// backslash escapes those); a backslash outside quotes escapes the next character.
inline std::vector<std::string> splitWords(const std::string& text) {
    std::vector<std::string> words;
    std::string word;
    bool inWord = false;
    for (std::size_t i = 0; i < text.size(); ++i) {
        const char c = text[i];
        if (c == ' ' || c == '\t' || c == '\n') {
            if (inWord) words.push_back(word), word.clear(), inWord = false;
        } else if (c == '\'') {
            const std::size_t end = text.find('\'', i + 1);
            if (end == std::string::npos) throw std::invalid_argument("unclosed ' in: " + text);
            word += text.substr(i + 1, end - i - 1), i = end, inWord = true;
        } else if (c == '"') {
            for (++i; i < text.size() && text[i] != '"'; ++i) {
                if (text[i] == '\\' && i + 1 < text.size() &&
                    std::string("\"\\$`").find(text[i + 1]) != std::string::npos)
                    ++i;
                word += text[i];
            }
            if (i >= text.size()) throw std::invalid_argument("unclosed \" in: " + text);
            inWord = true;
        } else if (c == '\\' && i + 1 < text.size()) {
            word += text[++i], inWord = true;
        } else {
            word += c, inWord = true;
        }
    }
    if (inWord) words.push_back(word);
    return words;
}

// An executable of that name in a directory of PATH.
inline bool onPath(const std::string& name) {
    const char* path = std::getenv("PATH");
    const std::string dirs = path ? path : "";
    for (std::size_t start = 0; start <= dirs.size();) {
        const std::size_t end = std::min(dirs.find(':', start), dirs.size());
        const std::filesystem::path candidate =
            std::filesystem::path(dirs.substr(start, end - start)) / name;
        if (end > start && ::access(candidate.c_str(), X_OK) == 0) return true;
        start = end + 1;
    }
    return false;
}

// Runs the program argv[0] (found on PATH) with the argument vector `argv`, stdin from
// `stdinPath` (/dev/null if empty), stdout and stderr captured, in `workDir` if given. No shell.
inline CommandResult runCommand(std::vector<std::string> words, const std::string& stdinPath = "",
                                const std::filesystem::path& workDir = {}) {
    static int counter = 0;
    // ctest runs tests as parallel processes: the pid keeps their files apart.
    const std::string base = testing::TempDir() + "ambience_cli_" + std::to_string(getpid()) +
                             "_" + std::to_string(++counter);
    std::vector<char*> argv;
    for (std::string& w : words) argv.push_back(w.data());
    argv.push_back(nullptr);
    const std::string inPath = stdinPath.empty() ? "/dev/null" : stdinPath;
    const std::string outPath = base + ".out", errPath = base + ".err";
    posix_spawn_file_actions_t actions;
    posix_spawn_file_actions_init(&actions);
    posix_spawn_file_actions_addopen(&actions, 0, inPath.c_str(), O_RDONLY, 0);
    posix_spawn_file_actions_addopen(&actions, 1, outPath.c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0644);
    posix_spawn_file_actions_addopen(&actions, 2, errPath.c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0644);
    if (!workDir.empty()) posix_spawn_file_actions_addchdir_np(&actions, workDir.c_str());
    pid_t pid = -1;
    const int spawned = posix_spawnp(&pid, argv[0], &actions, nullptr, argv.data(), environ);
    posix_spawn_file_actions_destroy(&actions);
    CommandResult r;
    if (spawned != 0) {
        r.exitCode = 127;  // as a shell reports a command it cannot start
        r.err = std::string("cannot start ") + argv[0] + "\n";
        return r;
    }
    int status = 0;
    while (waitpid(pid, &status, 0) < 0 && errno == EINTR) {
    }
    r.exitCode = WIFEXITED(status) ? WEXITSTATUS(status) : 128 + WTERMSIG(status);
    r.out = slurp(outPath);
    r.err = slurp(errPath);
    return r;
}

// Runs `prefix ambience args` (splitWords of each; `prefix` is a wrapper such as xvfb-run,
// found on PATH) with stdin from /dev/null, in `workDir` if given (runCommand).
inline CommandResult runAmbience(const std::string& args, const std::string& prefix = "",
                                 const std::filesystem::path& workDir = {}) {
    std::vector<std::string> words = splitWords(prefix);
    words.push_back(std::string(AMBIENCE_BINARY_DIR) + "/bin/ambience");
    for (std::string& w : splitWords(args)) words.push_back(std::move(w));
    return runCommand(std::move(words), "", workDir);
}

inline std::string sourcePath(const std::string& relative) {
    return std::string(AMBIENCE_SOURCE_DIR) + "/" + relative;
}

}  // namespace amb::test
