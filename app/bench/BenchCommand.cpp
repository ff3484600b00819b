// BenchCommand.cpp — `ambience bench`: replays x methods x parameter points, speed against error
// (docs/ARCHITECTURE.md "Measuring speed against error").
//
// Each run is a child process `ambience run --no-frames --measure-every K --oracle ...`, so a run
// that fails (or crashes) is recorded with its error and the sweep goes on, and `--jobs` runs
// go side by side. The oracle of a replay does not depend on the method: the first run of each
// replay (the cheapest method) captures it and saves it, the others of that replay wait for it
// and read it back. Outputs in --out: runs/<replay>__<method>__<point>/ (each run's report,
// measurement CSV, log and exit status), oracle/<replay>.json, results.csv (one row per run),
// summary.md (tables), PNG plots from bench-plots.py (matplotlib), and with --tune, tune.csv and
// tuned-volume.json. `--emit DIR` writes the runs as shell command lines for GNU parallel or
// Slurm instead (BenchEmit.h), and `--collect DIR` reads them back: every run's result is read
// from its folder (readRun), whoever ran it.
#include <fcntl.h>
#include <sys/stat.h>
#include <spawn.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cmath>
#include <condition_variable>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <functional>
#include <limits>
#include <map>
#include <mutex>
#include <set>
#include <sstream>
#include <thread>

#include <CLI/CLI.hpp>
#include <nlohmann/json.hpp>

#include "app/bench/BenchCollect.h"
#include "app/bench/BenchEmit.h"
#include "app/bench/BenchStats.h"
#include "app/bench/BenchSweep.h"
#include "app/cli/Commands.h"
#include "app/cli/OutputPaths.h"
#include "app/cli/RunReport.h"
#include "app/frame/MethodStages.h"
#include "app/platform/Platform.h"
#include "lighting/Metrics.h"
#include "world/DataPaths.h"
#include "world/Error.h"
#include "world/TextFile.h"

extern char** environ;

