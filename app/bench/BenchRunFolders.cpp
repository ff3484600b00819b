// BenchRunFolders.cpp — the names and folders of `ambience bench` (BenchRunFolders.h).
#include <sys/stat.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <sstream>

#include "app/bench/BenchCollect.h"
#include "app/bench/BenchEmit.h"
#include "app/bench/BenchRunFolders.h"
#include "app/cli/Commands.h"
#include "app/cli/OutputPaths.h"
#include "app/cli/RunReport.h"
#include "world/DataPaths.h"
#include "world/Error.h"
#include "world/TextFile.h"

namespace amb::bench {

namespace fs = std::filesystem;

namespace {

// A replay's name is its file's stem made a plain file name (OutputPaths.h safeFileStem): it
// names the run folders and the oracle caches, so two replays of one bench must not share it,
// and its path goes into the emitted command lines, so it must be one line.
ReplayRef replayRef(const fs::path& file, std::vector<ReplayRef>& taken) {
    const std::string path = fs::weakly_canonical(file).string();
    if (hasControlCharacter(path))
        throw InputError("--replays", "the path '" + printable(path) +
                                          "' holds a control character (a newline or tab "
                                          "cannot go into a run's command line): rename it");
    ReplayRef ref{safeFileStem(file.stem().string()), path};
    for (const ReplayRef& other : taken)
        if (other.name == ref.name)
            throw InputError("--replays", "two replays named '" + ref.name + "' (" +
                                              printable(other.path) + " and " +
                                              printable(ref.path) +
                                              "): run folders and oracle caches are named by "
                                              "the replay, so rename one");
    taken.push_back(ref);
    return ref;
}

// The last `count` lines of a run's log, joined by " | " (one line, control characters shown
// as escapes). Only the log's end is read, and only from a regular file in the run's folder.
std::string lastLines(const std::string& path, int count) {
    std::string text;
    try {
        text = readTextFileTail(path, "run log", kLogTailBytes, Links::Refuse);
    } catch (const InputError& e) {
        return std::string("(") + e.what() + ")";
    }
    std::vector<std::string> lines;
    std::stringstream in(text);
    std::string line;
    while (std::getline(in, line)) {
        // Progress output uses carriage returns; keep the text after the last one.
        const auto cr = line.find_last_of('\r');
        if (cr != std::string::npos) line = line.substr(cr + 1);
        // Progress lines come every few seconds: a log's last lines are read without them.
        if (!line.empty() && !isProgressLine(line)) lines.push_back(printable(line));
    }
    std::string out;
    for (std::size_t i = lines.size() > std::size_t(count) ? lines.size() - count : 0;
         i < lines.size(); ++i)
        out += (out.empty() ? "" : " | ") + lines[i];
    return out;
}

// True when `path` is a folder itself, not a link to one (lstat).
bool isRealFolder(const fs::path& path) {
    struct stat st {};
    return ::lstat(path.c_str(), &st) == 0 && S_ISDIR(st.st_mode);
}

}  // namespace

std::vector<ReplayRef> resolveReplays(const std::string& list) {
    std::vector<ReplayRef> out;
    const std::string dir = shippedReplayDir();
    if (list.empty()) {
        if (dir.empty()) throw InputError("--replays", "no shipped replays found; name files");
        std::vector<fs::path> files;
        for (const auto& e : fs::directory_iterator(dir))
            if (e.path().extension() == ".json") files.push_back(e.path());
        std::sort(files.begin(), files.end());
        for (const auto& f : files) replayRef(f, out);
        return out;
    }
    const std::vector<std::string> items = splitList(list);
    if (items.empty()) throw InputError("--replays", "no replay named in '" + list + "'");
    for (const std::string& item : items) {
        fs::path p = item;
        if (p.extension() != ".json")
            p = fs::path(dir.empty() ? "replays" : dir) / (item + ".json");
        if (!fs::exists(p))
            throw InputError("--replays", "no replay '" + printable(item) + "' (looked for " +
                                              printable(p.string()) + ")");
        replayRef(p, out);
    }
    return out;
}

void flatten(const json& j, const std::string& prefix, std::string& out) {
    for (auto it = j.begin(); it != j.end(); ++it) {
        const std::string key = prefix.empty() ? it.key() : prefix + "." + it.key();
        if (it->is_object()) {
            flatten(*it, key, out);
        } else {
            if (!out.empty()) out += ';';
            out += key + "=" + it->dump();
        }
    }
}

std::string pointParams(const Point& p) {
    std::string s;
    if (p.facesPerFrame != 1) s = "facesPerFrame=" + std::to_string(p.facesPerFrame);
    std::string v, b;
    flatten(p.volume, "volume", v);
    flatten(p.baseline, "baseline", b);
    for (const std::string& part : {v, b})
        if (!part.empty()) s += (s.empty() ? "" : ";") + part;
    return s;
}

std::string jobDir(const std::string& replay, const std::string& method, const std::string& p) {
    return "runs/" + replay + "__" + method + "__" + p;
}

// True when anything, a dangling link included, is at `path`.
bool somethingAt(const fs::path& path) {
    struct stat st {};
    return ::lstat(path.c_str(), &st) == 0;
}

// A run's outcome, read back from its folder alone (kExitStatusFile, report.json, log.txt), the
// same way whoever ran it: a local bench just after the run, --from-runs and --collect later.
// The folder may have been in other hands: each file is read as hostile input (BenchCollect.h),
// and whatever is wrong with one is that run's error, not the bench's.
void readRun(Job& job, const std::string& out) {
    const fs::path dir = fs::path(out) / job.runDir;
    job.ok = false;
    job.error.clear();
    job.report = json();
    job.wall_s = std::nan("");
    const fs::path rel = fs::path(job.runDir);
    if (!somethingAt(dir)) {
        job.error = "not run: no " + (rel / kExitStatusFile).string();
        return;
    }
    if (!isRealFolder(fs::path(out) / "runs") || !isRealFolder(dir)) {
        job.error = "not read: " + job.runDir + " is not a folder (a symbolic link is refused)";
        return;
    }
    ExitStatus status;
    bool ended = false;
    if (somethingAt(dir / kExitStatusFile)) {
        try {
            status = parseExitStatus(readTextFile((dir / kExitStatusFile).string(),
                                                  "exit status file", kMaxExitStatusBytes,
                                                  Links::Refuse),
                                     (rel / kExitStatusFile).string());
        } catch (const InputError& e) {
            job.error = std::string("not read: ") + e.what();
            return;
        }
        ended = true;
        if (status.wall_s >= 0.0) job.wall_s = status.wall_s;
    }
    const fs::path report = dir / "report.json";
    // A folder from before the exit status was kept counts as ended when it has its report.
    if (!ended && !somethingAt(report)) {
        job.error = "not run: no " + (rel / kExitStatusFile).string();
        return;
    }
    if (status.code != 0 || !somethingAt(report)) {
        job.error = (status.code > 128 ? "killed by signal " + std::to_string(status.code - 128)
                                       : "exit code " + std::to_string(status.code)) +
                    ": " + lastLines((dir / "log.txt").string(), 2);
        return;
    }
    try {
        job.report = parseRunReport(
            readTextFile(report.string(), "run report", kMaxRunReportBytes, Links::Refuse),
            (rel / "report.json").string());
        job.ok = true;
    } catch (const InputError& e) {
        job.error = std::string("unreadable report: ") + e.what();
    }
}

// Creates `path` (a folder the bench writes into) unless it is one already; a symbolic link or
// a file there is refused, so that nothing is written outside the bench's folder.
void makeRealFolder(const fs::path& path) {
    struct stat st {};
    if (::lstat(path.c_str(), &st) == 0) {
        if (S_ISDIR(st.st_mode)) return;
        throw InputError(path.string(), "is not a folder (a symbolic link or a file): refusing "
                                        "to write through it");
    }
    std::error_code ec;
    fs::create_directory(path, ec);
    if (ec) throw InputError(path.string(), "cannot create the folder (" + ec.message() + ")");
}

}  // namespace amb::bench
