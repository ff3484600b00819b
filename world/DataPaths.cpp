// DataPaths.cpp — the data-folder lookup (DataPaths.h).
#include "world/DataPaths.h"

#include <climits>
#include <filesystem>
#include <system_error>

#include <unistd.h>

// The installed data folder relative to the installed executable's folder; CMake sets it from
// CMAKE_INSTALL_BINDIR and CMAKE_INSTALL_DATADIR (root CMakeLists.txt).
#ifndef AMBIENCE_DATA_FROM_BIN
#define AMBIENCE_DATA_FROM_BIN "../share/ambience"
#endif

namespace fs = std::filesystem;

namespace amb {

namespace {

// `p` without "." and ".." steps and without a trailing separator ("/a/b/.." -> "/a").
fs::path normalised(const fs::path& p) {
    fs::path n = p.lexically_normal();
    if (n.filename().empty() && n.has_parent_path() && n != n.root_path()) n = n.parent_path();
    return n;
}

}  // namespace

std::string installedDataFromBin() { return AMBIENCE_DATA_FROM_BIN; }

std::string executableDirectory() {
    char exe[PATH_MAX] = {};
    const ssize_t n = readlink("/proc/self/exe", exe, sizeof(exe) - 1);
    if (n <= 0) return "";
    return fs::path(std::string(exe, std::size_t(n))).parent_path().string();
}

std::vector<std::string> dataFolders(const std::string& exeDirectory) {
    if (exeDirectory.empty()) return {};
    const fs::path exe(exeDirectory);
    std::vector<std::string> out;
    for (const fs::path& p : {exe / installedDataFromBin(), exe, exe / "..", exe / "../.."})
        out.push_back(normalised(p).string());
    return out;
}

std::string findDataFileFrom(const std::string& exeDirectory, const std::string& relative) {
    for (const std::string& folder : dataFolders(exeDirectory)) {
        const fs::path candidate = normalised(fs::path(folder) / relative);
        std::error_code ec;
        if (fs::exists(candidate, ec)) return candidate.string();
    }
    return "";
}

std::string findDataFile(const std::string& relative) {
    return findDataFileFrom(executableDirectory(), relative);
}

}  // namespace amb