namespace amb {

namespace {

namespace fs = std::filesystem;
using nlohmann::json;

struct ReplayRef {
    std::string name, path;  // path absolute
};

struct BenchOptions {
    std::string replays, methods, sweep, budgets, out = "out/bench";
    std::string oracle = "self";
    int referenceEvery = 6;
    int fullLengthBudget = 3;
    int screenWitnesses = 0;
    int jobs = 0;
    int measureEvery = 10;
    int maxFrames = 0;
    int stride = 2;
    bool frames = false;  // render the main view too (slow on a software rasteriser)
    bool noFrames = false;
    bool tune = false;
    bool fromRuns = false;
    std::string tuneReplays = "highway-drive,mountain-drive,low-flight,stress-flight";
    int tuneRounds = 1;
    int tuneBudget = 1;  // faces per frame: the cost the tuning holds fixed
    double tuneMinGain = 0.002;
    std::string backend = "auto";
    std::string emit;     // --emit DIR: write the runs as command lines, run nothing
    std::string collect;  // --collect DIR: the results of runs emitted there
    // With --collect: the replays as emitted (their files need not be here), and where the
    // runs were read from in the summary.
    std::vector<ReplayRef> resolved;
    std::vector<std::string> emitted;  // the run folders bench.json lists
    bool collected = false;
};

std::vector<std::string> splitList(const std::string& text) {
    std::vector<std::string> out;
    std::stringstream in(text);
    std::string item;
    while (std::getline(in, item, ',')) {
        item.erase(0, item.find_first_not_of(" \t"));
        item.erase(item.find_last_not_of(" \t") + 1);
        if (!item.empty()) out.push_back(item);
    }
    return out;
}

std::string selfExecutable() {
    char exe[4096] = {};
    const ssize_t n = readlink("/proc/self/exe", exe, sizeof(exe) - 1);
    if (n <= 0) throw std::runtime_error("bench: cannot find its own executable");
    return std::string(exe, std::size_t(n));
}

// ---- What to run -----------------------------------------------------------------------------

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

using Point = SweepPoint;  // app/bench/BenchSweep.h

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

// ---- Running ---------------------------------------------------------------------------------

struct Job {
    ReplayRef replay;
    std::string method;
    Point point;
    std::string runDir;  // relative to --out
    bool makesOracle = false;
    // Results.
    bool ok = false;
    std::string error;
    json report;
    double wall_s = 0.0;
};

// Runs argv with stdout and stderr into `log`; returns the exit status (or -signal).
int spawnAndWait(const std::vector<std::string>& args, const std::string& log) {
    // A link planted at the log's name is replaced, never written through.
    struct stat st {};
    if (::lstat(log.c_str(), &st) == 0 && S_ISLNK(st.st_mode)) ::unlink(log.c_str());
    posix_spawn_file_actions_t actions;
    posix_spawn_file_actions_init(&actions);
    posix_spawn_file_actions_addopen(&actions, 1, log.c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0644);
    posix_spawn_file_actions_adddup2(&actions, 1, 2);
    posix_spawn_file_actions_addopen(&actions, 0, "/dev/null", O_RDONLY, 0);
    std::vector<char*> argv;
    for (const auto& a : args) argv.push_back(const_cast<char*>(a.c_str()));
    argv.push_back(nullptr);
    pid_t pid = 0;
    const int rc = posix_spawn(&pid, argv[0], &actions, nullptr, argv.data(), environ);
    posix_spawn_file_actions_destroy(&actions);
    if (rc != 0) return -1000 - rc;
    int status = 0;
    while (waitpid(pid, &status, 0) < 0 && errno == EINTR) {
    }
    if (WIFEXITED(status)) return WEXITSTATUS(status);
    if (WIFSIGNALED(status)) return -WTERMSIG(status);
    return -1;
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

struct Runner {
    std::string exe, out, backend;  // `out` absolute
    int measureEvery = 30, maxFrames = 0, stride = 2;
    bool frames = false;
    // The reference oracle (lighting/ReferenceOracle.h) for every run, and the capture budget
    // whose runs also capture the ideal volume for the error budget (the others report its
    // spacing and schedule terms as one).
    bool reference = false;
    int referenceEvery = 6;
    int idealBudget = 1;
    int screenWitnesses = 0;  // per reference frame, in the runs at idealBudget
    // Runs above this many faces per frame play the first fullLengthBudget / faces of the replay.
    int fullLengthBudget = 64;

    std::string dirOf(const Job& job) const { return (fs::path(out) / job.runDir).string(); }

    // The run's folder with its settings files and command line, without the outcome of an
    // earlier run there.
    void prepare(const Job& job) const {
        const fs::path dir = dirOf(job);
        makeRealFolder(fs::path(out) / "runs");
        makeRealFolder(dir);
        writeTextFile((dir / "volume.json").string(), job.point.volume.dump(2) + "\n",
                      "run's settings file");
        writeTextFile((dir / "baseline.json").string(), job.point.baseline.dump(2) + "\n",
                      "run's settings file");
        writeTextFile((dir / "command.txt").string(), shellCommand(args(job)) + "\n",
                      "run's command line");
        std::error_code ec;
        fs::remove(dir / kExitStatusFile, ec);
        fs::remove(dir / "report.json", ec);
    }

    // `ambience run ...` for the job (absolute paths: the same line runs anywhere).
    std::vector<std::string> args(const Job& job) const {
        const fs::path dir = dirOf(job);
        std::vector<std::string> a = {
            exe,
            "run",
            "--replay",
            job.replay.path,
            "--ambient",
            job.method,
            "--config",
            (dir / "volume.json").string(),
            "--baseline-config",
            (dir / "baseline.json").string(),
            "--faces-per-frame",
            std::to_string(job.point.facesPerFrame),
            "--measure-every",
            std::to_string(measureEvery),
            "--oracle",
            (fs::path(out) / "oracle" / (job.replay.name + ".json")).string(),
            "--stride",
            std::to_string(stride),
            // An oracle left in the folder by other code or another replay is made again.
            "--replace-stale-caches",
            "--backend",
            backend,
            "--out",
            dir.string()};
        if (reference) {
            a.insert(a.end(),
                     {"--oracle-kind", "reference", "--reference",
                      (fs::path(out) / "oracle" / (job.replay.name + "-reference.json")).string(),
                      "--reference-every", std::to_string(referenceEvery)});
            if (job.point.facesPerFrame != idealBudget) {
                a.push_back("--no-ideal-volume");
            } else if (screenWitnesses > 0) {
                a.insert(a.end(), {"--screen-witnesses", std::to_string(screenWitnesses)});
            }
        }
        if (frames) {
            a.insert(a.end(), {"--frames", "none", "--no-video"});
        } else {
            a.push_back("--no-frames");
        }
        if (maxFrames > 0) a.insert(a.end(), {"--max-frames", std::to_string(maxFrames)});
        if (job.point.facesPerFrame > fullLengthBudget) {
            char share[32];
            std::snprintf(share, sizeof(share), "%.6f",
                          double(fullLengthBudget) / double(job.point.facesPerFrame));
            a.insert(a.end(), {"--share", share});
        }
        return a;
    }

    // Runs the job here, records its exit status as an emitted line does, and reads it back.
    void run(Job& job) const {
        try {
            prepare(job);
        } catch (const InputError& e) {
            job.ok = false;
            job.error = std::string("not run: ") + e.what();
            return;
        }
        const fs::path dir = dirOf(job);
        const auto t0 = std::chrono::steady_clock::now();
        const int status = spawnAndWait(args(job), (dir / "log.txt").string());
        const double wall_s =
            std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
        // As a shell reports it: 128 + signal for a killed run, 127 for one that did not start.
        const int code = status <= -1000 ? 127 : status < 0 ? 128 - status : status;
        char text[64];
        std::snprintf(text, sizeof text, "%d %.3f\n", code, wall_s);
        try {
            writeTextFile((dir / kExitStatusFile).string(), text, "exit status file");
        } catch (const InputError&) {
            // readRun reports the run as not run.
        }
        readRun(job, out);
    }
};

// "bench: <replay>/<method>/<point> FAILED: <error>", for a run that failed.
std::string failureLine(const std::string& title, const Job& j) {
    return title + ": " + j.replay.name + "/" + j.method + "/" + j.point.label +
           " FAILED: " + j.error;
}

// Runs the jobs on `workers` threads; jobs of a replay wait for that replay's oracle job. This
// thread shows the progress (ProgressBar: a bar on a terminal, else a line every few seconds)
// and a line for each run that failed.
void runJobs(std::vector<Job>& jobs, const Runner& runner, int workers, const std::string& title) {
    std::mutex mutex;
    std::condition_variable changed;
    std::vector<int> state(jobs.size(), 0);  // 0 waiting, 1 running, 2 done
    std::map<std::string, bool> oracleDone;
    for (const Job& j : jobs) oracleDone[j.replay.name] = true;
    for (const Job& j : jobs)
        if (j.makesOracle) oracleDone[j.replay.name] = false;
    std::size_t done = 0;
    std::string last;                 // the run that ended last
    std::vector<std::string> failed;  // not yet shown
    std::fprintf(stderr, "%s: %zu runs on %d job(s)\n", title.c_str(), jobs.size(), workers);
    ProgressBar bar(int(jobs.size()), title, "run");
    auto worker = [&] {
        for (;;) {
            std::size_t pick = jobs.size();
            {
                std::unique_lock<std::mutex> lock(mutex);
                for (;;) {
                    bool waiting = false;
                    for (std::size_t i = 0; i < jobs.size(); ++i) {
                        if (state[i] != 0) continue;
                        waiting = true;
                        if (jobs[i].makesOracle || oracleDone[jobs[i].replay.name]) {
                            pick = i;
                            break;
                        }
                    }
                    if (pick < jobs.size() || !waiting) break;
                    changed.wait(lock);
                }
                if (pick == jobs.size()) return;
                state[pick] = 1;
            }
            runner.run(jobs[pick]);
            {
                std::lock_guard<std::mutex> lock(mutex);
                state[pick] = 2;
                ++done;
                if (jobs[pick].makesOracle) oracleDone[jobs[pick].replay.name] = true;
                const Job& j = jobs[pick];
                last = j.replay.name + "/" + j.method + "/" + j.point.label;
                if (!j.ok) failed.push_back(failureLine(title, j));
            }
            changed.notify_all();
        }
    };
    std::vector<std::thread> threads;
    for (int w = 0; w < workers; ++w) threads.emplace_back(worker);
    {
        std::unique_lock<std::mutex> lock(mutex);
        for (;;) {
            for (const std::string& f : failed) bar.note(f);
            failed.clear();
            if (done == jobs.size()) break;
            bar.update(int(done), last.empty() ? "" : "last " + last);
            changed.wait_for(lock, std::chrono::milliseconds(200));
        }
        bar.update(int(done), last.empty() ? "" : "last " + last);
    }
    for (auto& t : threads) t.join();
    bar.finish();
}

// ---- Results ---------------------------------------------------------------------------------

// The object at `key` of `j`, or an empty object (a report read back may hold anything).
const json& objectAt(const json& j, const char* key) {
    static const json empty = json::object();
    if (!j.is_object()) return empty;
    const auto it = j.find(key);
    return it != j.end() && it->is_object() ? *it : empty;
}

// The string at `key` of `j`, or `fallback`.
std::string stringAt(const json& j, const char* key, const std::string& fallback) {
    if (!j.is_object()) return fallback;
    const auto it = j.find(key);
    return it != j.end() && it->is_string() ? it->get<std::string>() : fallback;
}

double number(const json& j, std::initializer_list<const char*> path) {
    const json* at = &j;
    for (const char* key : path) {
        if (!at->is_object() || !at->contains(key)) return std::nan("");
        at = &(*at)[key];
    }
    return at->is_number() ? at->get<double>() : std::nan("");
}

const std::vector<std::string> kColumns = {"replay",
                                           "method",
                                           "point",
                                           "params",
                                           "status",
                                           "error_message",
                                           "frames",
                                           "measured_frames",
                                           "error_mean",
                                           "error_p50",
                                           "error_p95",
                                           "error_max",
                                           "error_ring0_mean",
                                           "error_ring1_mean",
                                           "error_ring2_mean",
                                           "error_ring3_mean",
                                           "error_ring0_p95",
                                           "error_ring1_p95",
                                           "error_ring2_p95",
                                           "error_ring3_p95",
                                           "error_ring0_max",
                                           "error_ring1_max",
                                           "error_ring2_max",
                                           "error_ring3_max",
                                           "pop_p99",
                                           "pop_max",
                                           "pop_move_p99",
                                           "pop_move_max",
                                           "ambience_ms_median",
                                           "ambience_ms_p95",
                                           "frame_ms_median",
                                           "frame_ms_p95",
                                           "predict_ms_median",
                                           "predict_ms_p95",
                                           "capture_ms_median",
                                           "capture_ms_p95",
                                           "store_ms_median",
                                           "store_ms_p95",
                                           "interpolate_ms_median",
                                           "interpolate_ms_p95",
                                           "lookup_ms_median",
                                           "lookup_ms_p95",
                                           "share_of_frame",
                                           "faces_per_s",
                                           "faces_captured",
                                           "probes_max",
                                           "probes_end",
                                           "bytes_max",
                                           "bytes_end",
                                           "teleports",
                                           "rejected_probes",
                                           "mean_speed_mps",
                                           "oracle_s",
                                           "oracle",
                                           "self_error_mean",
                                           "budget_witnesses",
                                           "budget_total_rms",
                                           "budget_truncation",
                                           "budget_capture",
                                           "budget_spacing",
                                           "budget_schedule",
                                           "budget_closure",
                                           "car_error_mean",
                                           "tree_base_error_mean",
                                           "tree_crown_error_mean",
                                           "screen_error_mean",
                                           "screen_terrain_error_mean",
                                           "screen_road_error_mean",
                                           "screen_object_error_mean",
                                           "screen_witnesses",
                                           "drawn_error_mean",
                                           "drawn_error_p95",
                                           "drawn_witnesses",
                                           "drawn_under_crown_error_mean",
                                           "drawn_under_crown_witnesses",
                                           "drawn_hidden_witnesses",
                                           "reference_s",
                                           "wall_s",
                                           "run_dir"};

std::map<std::string, std::string> resultRow(const Job& job) {
    std::map<std::string, std::string> row;
    auto put = [&](const std::string& key, double v) {
        if (!std::isfinite(v)) return;
        char text[64];
        std::snprintf(text, sizeof(text), "%.6g", v);
        row[key] = text;
    };
    row["replay"] = job.replay.name;
    row["method"] = job.method;
    row["point"] = job.point.label;
    row["params"] = job.point.params;
    row["status"] = job.ok ? "ok" : "failed";
    row["error_message"] = job.error;
    row["run_dir"] = job.runDir;
    put("wall_s", job.wall_s);
    if (!job.ok) return row;
    const json& r = job.report;
    put("frames", number(r, {"frameCount"}));
    const json m = objectAt(r, "measurement");
    put("measured_frames", number(m, {"measuredFrames"}));
    put("error_mean", number(m, {"error", "mean"}));
    put("error_p50", number(m, {"error", "p50"}));
    put("error_p95", number(m, {"error", "p95"}));
    put("error_max", number(m, {"error", "max"}));
    if (m.contains("errorByRing") && m["errorByRing"].is_array()) {
        for (std::size_t ring = 0; ring < m["errorByRing"].size() && ring < 4; ++ring) {
            const json& e = m["errorByRing"][ring];
            const std::string name = "error_ring" + std::to_string(ring);
            put(name + "_mean", number(e, {"mean"}));
            put(name + "_p95", number(e, {"p95"}));
            put(name + "_max", number(e, {"max"}));
        }
    }
    put("pop_p99", number(m, {"pop", "p99"}));
    put("pop_max", number(m, {"pop", "max"}));
    put("pop_move_p99", number(m, {"pop_move", "p99"}));
    put("pop_move_max", number(m, {"pop_move", "max"}));
    put("mean_speed_mps", number(m, {"meanSpeed_mps"}));
    put("oracle_s", number(m, {"oracle_s"}));
    row["oracle"] = stringAt(m, "oracle", "self");
    if (m.contains("reference")) {
        const json& ref = m["reference"];
        const json& b = objectAt(ref, "budget");
        put("self_error_mean", number(b, {"selfError", "mean"}));
        put("budget_witnesses", number(b, {"count"}));
        put("budget_total_rms", number(b, {"rmsTotal"}));
        for (const char* term : {"truncation", "capture", "spacing", "schedule", "closure"})
            put(std::string("budget_") + term, number(b, {term}));
        for (const char* kind : {"car", "tree_base", "tree_crown"})
            put(std::string(kind) + "_error_mean", number(ref, {"objects", kind, "error", "mean"}));
        put("reference_s", number(ref, {"reference_s"}));
        if (number(ref, {"drawn", "error", "count"}) > 0) {
            put("drawn_error_mean", number(ref, {"drawn", "error", "mean"}));
            put("drawn_error_p95", number(ref, {"drawn", "error", "p95"}));
            put("drawn_witnesses", number(ref, {"drawn", "error", "count"}));
            put("drawn_under_crown_error_mean", number(ref, {"drawn", "underCrown", "mean"}));
            put("drawn_under_crown_witnesses", number(ref, {"drawn", "underCrown", "count"}));
            put("drawn_hidden_witnesses", number(ref, {"drawn", "hidden"}));
        }
        if (number(ref, {"screen", "error", "count"}) > 0) {
            put("screen_error_mean", number(ref, {"screen", "error", "mean"}));
            put("screen_witnesses", number(ref, {"screen", "error", "count"}));
            for (const char* kind : {"terrain", "road", "object"})
                if (number(ref, {"screen", kind, "count"}) > 0)
                    put(std::string("screen_") + kind + "_error_mean",
                        number(ref, {"screen", kind, "mean"}));
        }
    }
    put("ambience_ms_median", number(r, {"ambience", "ambience_ms", "median"}));
    put("ambience_ms_p95", number(r, {"ambience", "ambience_ms", "p95"}));
    put("frame_ms_median", number(r, {"frame_ms", "median"}));
    put("frame_ms_p95", number(r, {"frame_ms", "p95"}));
    for (const char* stage : {"predict", "capture", "store", "interpolate"}) {
        put(std::string(stage) + "_ms_median", number(r, {"stages_ms", stage, "median"}));
        put(std::string(stage) + "_ms_p95", number(r, {"stages_ms", stage, "p95"}));
    }
    put("lookup_ms_median", number(r, {"ambience", "lookup_ms", "median"}));
    put("lookup_ms_p95", number(r, {"ambience", "lookup_ms", "p95"}));
    put("share_of_frame", number(r, {"ambience", "shareOfFrameTime"}));
    put("faces_per_s", number(r, {"ambience", "facesPerSecond"}));
    put("faces_captured", number(r, {"ambience", "facesCaptured"}));
    put("probes_max", number(r, {"ambience", "anchorsMax"}));
    put("probes_end", number(r, {"ambience", "anchorsEnd"}));
    put("bytes_max", number(r, {"ambience", "bytesMax"}));
    put("bytes_end", number(r, {"ambience", "bytesEnd"}));
    put("teleports", number(r, {"ambience", "teleports"}));
    put("rejected_probes", number(r, {"ambience", "rejectedProbes"}));
    return row;
}

// A CSV field on one line: quoted when it holds a comma or a quote, control characters (a
// newline from a report read back) as spaces.
std::string csvField(const std::string& s) {
    if (s.find_first_of(",\"") == std::string::npos && !hasControlCharacter(s)) return s;
    std::string q = "\"";
    for (char c : s) {
        if (c == '"')
            q += "\"\"";
        else
            q += hasControlCharacter(std::string(1, c)) ? ' ' : c;
    }
    return q + "\"";
}

void writeResultsCsv(const std::vector<Job>& jobs, const std::string& path) {
    std::ostringstream out;
    for (std::size_t c = 0; c < kColumns.size(); ++c) out << (c ? "," : "") << kColumns[c];
    out << "\n";
    for (const Job& job : jobs) {
        const auto row = resultRow(job);
        for (std::size_t c = 0; c < kColumns.size(); ++c) {
            const auto it = row.find(kColumns[c]);
            out << (c ? "," : "") << (it == row.end() ? "" : csvField(it->second));
        }
        out << "\n";
    }
    writeTextFile(path, out.str(), "results");
}

std::string fmt(double v, const char* format) {
    if (!std::isfinite(v)) return "—";
    char text[64];
    std::snprintf(text, sizeof(text), format, v);
    return text;
}

// With --budgets: per replay, each method's mean error and ambience ms at each budget (the
// default point's family), ours against the best other method at that budget, and the Pareto
// front over every run of the replay (no other run both cheaper and more accurate).
// The headline error of a run over its measured frames up to `lastFrame`, from the run's CSV:
// the terrain witnesses of reference.csv with the reference oracle, else measure.csv's
// per-frame means (every measured frame has the same witnesses). NaN without data.
double errorUpTo(const std::string& dir, const Job& j, int lastFrame) {
    const bool reference =
        stringAt(objectAt(j.report, "measurement"), "oracle", "") == "reference";
    std::stringstream in;
    try {
        in.str(readTextFile(
            (fs::path(dir) / j.runDir / (reference ? "reference.csv" : "measure.csv")).string(),
            "measurement file", kMaxOracleFileBytes, Links::Refuse));
    } catch (const InputError&) {
        return std::nan("");
    }
    std::string line;
    if (!std::getline(in, line)) return std::nan("");
    double sum = 0.0;
    std::size_t count = 0;
    while (std::getline(in, line)) {
        std::vector<std::string> f;
        std::stringstream ss(line);
        for (std::string cell; std::getline(ss, cell, ',');) f.push_back(cell);
        if (f.size() < 6) continue;
        if (std::atoi(f[0].c_str()) > lastFrame) continue;
        if (reference && f[1].rfind("ring_", 0) != 0) continue;  // objects are not headline
        const double e = std::atof(f[reference ? 5 : 4].c_str());
        if (std::isfinite(e)) sum += e, ++count;
    }
    return count ? sum / double(count) : std::nan("");
}

// Our run against another of the same replay: the ratio of mean errors over the frames both
// measured, with its paired bootstrap 95 % interval (BenchStats.h).
// With `drawn`, the terrain witnesses' errors at the drawn normal (reference runs only).
RatioInterval ratioAgainst(const std::string& dir, const Job& ours, const Job& other,
                           bool drawn = false) {
    const bool reference =
        stringAt(objectAt(ours.report, "measurement"), "oracle", "") == "reference";
    const auto errors = [&](const Job& j) {
        return readFrameErrors((fs::path(dir) / j.runDir).string(), reference, drawn);
    };
    return pairedBootstrapRatio(errors(ours), errors(other));
}

void writeBudgetSection(std::ostream& out, const std::vector<Job>& jobs,
                        const std::vector<std::string>& replays, int fullLengthBudget,
                        const std::string& dir) {
    std::vector<int> budgets;
    std::vector<std::string> methods;
    for (const Job& j : jobs) {
        if (j.point.family.empty()) return;  // no --budgets
        if (std::find(budgets.begin(), budgets.end(), j.point.facesPerFrame) == budgets.end())
            budgets.push_back(j.point.facesPerFrame);
        if (std::find(methods.begin(), methods.end(), j.method) == methods.end())
            methods.push_back(j.method);
    }
    std::sort(budgets.begin(), budgets.end());
    auto errorOf = [](const Job& j) {
        return number(objectAt(j.report, "measurement"), {"error", "mean"});
    };
    auto msOf = [](const Job& j) { return number(j.report, {"ambience", "ambience_ms", "median"}); };
    out << "## Budget: error against cost\n\n";
    out << "Each cell: mean error / ambience ms per frame (median), default settings at each "
           "capture budget (faces per frame). Ours / best other = our mean error over the "
           "lowest of the other methods' at that budget, over the frames both measured, with "
           "its paired bootstrap 95 % interval. Runs above "
        << fullLengthBudget
        << " faces per frame play the first (" << fullLengthBudget
        << " / faces) of each replay, every method alike.\n\n";
    for (const std::string& replay : replays) {
        out << "### " << replay << "\n\n| faces per frame |";
        for (const auto& m : methods) out << " " << (m == "volume" ? "**volume (ours)**" : m) << " |";
        out << " ours / best other |\n|---|";
        for (std::size_t i = 0; i <= methods.size(); ++i) out << "---|";
        out << "\n";
        for (int b : budgets) {
            out << "| " << b << " |";
            double best = std::nan("");
            const Job *oursJob = nullptr, *bestJob = nullptr;
            for (const auto& m : methods) {
                const Job* found = nullptr;
                for (const Job& j : jobs)
                    if (j.replay.name == replay && j.method == m && j.point.family == "default" &&
                        j.point.facesPerFrame == b && j.ok)
                        found = &j;
                if (!found) {
                    out << " — |";
                    continue;
                }
                const double e = errorOf(*found);
                out << " " << fmt(e, "%.4f") << " / " << fmt(msOf(*found), "%.2f") << " |";
                if (m == "volume") oursJob = found;
                else if (std::isfinite(e) && !(e >= best)) best = e, bestJob = found;
            }
            out << " **"
                << (oursJob && bestJob ? formatRatio(ratioAgainst(dir, *oursJob, *bestJob)) : "—")
                << "** |\n";
        }
        // Runs above the full-length budget play a share of the replay: every run is also
        // measured over the frames all of them play, and the Pareto front is taken on that.
        int common = std::numeric_limits<int>::max();
        std::vector<const Job*> runs;
        for (const Job& j : jobs)
            if (j.replay.name == replay && j.ok && std::isfinite(msOf(j))) {
                runs.push_back(&j);
                common = std::min(common, int(number(j.report, {"frameCount"})) - 1);
            }
        std::map<const Job*, double> prefix;
        for (const Job* j : runs) prefix[j] = errorUpTo(dir, *j, common);
        out << "\nOver the frames every budget plays (0 to " << common
            << "), mean error: ";
        for (int b : budgets) {
            out << (b == budgets.front() ? "" : "; ") << b << " faces:";
            for (const auto& m : methods)
                for (const Job* j : runs)
                    if (j->method == m && j->point.family == "default" &&
                        j->point.facesPerFrame == b)
                        out << " " << (m == "volume" ? "**ours**" : m) << " "
                            << fmt(prefix[j], "%.3f");
        }
        std::vector<const Job*> front;
        for (const Job* a : runs) {
            if (!std::isfinite(prefix[a])) continue;
            bool dominated = false;
            for (const Job* b : runs) {
                if (!std::isfinite(prefix[b])) continue;
                const bool noWorse = msOf(*b) <= msOf(*a) && prefix[b] <= prefix[a];
                const bool better = msOf(*b) < msOf(*a) || prefix[b] < prefix[a];
                if (b != a && noWorse && better) dominated = true;
            }
            if (!dominated) front.push_back(a);
        }
        std::sort(front.begin(), front.end(),
                  [&](const Job* a, const Job* b) { return msOf(*a) < msOf(*b); });
        out << "\n\nPareto front over those frames (cheapest first): ";
        for (std::size_t i = 0; i < front.size(); ++i)
            out << (i ? ", " : "") << front[i]->method << " " << front[i]->point.label << " ("
                << fmt(prefix[front[i]], "%.3f") << " at " << fmt(msOf(*front[i]), "%.2f")
                << " ms)";
        out << "\n\n";
    }
}

// With the reference oracle: per replay, the error budget of each method at the default point
// of the ideal budget (RMS over the terrain witnesses of the reference frames), the errors on
// objects, and the pop along the car.
void writeErrorBudgetSection(std::ostream& out, const std::vector<Job>& jobs,
                             const std::vector<std::string>& replays, int idealBudget) {
    bool any = false;
    for (const Job& j : jobs)
        any |= j.ok && objectAt(j.report, "measurement").contains("reference");
    if (!any) return;
    out << "## Error budget against the reference oracle\n\n"
           "RMS over the terrain witnesses of the reference frames, each term relative to the "
           "reference irradiance (lighting/ReferenceOracle.h): **a** SH order-2 truncation, "
           "**b** capture resolution and scene simplification (16 x 16 coarse capture against "
           "the 64 x 64 full scene), **c** spacing and interpolation (an ideal volume of fresh "
           "captures at the lattice points the method reads, against a capture at the point), "
           "**d** scheduling, staleness and blending (the method against its ideal volume). "
           "Closure = (a² + b² + c² + d²) / total²: 1 when the terms add up as squares. Methods "
           "without a lattice show c + d in column d. Objects: mean error against the reference "
           "at the car (1 m above its ground point) and at tree bases and crowns within 6-48 m. "
           "Screen: the screen-weighted mean error, at random pixels of the main view (terrain, "
           "road, plants and the car), of the ambient irradiance as the draw applies it against "
           "the reference at that surface point and normal (terrain / road / object means in "
           "brackets). Pop moving: along the car.\n\n";
    for (const std::string& replay : replays) {
        out << "### " << replay << "\n\n| method | total (RMS) | a truncation | b capture | "
               "c spacing | d schedule | closure | dominant | mean error | self-oracle error | "
               "car | tree base | tree crown | screen (terrain / road / object) | "
               "pop moving p99 / max |\n"
               "|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|\n";
        for (const Job& j : jobs) {
            if (j.replay.name != replay || !j.ok) continue;
            if (j.point.family.empty() && j.point.label != "default") continue;
            if (!j.point.family.empty() &&
                (j.point.family != "default" || j.point.facesPerFrame != idealBudget))
                continue;
            const json m = objectAt(j.report, "measurement");
            if (!m.contains("reference")) continue;
            const json& ref = m["reference"];
            const json b = objectAt(ref, "budget");
            const double terms[4] = {number(b, {"truncation"}), number(b, {"capture"}),
                                     number(b, {"spacing"}), number(b, {"schedule"})};
            const char* names[4] = {"a", "b", "c", "d"};
            int dominant = 0;
            for (int t = 1; t < 4; ++t)
                if (std::isfinite(terms[t]) && !(terms[t] <= terms[dominant])) dominant = t;
            out << "| " << (j.method == "volume" ? "**volume (ours)**" : j.method) << " | "
                << fmt(number(b, {"rmsTotal"}), "%.4f");
            for (double t : terms) out << " | " << fmt(t, "%.4f");
            out << " | " << fmt(number(b, {"closure"}), "%.2f") << " | " << names[dominant]
                << " | " << fmt(number(b, {"error", "mean"}), "%.4f") << " | "
                << fmt(number(b, {"selfError", "mean"}), "%.4f");
            for (const char* kind : {"car", "tree_base", "tree_crown"})
                out << " | " << fmt(number(ref, {"objects", kind, "error", "mean"}), "%.3f");
            const auto screenMean = [&](const char* kind) {
                return number(ref, {"screen", kind, "count"}) > 0
                           ? number(ref, {"screen", kind, "mean"})
                           : std::nan("");
            };
            out << " | " << fmt(screenMean("error"), "%.3f") << " ("
                << fmt(screenMean("terrain"), "%.2f") << " / " << fmt(screenMean("road"), "%.2f")
                << " / " << fmt(screenMean("object"), "%.2f") << ")";
            out << " | " << fmt(number(m, {"pop_move", "p99"}), "%.4f") << " / "
                << fmt(number(m, {"pop_move", "max"}), "%.3f") << " |\n";
        }
        out << "\n";
    }
    out << "Plot: `error-budget.png` (squared terms stacked, per replay and method).\n\n";
}

void writeSummary(const std::vector<Job>& jobs, const std::string& path,
                  const std::string& commandLine, const std::string& timing,
                  const std::string& oracle, int idealBudget, int fullLengthBudget) {
    std::ostringstream out;
    const std::string dir = fs::path(path).parent_path().string();
    out << "# Ambience bench: speed against error\n\n";
    out << "Command: `" << commandLine << "`  \n";
    out << timing << " **Oracle: " << oracle
        << (oracle == "reference"
                ? "** (the full scene at 64 x 64, irradiance straight from the cube map, on every "
                  "reference frame; lighting/ReferenceOracle.h)."
                : "** (the methods' own 16 x 16 coarse capture at the point, projected to order-2 "
                  "SH: it leaves out capture resolution, scene simplification and SH truncation).")
        << " Error = relative L2 distance of the applied irradiance from the oracle's over the "
           "sphere of normals, luminance-weighted, at the witness points "
           "(the camera's ground point and terrain patch corners in rings of 16-48, 48-144 and "
           "144-432 m). Pop = per-frame change of applied irradiance at fixed points less the "
           "oracle's own change; pop moving = along the camera's ground point (the car on "
           "drives), the per-frame change less the previous frame's (lighting/Metrics.h). "
           "Ambience ms = stages predict + capture + store + interpolate "
           "and the lookups, per frame (median). All methods have the same capture budget.\n\n";
    std::vector<std::string> replays;
    for (const Job& j : jobs)
        if (std::find(replays.begin(), replays.end(), j.replay.name) == replays.end())
            replays.push_back(j.replay.name);
    // Headline: default point, per replay.
    for (const std::string& replay : replays) {
        out << "## " << replay << "\n\n";
        const bool drawn = oracle == "reference";
        if (drawn && replay == replays.front())
            out << "Error at the drawn normal: the terrain witnesses as the screen shows them, "
                   "the ambient the draw applies there (the drawn patch's corners, each at its "
                   "normal, interpolated across the patch) against the reference irradiance at "
                   "that surface point and its normal (lighting/Metrics.h ReferenceWitness); "
                   "witnesses under tree crowns are in the mean and also shown alone; those on "
                   "ground a bush, rock or trunk hides are left out. Sphere: the same "
                   "witnesses' error over the whole sphere of normals.\n\n";
        out << "| method | point | " << (drawn ? "error at the drawn normal (terrain) | " : "")
            << (drawn ? "sphere " : "")
            << "mean error | p95 error | max error | p99 pop | max pop | "
               "p99 pop moving | max pop moving | ambience ms (median) | faces/s | "
               "probes (max) | kB (max) |\n";
        out << (drawn ? "|---" : "") << "|---|---|---|---|---|---|---|---|---|---|---|---|---|\n";
        const Job* ours = nullptr;
        std::vector<const Job*> others;
        for (const Job& j : jobs) {
            if (j.replay.name != replay) continue;
            if (!j.ok) {
                out << "| " << j.method << " | " << j.point.label
                    << " | failed: " << j.error.substr(0, 120) << " | | | | | | | | | |\n";
                continue;
            }
            const json& r = j.report;
            const json m = objectAt(r, "measurement");
            const double e = number(m, {"error", "mean"});
            if (j.point.label == "default" && j.method == "volume") ours = &j;
            if (j.point.label == "default" && j.method != "volume") others.push_back(&j);
            out << "| " << (j.method == "volume" ? "**volume (ours)**" : j.method) << " | "
                << j.point.label << " | ";
            if (drawn) {
                const auto d = [&](const char* a, const char* b) {
                    return number(m, {"reference", "drawn", a, b});
                };
                out << "**" << fmt(d("error", "mean"), "%.4f") << "** (under crowns "
                    << fmt(d("underCrown", "mean"), "%.3f") << ", "
                    << fmt(d("underCrown", "count"), "%.0f") << " of "
                    << fmt(d("error", "count"), "%.0f") << ") | ";
            }
            out << fmt(e, "%.4f") << " | "
                << fmt(number(m, {"error", "p95"}), "%.4f") << " | "
                << fmt(number(m, {"error", "max"}), "%.3f") << " | "
                << fmt(number(m, {"pop", "p99"}), "%.5f") << " | "
                << fmt(number(m, {"pop", "max"}), "%.3f") << " | "
                << fmt(number(m, {"pop_move", "p99"}), "%.5f") << " | "
                << fmt(number(m, {"pop_move", "max"}), "%.3f") << " | "
                << fmt(number(r, {"ambience", "ambience_ms", "median"}), "%.2f") << " | "
                << fmt(number(r, {"ambience", "facesPerSecond"}), "%.1f") << " | "
                << fmt(number(r, {"ambience", "anchorsMax"}), "%.0f") << " | "
                << fmt(number(r, {"ambience", "bytesMax"}) / 1024.0, "%.1f") << " |\n";
        }
        if (ours && !others.empty()) {
            // The drawn normal's ratio first (the headline) with the reference, then the
            // sphere's.
            for (const bool atDrawn : drawn ? std::vector<bool>{true, false}
                                            : std::vector<bool>{false}) {
                out << "\nOur mean error" << (atDrawn ? " at the drawn normal" : drawn ? " over the sphere of normals" : "")
                    << " / each other method's (default points), over the frames both "
                       "measured, with the paired bootstrap 95 % interval (blocks of "
                       "consecutive measured frames resampled; app/bench/BenchStats.h):";
                int frames = 0;
                for (const Job* other : others) {
                    const RatioInterval r = ratioAgainst(dir, *ours, *other, atDrawn);
                    frames = std::max(frames, r.frames);
                    out << (other == others.front() ? " " : "; ") << other->method << " **"
                        << formatRatio(r) << "**" << (r.excludesOne() ? "" : " (interval holds 1)");
                }
                out << " (" << frames << " frames).\n";
            }
            out << "\n";
        } else {
            out << "\n";
        }
    }
    // Stress: every replay (the fast flight with its cut, the time-lapse, the far flight), for
    // every method: finite error, memory held, teleports and rejected probes.
    out << "## Stress and memory (default point)\n\n";
    out << "| replay | method | frames | teleports | rejected probes | probes (max) | kB (max) | "
           "max error | finite |\n";
    out << "|---|---|---|---|---|---|---|---|---|\n";
    for (const Job& j : jobs) {
        if (j.point.label != "default" || !j.ok) continue;
        const json& r = j.report;
        const double maxError = number(r, {"measurement", "error", "max"});
        out << "| " << j.replay.name << " | " << j.method << " | "
            << fmt(number(r, {"frameCount"}), "%.0f") << " | "
            << fmt(number(r, {"ambience", "teleports"}), "%.0f") << " | "
            << fmt(number(r, {"ambience", "rejectedProbes"}), "%.0f") << " | "
            << fmt(number(r, {"ambience", "anchorsMax"}), "%.0f") << " | "
            << fmt(number(r, {"ambience", "bytesMax"}) / 1024.0, "%.1f") << " | "
            << fmt(maxError, "%.3f") << " | " << (std::isfinite(maxError) ? "yes" : "**NO**")
            << " |\n";
    }
    out << "\n";
    writeBudgetSection(out, jobs, replays, fullLengthBudget, fs::path(path).parent_path().string());
    writeErrorBudgetSection(out, jobs, replays, idealBudget);
    out << "## Plots\n\n";
    for (const std::string& replay : replays)
        out << "- `pareto-" << replay << ".png`, `error-over-time-" << replay << ".png`\n";
    out << "- `error-vs-speed.png`, `error-by-ring.png`\n\n";
    out << "Each run's report, measurement CSV, log and exact command line are in `runs/`.\n";
    writeTextFile(path, out.str(), "summary");
}

void drawPlots(const std::string& out) {
    // Beside the executable in the build tree, in P/share/ambience when installed (DataPaths.h).
    const fs::path script = findDataFile("bench-plots.py");
    if (script.empty()) {
        std::fprintf(stderr, "plots skipped: bench-plots.py found neither beside the executable "
                             "nor in its installed data folder\n");
        return;
    }
    // Debian's Python (the one python3-matplotlib installs into), else the first on PATH.
    const std::string python = fs::exists("/usr/bin/python3") ? "/usr/bin/python3" : "python3";
    if (spawnAndWait({"/usr/bin/env", python, "-c", "import matplotlib"}, "/dev/null") != 0) {
        std::fprintf(stderr,
                     "plots skipped: python3 with matplotlib is missing (Debian: apt-get install "
                     "python3-matplotlib); results.csv and summary.md are written\n");
        return;
    }
    const int rc = spawnAndWait({"/usr/bin/env", python, script.string(), out},
                                (fs::path(out) / "plots.log").string());
    if (rc != 0)
        std::fprintf(stderr, "plots failed (exit %d), see %s/plots.log\n", rc, out.c_str());
    else
        std::fprintf(stderr, "plots written (see %s/plots.log)\n", out.c_str());
}

std::string jobDir(const std::string& replay, const std::string& method, const std::string& p) {
    return "runs/" + replay + "__" + method + "__" + p;
}

// ---- Tuning ----------------------------------------------------------------------------------

// Coordinate descent over the scheduler's, the store's and the near field's main parameters, for
// the volume at the default capture budget: each parameter in turn tries the values around the current best,
// keeping a change only when the mean error over the tuning replays falls.
struct TuneParameter {
    std::vector<std::string> path;  // into the volume settings JSON
    double start;
    std::vector<double> factors;
    bool integer;
};

json withValue(json base, const std::vector<std::string>& path, double value, bool integer) {
    json* at = &base;
    for (std::size_t i = 0; i + 1 < path.size(); ++i) {
        if (!at->contains(path[i])) (*at)[path[i]] = json::object();
        at = &(*at)[path[i]];
    }
    if (integer)
        (*at)[path.back()] = int(std::lround(value));
    else
        (*at)[path.back()] = value;
    return base;
}

double valueAt(const json& j, const std::vector<std::string>& path, double fallback) {
    const json* at = &j;
    for (const auto& k : path) {
        if (!at->is_object() || !at->contains(k)) return fallback;
        at = &(*at)[k];
    }
    return at->is_number() ? at->get<double>() : fallback;
}

void tune(const BenchOptions& o, const Runner& runner, int workers) {
    const auto replays = resolveReplays(o.tuneReplays);
    const AmbienceVolumeSettings d;
    const std::vector<TuneParameter> parameters = {
        {{"scheduler", "horizon_s"}, d.scheduler.horizon_s, {0.5, 2.0}, false},
        {{"scheduler", "corridorCells"}, d.scheduler.corridorCells, {0.5, 2.0}, false},
        {{"store", "blendTime_s"}, d.store.blendTime_s, {0.5, 2.0}, false},
        {{"scheduler", "finestRingCells"}, d.scheduler.finestRingCells, {0.5, 2.0}, false},
        {{"scheduler", "coarseRingCells"}, d.scheduler.coarseRingCells, {0.5, 2.0}, false},
        {{"store", "reachCells"}, double(d.store.reachCells), {2.0, 3.0}, true},
        // The two scales (lighting/NearField.h): what probes leave out, what points put back.
        {{"nearField", "captureRadius_m"}, d.capture.nearField.captureRadius_m, {0.75, 1.5}, false},
        {{"nearField", "radius_m"}, d.capture.nearField.radius_m, {0.75, 1.5}, false},
    };
    struct Candidate {
        std::string label;
        json volume;
        std::vector<double> errors;  // per replay
        double ms = 0.0, mean = 0.0;
    };
    std::vector<Candidate> tried;
    // Written as the tuning goes; a link planted at its name is replaced, not written through.
    const std::string tuneCsv = (fs::path(o.out) / "tune.csv").string();
    struct stat st {};
    if (::lstat(tuneCsv.c_str(), &st) == 0 && S_ISLNK(st.st_mode)) ::unlink(tuneCsv.c_str());
    std::ofstream log(tuneCsv);
    log << "round,candidate,params,replay,mean_error,p95_error,pop_p99,ambience_ms_median,status\n";
    auto evaluate = [&](const json& volume, const std::string& label, int round) {
        std::vector<Job> jobs;
        for (const auto& r : replays) {
            Job j;
            j.replay = r;
            j.method = "volume";
            j.point.label = label;
            j.point.volume = volume;
            j.point.facesPerFrame = o.tuneBudget;
            j.point.params = pointParams(j.point);
            j.runDir = "tune/" + label + "__" + r.name;
            j.makesOracle = !fs::exists(fs::path(o.out) / "oracle" / (r.name + ".json"));
            jobs.push_back(j);
        }
        runJobs(jobs, runner, workers, "tune " + label);
        Candidate c{label, volume, {}, 0.0, 0.0};
        std::string params;
        flatten(volume, "volume", params);
        for (const Job& j : jobs) {
            const double e =
                j.ok ? number(j.report, {"measurement", "error", "mean"}) : std::nan("");
            const double ms = j.ok ? number(j.report, {"ambience", "ambience_ms", "median"}) : 0;
            c.errors.push_back(std::isfinite(e) ? e : std::numeric_limits<double>::infinity());
            c.mean += c.errors.back() / double(jobs.size());
            c.ms += ms / double(jobs.size());
            log << round << "," << label << "," << csvField(params) << "," << j.replay.name << ","
                << e << "," << number(j.report, {"measurement", "error", "p95"}) << ","
                << number(j.report, {"measurement", "pop", "p99"}) << "," << ms << ","
                << (j.ok ? "ok" : csvField("failed: " + j.error)) << "\n";
        }
        log << round << "," << label << "," << csvField(params) << ",(mean)," << c.mean << ",,,"
            << c.ms << ",\n";
        log.flush();
        tried.push_back(c);
        return c;
    };
    Candidate best = evaluate(json::object(), "t0", 0);
    std::fprintf(stderr, "tune: defaults give mean error %.4f\n", best.mean);
    int candidate = 0;
    for (int round = 1; round <= o.tuneRounds; ++round) {
        for (const TuneParameter& p : parameters) {
            const double current = valueAt(best.volume, p.path, p.start);
            for (double f : p.factors) {
                const double value =
                    p.integer ? std::max(1.0, std::round(current * f)) : current * f;
                if (value == current) continue;
                const Candidate c = evaluate(withValue(best.volume, p.path, value, p.integer),
                                             "t" + std::to_string(++candidate), round);
                std::fprintf(stderr, "tune: %s = %g -> mean error %.4f (best %.4f)\n",
                             p.path.back().c_str(), value, c.mean, best.mean);
                // A change must lower the mean error by a margin: smaller gains are within what
                // the witness sampling resolves, and they may cost lookups (wider search).
                if (c.mean < best.mean - o.tuneMinGain) best = c;
            }
        }
    }
    const std::string file = (fs::path(o.out) / "tuned-volume.json").string();
    writeTextFile(file, best.volume.dump(2) + "\n", "tuned settings");
    std::printf(
        "tuned settings %s: mean error %.4f over %s (defaults %.4f), budget %d face(s) "
        "per frame, ambience %.2f ms/frame: %s\n",
        best.label.c_str(), best.mean, o.tuneReplays.c_str(), tried.front().mean, o.tuneBudget,
        best.ms, file.c_str());
    // The best candidate for each replay on its own.
    for (std::size_t r = 0; r < replays.size(); ++r) {
        const Candidate* b = &tried.front();
        for (const Candidate& c : tried)
            if (c.errors[r] < b->errors[r]) b = &c;
        const std::string f = (fs::path(o.out) / ("tuned-" + replays[r].name + ".json")).string();
        writeTextFile(f, b->volume.dump(2) + "\n", "tuned settings");
        std::printf("  %s: best %s, mean error %.4f (defaults %.4f): %s\n", replays[r].name.c_str(),
                    b->label.c_str(), b->errors[r], tried.front().errors[r], f.c_str());
    }
    std::printf("  use with: ambience run --config %s\n", file.c_str());
}

// ---- The command -----------------------------------------------------------------------------

// How each run is started (the options every child gets), after checking those options.
Runner benchRunner(const BenchOptions& o, const std::vector<Point>& points) {
    Runner runner;
    runner.exe = selfExecutable();
    runner.out = fs::absolute(o.out).lexically_normal().string();
    runner.backend = o.backend;
    runner.measureEvery = o.measureEvery;
    runner.maxFrames = o.maxFrames;
    runner.stride = o.stride;
    runner.frames = o.frames;
    runner.reference = parseOracleKind(o.oracle, "--oracle") == OracleKind::Reference;
    if (o.referenceEvery < 1 || o.referenceEvery > 1000000)
        throw InputError("--reference-every", "expected 1 to 1000000");
    runner.referenceEvery = o.referenceEvery;
    if (o.fullLengthBudget < 1 || o.fullLengthBudget > kMaxFacesPerFrame)
        throw InputError("--full-length-budget",
                         "expected 1 to " + std::to_string(kMaxFacesPerFrame));
    runner.fullLengthBudget = o.fullLengthBudget;
    if (o.screenWitnesses < 0 || o.screenWitnesses > 4096)
        throw InputError("--screen-witnesses", "expected 0 to 4096");
    if (o.screenWitnesses > 0 && !runner.reference)
        throw InputError("--screen-witnesses", "needs --oracle reference");
    runner.screenWitnesses = o.screenWitnesses;
    runner.idealBudget = points.empty() ? 1 : points.front().facesPerFrame;
    for (const Point& p : points) runner.idealBudget = std::min(runner.idealBudget, p.facesPerFrame);
    return runner;
}

// The runs: replays x methods x points, per replay the cheapest method first (it captures the
// oracle unless a saved one matches), every replay's oracle run at the front.
std::vector<Job> benchJobs(const std::vector<ReplayRef>& replays,
                           const std::vector<std::string>& methods,
                           const std::vector<Point>& points) {
    std::vector<Job> jobs;
    const std::vector<std::string> cheapFirst = {"constant", "hemisphere"};
    for (const auto& r : replays) {
        std::vector<std::string> order = methods;
        std::stable_sort(order.begin(), order.end(), [&](const auto& a, const auto& b) {
            auto rank = [&](const std::string& m) {
                return int(std::find(cheapFirst.begin(), cheapFirst.end(), m) - cheapFirst.begin());
            };
            return rank(a) < rank(b);
        });
        bool first = true;
        for (const auto& m : order)
            for (const Point& p : points) {
                if (!p.methods.empty() && !p.methods.count(m)) continue;
                Job j;
                j.replay = r;
                j.method = m;
                j.point = p;
                j.point.params = pointParams(p);
                j.runDir = jobDir(r.name, m, p.label);
                j.makesOracle = first;
                first = false;
                jobs.push_back(j);
            }
    }
    // Put every replay's oracle job at the front, so the replays' oracles are made in parallel.
    std::stable_partition(jobs.begin(), jobs.end(), [](const Job& j) { return j.makesOracle; });
    return jobs;
}

// --emit: each run's folder and settings, its command line (commands.txt, jobs.txt, slurm.sh,
// README.txt: BenchEmit.h) and bench.json, the sweep for --collect. The oracle runs (one per
// replay, at the front of `jobs`) are the first stage: their lines come first, and in jobs.txt
// the others wait for their replay's one, as a local bench's runs do. (An oracle per run would
// need no waiting, but capture the same oracle once per run: most of a cheap method's time.)
void emitBench(const BenchOptions& o, const std::vector<Job>& jobs, const Runner& runner,
               const std::vector<ReplayRef>& replays, const std::vector<std::string>& methods,
               const std::string& commandLine) {
    std::map<std::string, std::string> oracleRun;  // replay -> its oracle run's folder
    int firstStage = 0;
    for (const Job& j : jobs)
        if (j.makesOracle) oracleRun[j.replay.name] = runner.dirOf(j), ++firstStage;
    std::vector<EmittedRun> runs;
    BenchManifest manifest;
    for (const Job& j : jobs) {
        runner.prepare(j);
        runs.push_back(
            {runner.args(j), runner.dirOf(j), j.makesOracle ? "" : oracleRun[j.replay.name]});
        manifest.runs.push_back(j.runDir);
    }
    const std::string dir = runner.out;
    writeJobFiles(dir, runs, firstStage, runner.exe);
    // The sweep file is copied in, so the collector needs nothing outside the folder.
    const fs::path sweepCopy = fs::path(dir) / "sweep.json";
    std::error_code ec;
    if (!o.sweep.empty() && !fs::equivalent(o.sweep, sweepCopy, ec))
        writeTextFile(sweepCopy.string(),
                      readTextFile(o.sweep, "sweep file", kMaxSettingsFileBytes), "sweep copy");
    manifest.command = commandLine;
    for (const ReplayRef& r : replays) manifest.replays.push_back({r.name, r.path});
    for (const auto& m : methods) manifest.methods += (manifest.methods.empty() ? "" : ",") + m;
    manifest.sweep = o.sweep.empty() ? "" : "sweep.json";
    manifest.budgets = o.budgets;
    manifest.oracle = o.oracle;
    manifest.referenceEvery = o.referenceEvery;
    manifest.fullLengthBudget = o.fullLengthBudget;
    manifest.screenWitnesses = o.screenWitnesses;
    manifest.measureEvery = o.measureEvery;
    manifest.maxFrames = o.maxFrames;
    manifest.stride = o.stride;
    manifest.frames = o.frames;
    manifest.backend = o.backend;
    writeTextFile((fs::path(dir) / "bench.json").string(),
                  benchManifestJson(manifest).dump(2) + "\n", "bench.json");
    const auto q = [&](const char* file) { return shellQuote((fs::path(dir) / file).string()); };
    std::printf("bench: %zu runs emitted into %s (the first %d make the oracles)\n", jobs.size(),
                dir.c_str(), firstStage);
    std::printf("  here:           parallel --will-cite --jobs N < %s\n", q("jobs.txt").c_str());
    std::printf("  over machines:  parallel --will-cite --jobs N --sshloginfile hosts.txt < %s\n",
                q("jobs.txt").c_str());
    std::printf("  Slurm:          sbatch --array=0-%zu %s\n", jobs.size() - 1,
                q("slurm.sh").c_str());
    std::printf("  then:           %s bench --collect %s   (%s says more)\n",
                shellQuote(runner.exe).c_str(), shellQuote(dir).c_str(), q("README.txt").c_str());
}

// --collect DIR: the bench options as --emit saved them in DIR/bench.json.
BenchOptions readManifest(const std::string& dir, std::string& commandLine) {
    const std::string path = (fs::path(dir) / "bench.json").string();
    if (!somethingAt(path))
        throw InputError("--collect", "no bench.json in '" + printable(dir) +
                                          "' (write one with --emit DIR)");
    const BenchManifest m = parseBenchManifest(
        readTextFile(path, "bench.json", kMaxBenchManifestBytes, Links::Refuse), path);
    BenchOptions o;
    commandLine = m.command;
    for (const auto& r : m.replays) o.resolved.push_back({r.name, r.path});
    o.methods = m.methods;
    o.sweep = m.sweep.empty() ? "" : (fs::path(dir) / m.sweep).string();
    o.budgets = m.budgets;
    o.oracle = m.oracle;
    o.referenceEvery = m.referenceEvery;
    o.fullLengthBudget = m.fullLengthBudget;
    o.screenWitnesses = m.screenWitnesses;
    o.measureEvery = m.measureEvery;
    o.maxFrames = m.maxFrames;
    o.stride = m.stride;
    o.frames = m.frames;
    o.backend = m.backend;
    o.emitted = m.runs;
    o.out = dir;
    o.fromRuns = true;
    o.collected = true;
    return o;
}

// Results keep the order replay x method x point.
void sortForResults(std::vector<Job>& jobs, const std::vector<ReplayRef>& replays,
                    const std::vector<std::string>& methods) {
    std::stable_sort(jobs.begin(), jobs.end(), [&](const Job& a, const Job& b) {
        auto ri = [&](const Job& j) {
            for (std::size_t i = 0; i < replays.size(); ++i)
                if (replays[i].name == j.replay.name) return i;
            return replays.size();
        };
        auto mi = [&](const Job& j) {
            return std::find(methods.begin(), methods.end(), j.method) - methods.begin();
        };
        return std::make_pair(ri(a), mi(a)) < std::make_pair(ri(b), mi(b));
    });
}

void checkOptions(const BenchOptions& o) {
    if (o.jobs < 0 || o.jobs > 64) throw InputError("--jobs", "expected 0 (cores) to 64");
    if (o.measureEvery < 1) throw InputError("--measure-every", "must be at least 1");
    if (o.maxFrames < 0) throw InputError("--max-frames", "must be >= 0");
    if (o.stride < 1) throw InputError("--stride", "must be at least 1");
    if (o.frames && o.noFrames) throw InputError("--frames", "conflicts with --no-frames");
    if (o.tuneRounds < 1 || o.tuneRounds > 5) throw InputError("--tune-rounds", "expected 1 to 5");
    if (o.tuneBudget < 1 || o.tuneBudget > 6) throw InputError("--tune-budget", "expected 1 to 6");
    if (!(o.tuneMinGain >= 0.0 && o.tuneMinGain < 1.0))
        throw InputError("--tune-min-gain", "expected 0 to 1");
    if (!o.emit.empty() && o.tune)
        throw InputError("--emit",
                         "--tune picks each candidate from the last: it cannot be emitted");
    if (!o.emit.empty() && o.fromRuns) throw InputError("--emit", "conflicts with --from-runs");
}

// The checks `run` makes of its files, for the bench's own: no output is an input (the sweep, a
// replay), and each can be written (not a folder; a link at an output's name is replaced by the
// file, never written through: writeTextFile).
void checkBenchFiles(const BenchOptions& o, const std::vector<ReplayRef>& replays,
                     const std::string& folderOption) {
    FilePlan plan;
    if (!o.collected) {
        plan.input("--sweep", o.sweep);
        for (const ReplayRef& r : replays) plan.input("--replays", r.path);
    }
    const auto output = [&](const char* file) {
        plan.replacedOutput(folderOption + " (" + file + ")",
                            (fs::path(o.out) / file).string());
    };
    if (!o.emit.empty()) {
        for (const char* file :
             {"commands.txt", "jobs.txt", "slurm.sh", "README.txt", "bench.json"})
            output(file);
        std::error_code ec;
        if (!o.sweep.empty() && !fs::equivalent(o.sweep, fs::path(o.out) / "sweep.json", ec))
            output("sweep.json");
    } else if (!o.tune) {
        for (const char* file : {"results.csv", "summary.md", "plots.log"}) output(file);
    }
    plan.check();
}

void runBench(const BenchOptions& o, const std::string& commandLine) {
    checkOptions(o);
    std::vector<std::string> methods =
        o.methods.empty() ? ambienceMethodNames() : splitList(o.methods);
    if (methods.empty()) throw InputError("--methods", "no method named in '" + o.methods + "'");
    for (const auto& m : methods) checkAmbienceMethod(m, "--methods");
    if (parseBackend(o.backend, "--backend") == Backend::Glfw)
        throw InputError("--backend", "bench runs headless: auto, egl or osmesa");
    // The bench's folder, named by the option that gave it.
    const std::string folderOption =
        o.collected ? "--collect" : !o.emit.empty() ? "--emit" : "--out";
    auto points = readSweep(o.sweep, ambienceMethodNames(),
                            o.collected ? Links::Refuse : Links::Follow);
    if (!o.budgets.empty())
        points = withBudgets(points, parseBudgets(o.budgets, "--budgets"), "--budgets");
    const int workers = o.jobs > 0 ? o.jobs : std::max(1, int(std::thread::hardware_concurrency()));
    std::error_code ec;
    fs::create_directories(o.out, ec);
    if (ec || !fs::is_directory(o.out) || access(o.out.c_str(), W_OK | X_OK) != 0)
        throw InputError(folderOption,
                         "cannot create or write the folder '" + printable(o.out) + "'");
    makeRealFolder(fs::path(o.out) / "oracle");
    makeRealFolder(fs::path(o.out) / "runs");

    Runner runner = benchRunner(o, points);
    const auto start = std::chrono::steady_clock::now();
    if (o.tune) {
        tune(o, runner, workers);
        return;
    }
    const auto replays = o.resolved.empty() ? resolveReplays(o.replays) : o.resolved;
    checkBenchFiles(o, replays, folderOption);

    std::vector<Job> jobs = benchJobs(replays, methods, points);
    if (!o.emit.empty()) {
        emitBench(o, jobs, runner, replays, methods, commandLine);
        return;
    }
    if (o.collected) {
        std::vector<std::string> dirs;
        for (const Job& j : jobs) dirs.push_back(j.runDir);
        if (dirs != o.emitted)
            throw InputError((fs::path(o.out) / "bench.json").string(),
                             "its sweep no longer gives the runs it emitted");
    }
    // One path for the results: every run is read back from its folder (readRun), whether it ran
    // here just now or earlier (--from-runs), or was emitted and ran elsewhere (--collect).
    if (o.fromRuns) {
        for (Job& j : jobs) {
            readRun(j, runner.out);
            if (!j.ok) std::fprintf(stderr, "%s\n", failureLine("bench", j).c_str());
        }
    } else {
        runJobs(jobs, runner, workers, "bench");
    }
    const double wall =
        std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    double runTime_s = 0.0;
    for (const Job& j : jobs)
        if (std::isfinite(j.wall_s)) runTime_s += j.wall_s;
    char timing[200];
    if (o.fromRuns)
        std::snprintf(timing, sizeof(timing),
                      "Runs read back from their folders (%s): %.1f min of run time in all.",
                      o.collected ? "emitted, run elsewhere, --collect" : "--from-runs",
                      runTime_s / 60.0);
    else
        std::snprintf(timing, sizeof(timing), "Wall time %.1f min on %d job(s).", wall / 60.0,
                      workers);

    sortForResults(jobs, replays, methods);
    const std::string results = (fs::path(o.out) / "results.csv").string();
    writeResultsCsv(jobs, results);
    writeSummary(jobs, (fs::path(o.out) / "summary.md").string(), commandLine, timing, o.oracle,
                 runner.idealBudget, runner.fullLengthBudget);
    drawPlots(o.out);
    int failed = 0;
    for (const Job& j : jobs) failed += !j.ok;
    if (o.fromRuns)
        std::printf("bench: %zu runs (%d failed) read from %s\n", jobs.size(), failed,
                    o.out.c_str());
    else
        std::printf("bench: %zu runs (%d failed) in %.1f min on %d job(s)\n", jobs.size(), failed,
                    wall / 60.0, workers);
    std::printf("  results: %s\n  summary: %s\n", results.c_str(),
                (fs::path(o.out) / "summary.md").string().c_str());
    // A sweep goes on past a failed run, but a bench in which nothing ran is a failure.
    if (!jobs.empty() && failed == int(jobs.size()))
        throw RunFailure("bench: every run failed (see error_message in " + results + ")");
}

}  // namespace

void addBenchCommand(CLI::App& app) {
    auto* cmd = app.add_subcommand(
        "bench", "replays x methods x parameter points: error against an oracle, pop and cost");
    auto o = std::make_shared<BenchOptions>();
    cmd->add_option("--replays", o->replays,
                    "comma-separated replay names or files (default: every shipped replay)");
    cmd->add_option("--methods", o->methods,
                    "comma-separated methods (default: all): " + ambienceMethodHelp());
    cmd->add_option("--sweep", o->sweep,
                    "JSON parameter points: {\"points\": [{\"label\", \"methods\", \"volume\", "
                    "\"baseline\", \"facesPerFrame\"}]}");
    cmd->add_option("--budgets", o->budgets,
                    "comma-separated capture budgets, faces per frame (1 to 64): every point runs "
                    "at each, and summary.md gets error against cost per budget and the Pareto "
                    "front");
    cmd->add_option("--oracle", o->oracle,
                    "self (the methods' own coarse capture, fast: for tuning) or reference (the "
                    "full scene at 64 x 64 on every --reference-every-th measured frame, with the "
                    "error budget and errors on objects) (default self)");
    cmd->add_option("--reference-every", o->referenceEvery,
                    "with --oracle reference: a reference on every K-th measured frame "
                    "(default 6)");
    cmd->add_option("--full-length-budget", o->fullLengthBudget,
                    "runs above B faces per frame play the first B / faces of each replay, all "
                    "methods alike (their cost grows with the budget) (default 3)");
    cmd->add_option("--screen-witnesses", o->screenWitnesses,
                    "with --oracle reference: random pixels of the main view per reference frame "
                    "compared with the reference, in the runs at the lowest budget (opt-in, "
                    "slow; default 0)");
    cmd->add_option("--jobs", o->jobs, "runs side by side (default: the number of cores)");
    cmd->add_option("--out", o->out, "output folder (default out/bench)");
    cmd->add_option("--measure-every", o->measureEvery,
                    "measure every K-th frame against the oracle (default 10: 3 times a second)");
    cmd->add_option("--max-frames", o->maxFrames, "stop each run after N frames (default: all)");
    cmd->add_option("--stride", o->stride, "replay steps per frame (default 2: 30 frames/s)");
    cmd->add_flag("--frames", o->frames,
                  "render the main view too (slow; the error does not depend on it)");
    cmd->add_flag("--no-frames", o->noFrames,
                  "do not render the main view (the default; captures still render)");
    cmd->add_flag("--from-runs", o->fromRuns,
                  "run nothing: rewrite results.csv, summary.md and the plots from the runs "
                  "already in --out (same --replays, --methods, --sweep and --budgets)");
    cmd->add_flag("--tune", o->tune,
                  "coordinate descent over the volume's scheduler and store parameters at the "
                  "default budget; writes tune.csv and tuned-volume.json");
    cmd->add_option("--tune-replays", o->tuneReplays,
                    "replays the tuning averages over (default highway-drive,mountain-drive,"
                    "low-flight,stress-flight)");
    cmd->add_option("--tune-rounds", o->tuneRounds, "passes over the parameters (default 1)");
    cmd->add_option("--tune-min-gain", o->tuneMinGain,
                    "smallest fall of the mean error a change must bring (default 0.002)");
    cmd->add_option("--tune-budget", o->tuneBudget,
                    "capture budget held fixed while tuning, faces per frame (default 1)");
    cmd->add_option("--backend", o->backend, "auto, egl or osmesa (default auto)");
    auto* out = cmd->get_option("--out");
    cmd->add_option("--emit", o->emit,
                    "run nothing: write each run as one shell command line into DIR "
                    "(commands.txt, jobs.txt for GNU parallel, slurm.sh, README.txt) for "
                    "--collect DIR; replaces --out")
        ->excludes(out);
    cmd->add_option("--collect", o->collect,
                    "run nothing: results.csv, summary.md and the plots of runs --emit wrote "
                    "into DIR (the sweep comes from DIR/bench.json: no other option)");
    cmd->callback([o, cmd] {
        std::string line = "ambience bench";
        for (const auto* opt : cmd->get_options()) {
            if (opt->count() == 0 || opt->get_name() == "--help") continue;
            // An empty folder or list means nothing sensible (`--collect ''` would otherwise
            // run the default bench), and every value may end up in an emitted command line.
            if (opt->get_type_size() != 0) {
                for (const std::string& value : opt->results()) {
                    if (value.empty())
                        throw InputError(opt->get_name(), "an empty value (name what it means)");
                    if (hasControlCharacter(value))
                        throw InputError(opt->get_name(),
                                         "'" + printable(value) +
                                             "' holds a control character (a newline or tab "
                                             "cannot go into a command line)");
                }
            }
            if (!o->collect.empty() && opt->get_name() != "--collect")
                throw InputError("--collect",
                                 "takes the sweep from DIR/bench.json: give no "
                                 "other option (" +
                                     opt->get_name() + ")");
            line += " " + opt->get_name();
            if (opt->get_type_size() != 0) line += " " + shellQuote(opt->as<std::string>());
        }
        if (!o->collect.empty()) {
            std::string emitted;
            runBench(readManifest(o->collect, emitted), emitted);
            return;
        }
        if (!o->emit.empty()) o->out = o->emit;
        runBench(*o, line);
    });
}

}  // namespace amb
