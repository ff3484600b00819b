// BenchRunner.cpp — running `ambience bench`'s jobs (BenchRunner.h).
#include <fcntl.h>
#include <spawn.h>
#include <sys/stat.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <chrono>
#include <condition_variable>
#include <cstdio>
#include <filesystem>
#include <map>
#include <mutex>
#include <thread>

#include "app/bench/BenchEmit.h"
#include "app/bench/BenchRunFolders.h"
#include "app/bench/BenchRunner.h"
#include "app/cli/ReferenceLightFlags.h"
#include "app/cli/RunReport.h"
#include "app/frame/MethodStages.h"
#include "lighting/BounceField.h"
#include "lighting/Metrics.h"
#include "world/Error.h"
#include "world/TextFile.h"

extern char** environ;

namespace amb::bench {

namespace fs = std::filesystem;

namespace {

std::string selfExecutable() {
    char exe[4096] = {};
    const ssize_t n = readlink("/proc/self/exe", exe, sizeof(exe) - 1);
    if (n <= 0) throw std::runtime_error("bench: cannot find its own executable");
    return std::string(exe, std::size_t(n));
}

}  // namespace

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

std::string Runner::dirOf(const Job& job) const { return (fs::path(out) / job.runDir).string(); }

// The run's folder with its settings files and command line, without the outcome of an
// earlier run there.
void Runner::prepare(const Job& job) const {
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
std::vector<std::string> Runner::args(const Job& job) const {
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
                  "--reference-every", std::to_string(referenceEvery), "--reference-light",
                  referenceLight});
        if (referenceLight == "bounce") {
            char spacing[32], reach[32];
            std::snprintf(spacing, sizeof spacing, "%g", bounceSpacing_m);
            std::snprintf(reach, sizeof reach, "%g", bounceReach_m);
            a.insert(a.end(), {"--bounce-spacing", spacing, "--bounce-reach", reach,
                               "--bounce-face", std::to_string(bounceFace)});
            // Always given: `run`'s own default is two layers, so 0 must be said.
            char canopy[32];
            std::snprintf(canopy, sizeof canopy, "%g", bounceCanopy_m);
            a.insert(a.end(), {"--bounce-canopy", canopy});
        }
        if (captureLight != "own") a.insert(a.end(), {"--capture-light", captureLight});
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
void Runner::run(Job& job) const {
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
    if (o.screenWitnesses < -1 || o.screenWitnesses > 4096)
        throw InputError("--screen-witnesses", "expected 0 to 4096");
    if (o.screenWitnesses > 0 && !runner.reference)
        throw InputError("--screen-witnesses", "needs --oracle reference");
    runner.screenWitnesses =
        o.screenWitnesses >= 0 ? o.screenWitnesses : (runner.reference ? kDefaultScreenWitnesses : 0);
    parseReferenceLight(o.referenceLight, "--reference-light");
    runner.referenceLight = o.referenceLight;
    checkBounceSettings(o.bounce);
    runner.bounceSpacing_m = o.bounce.spacing_m;
    runner.bounceReach_m = o.bounce.reach_m;
    runner.bounceFace = o.bounce.faceSize;
    runner.bounceCanopy_m = o.bounce.canopy_m;
    if (!isCaptureLight(o.captureLight))
        throw InputError("--capture-light", "expected own or reference");
    if (o.captureLight == "reference" && (!runner.reference || o.referenceLight != "bounce"))
        throw InputError("--capture-light",
                         "reference needs --oracle reference with --reference-light bounce");
    runner.captureLight = o.captureLight;
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

}  // namespace amb::bench
