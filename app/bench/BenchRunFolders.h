// BenchRunFolders.h — the names and folders of `ambience bench`: the replays named by a list,
// the parameters of a point as one line, each run's folder under --out, and a run's outcome read
// back from its folder alone (readRun), whoever ran it.
#pragma once

#include <filesystem>
#include <string>
#include <vector>

#include "app/bench/BenchJobs.h"
#include "app/cli/CliChecks.h"

namespace amb::bench {

// The items of a comma-separated list, blanks around each trimmed, empty ones left out (one
// for every command: app/cli/CliChecks.h).
using amb::splitList;

// The replays a --replays list names (every shipped replay when empty), each with a name of its
// own: two replays of one bench may not share one.
std::vector<ReplayRef> resolveReplays(const std::string& list);

// A JSON object's leaves as "prefix.key=value" joined by ';' (appended to `out`).
void flatten(const json& j, const std::string& prefix, std::string& out);

// A point's parameters as one line: its budget when not 1, then its volume and baseline leaves.
std::string pointParams(const Point& p);

// A run's folder, relative to --out: runs/<replay>__<method>__<point>.
std::string jobDir(const std::string& replay, const std::string& method, const std::string& p);

// True when anything, a dangling link included, is at `path`.
bool somethingAt(const std::filesystem::path& path);

// Creates `path` (a folder the bench writes into) unless it is one already; a symbolic link or
// a file there is refused, so that nothing is written outside the bench's folder.
void makeRealFolder(const std::filesystem::path& path);

// A run's outcome, read back from its folder under `out` alone (kExitStatusFile, report.json,
// log.txt) into `job` (ok, error, report, wall_s).
void readRun(Job& job, const std::string& out);

}  // namespace amb::bench
