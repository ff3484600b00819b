// BenchCommand.cpp — `ambience bench`: replays x methods x parameter points, speed against error
// (docs/ARCHITECTURE.md "Measuring speed against error").
//
// Each run is a child process `ambience run --no-frames --measure-every K --oracle ...`, so a run
// that fails (or crashes) is recorded with its error and the sweep goes on, and `--jobs` runs
// go side by side. The oracle of a replay does not depend on the method: the first run of each
// replay (the cheapest method) captures it and saves it, the others of that replay wait for it
// and read it back. Outputs in --out: runs/<replay>__<method>__<point>/ (each run's report,
// measurement CSV, log and exit status), oracle/<replay>.json, results.csv (one row per run),
// summary.md (tables) and PNG plots from bench-plots.py (matplotlib). `--emit DIR` writes the runs as shell command lines for GNU parallel or
// Slurm instead (BenchEmit.h), and `--collect DIR` reads them back: every run's result is read
// from its folder (readRun), whoever ran it.
//
// The command line, --emit and --collect here; the jobs (BenchJobs.h), their names and folders
// (BenchRunFolders.h), running them (BenchRunner.h) and the results (BenchResults.h) in files of
// their own. Tuning is `ambience tune` (TuneCommand.cpp).
#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <map>
#include <thread>

#include <CLI/CLI.hpp>
#include <nlohmann/json.hpp>

#include "app/bench/BenchCollect.h"
#include "app/bench/BenchEmit.h"
#include "app/bench/BenchJobs.h"
#include "app/bench/BenchResults.h"
#include "app/bench/BenchRunFolders.h"
#include "app/bench/BenchRunner.h"
#include "app/bench/BenchSweep.h"
#include "app/cli/Commands.h"
#include "app/cli/OutputPaths.h"
#include "app/cli/ReferenceLightFlags.h"
#include "app/frame/MethodStages.h"
#include "app/platform/Platform.h"
#include "world/Error.h"
#include "world/TextFile.h"

namespace amb {

namespace {

namespace fs = std::filesystem;
using namespace bench;

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
    manifest.screenWitnesses = runner.screenWitnesses;
    manifest.referenceLight = o.referenceLight;
    manifest.captureLight = o.captureLight;
    manifest.bounceSpacing_m = o.bounce.spacing_m;
    manifest.bounceReach_m = o.bounce.reach_m;
    manifest.bounceFace = o.bounce.faceSize;
    manifest.bounceCanopy_m = o.bounce.canopy_m;
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
    o.referenceLight = m.referenceLight;
    o.captureLight = m.captureLight;
    o.bounce.spacing_m = m.bounceSpacing_m;
    o.bounce.reach_m = m.bounceReach_m;
    o.bounce.faceSize = m.bounceFace;
    o.bounce.canopy_m = m.bounceCanopy_m;
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
    if (o.tune)
        throw InputError("--tune",
                         "the coordinate descent is gone: `ambience tune` runs a study of error "
                         "against cost (docs/TUNING.md \"Tuning with Optuna\")");
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
    } else {
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
                    "compared with the reference, in the runs at the lowest budget (default " +
                        std::to_string(kDefaultScreenWitnesses) +
                        " with the reference, 0 to leave them out)");
    // With --oracle reference: what lights the reference's surfaces (as `run`'s options; the
    // bench's lattice is 256 m within 500 m of each run's path, BounceSettings' defaults).
    addReferenceLightOptions(*cmd, o->referenceLight, o->bounce);
    addCaptureLightOption(*cmd, o->captureLight);
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
    // Kept only to point whoever still types it to `ambience tune`.
    cmd->add_flag("--tune", o->tune, "removed: see `ambience tune`")->group("");
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
            // A flag (CLI11 gives it one item and no expected count) stands alone.
            if (opt->get_expected_min() != 0) line += " " + shellQuote(opt->as<std::string>());
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
