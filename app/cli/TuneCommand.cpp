// TuneCommand.cpp — `ambience tune`: a multi-objective Optuna study of the volume's settings
// (docs/TUNING.md "Tuning with Optuna"). Two objectives, both minimised over the tuning replays:
// the mean error against the oracle and the ambience's milliseconds a frame. Each trial runs
// `ambience run` children with the command lines `ambience bench` gives its runs.
//
// This command checks every option (a bad one is one line naming it, exit code 2), then hands
// over to scripts/ambience-tune.py (Debian's python3-optuna; found beside the executable in the
// build tree, in P/share/ambience when installed: world/DataPaths.h), which runs the study and
// writes the outputs. The parameters and their ranges come from the settings schema
// (lighting/SettingsSchema.h, which the script reads as `ambience settings --json`).
#include <unistd.h>

#include <algorithm>
#include <cctype>
#include <cerrno>
#include <cmath>
#include <cstring>
#include <filesystem>
#include <memory>
#include <set>
#include <sstream>
#include <string>
#include <vector>

#include <CLI/CLI.hpp>

#include "app/cli/CliChecks.h"
#include "app/cli/Commands.h"
#include "app/platform/Platform.h"
#include "lighting/JsonFields.h"
#include "lighting/Metrics.h"
#include "lighting/SettingsSchema.h"
#include "world/DataPaths.h"
#include "world/Error.h"

namespace amb {

namespace {

namespace fs = std::filesystem;

// The study's default parameters: the keys the coordinate descent it replaced (`bench --tune`,
// removed) stepped over.
const char* const kDefaultParams =
    "scheduler.horizon_s,scheduler.corridorCells,store.blendTime_s,scheduler.finestRingCells,"
    "scheduler.coarseRingCells,store.reachCells,nearField.captureRadius_m,nearField.radius_m";
const char* const kDefaultReplays = "highway-drive,mountain-drive,low-flight,stress-flight";
const char* const kDefaultEvalReplays = "dusk-mountain-held-out,hairpin-flight-held-out";

struct TuneOptions {
    std::string params = kDefaultParams;
    std::string replays = kDefaultReplays;
    std::string evalReplays = kDefaultEvalReplays;
    std::string oracle = "reference";
    std::string out = "out/tune";
    std::string storage;  // default: sqlite in --out
    std::string study = "ambience";
    std::string sampler = "tpe";
    std::string backend = "auto";
    int trials = 40;
    int jobs = 1;
    int maxFrames = 600;
    int evalMaxFrames = -1;  // default: --max-frames
    int seed = -1;           // default: none (each worker draws its own)
    bool noEval = false;
};

bool heldOut(const std::string& replay) {
    const std::string stem = fs::path(replay).stem().string();
    const std::string tag = "-held-out";
    return stem.size() >= tag.size() && stem.compare(stem.size() - tag.size(), tag.size(), tag) == 0;
}

// A list of replays (names of shipped ones or .json files), each found; their stems.
std::vector<std::string> checkReplays(const std::string& list, const char* option) {
    const std::vector<std::string> items = splitList(list);
    if (items.empty()) throw InputError(option, "no replay named in '" + list + "'");
    const std::string dir = shippedReplayDir();
    std::vector<std::string> stems;
    for (const std::string& item : items) {
        fs::path p = item;
        if (p.extension() != ".json") p = fs::path(dir.empty() ? "replays" : dir) / (item + ".json");
        std::error_code ec;
        if (!fs::is_regular_file(p, ec))
            throw InputError(option, "no replay '" + item + "' (looked for " + p.string() + ")");
        const std::string stem = p.stem().string();
        if (std::find(stems.begin(), stems.end(), stem) != stems.end())
            throw InputError(option, "'" + stem + "' named twice");
        stems.push_back(stem);
    }
    return stems;
}

// `KEY` or `KEY=LO:HI` (a narrower range than the schema's), each a key of the volume's file.
void checkParams(const std::string& list) {
    const std::vector<std::string> items = splitList(list);
    if (items.empty()) throw InputError("--params", "no key named in '" + list + "'");
    std::set<std::string> seen;
    const auto& schema = volumeSettingsSchema();
    for (const std::string& item : items) {
        const std::size_t eq = item.find('=');
        const std::string key = item.substr(0, eq);
        const auto* f = schema.find(key);
        if (!f)
            throw InputError("--params", "unknown setting '" + key +
                                             "' (`ambience settings` lists the volume's keys)");
        if (!seen.insert(key).second) throw InputError("--params", "'" + key + "' named twice");
        if (key == "facesPerFrame")
            throw InputError("--params", "'facesPerFrame' is the capture budget the study holds "
                                         "fixed");
        if (eq == std::string::npos) continue;
        if (f->kind == SettingSpec::Kind::Boolean)
            throw InputError("--params", "'" + key + "' is a switch: it takes no range");
        const std::string range = item.substr(eq + 1);
        const std::size_t colon = range.find(':');
        double lo = 0.0, hi = 0.0;
        std::size_t used = 0;
        bool ok = colon != std::string::npos;
        try {
            if (ok) {
                lo = std::stod(range.substr(0, colon), &used);
                ok = used == colon;
            }
            if (ok) {
                hi = std::stod(range.substr(colon + 1), &used);
                ok = used == range.size() - colon - 1;
            }
        } catch (const std::exception&) {
            ok = false;
        }
        if (!ok || !std::isfinite(lo) || !std::isfinite(hi))
            throw InputError("--params", "'" + item + "': expected KEY or KEY=LO:HI");
        if (!(lo < hi))
            throw InputError("--params", "'" + item + "': LO must be below HI");
        if (lo < f->lo || hi > f->hi)
            throw InputError("--params", "'" + item + "': outside the key's range [" +
                                             jsonNumber(f->lo) + ", " + jsonNumber(f->hi) + "]");
        if (f->kind == SettingSpec::Kind::Integer &&
            (lo != std::floor(lo) || hi != std::floor(hi)))
            throw InputError("--params", "'" + item + "': '" + key + "' takes whole numbers");
    }
}

void checkOptions(const TuneOptions& o) {
    checkParams(o.params);
    const auto tuning = checkReplays(o.replays, "--replays");
    for (const std::string& r : tuning)
        if (heldOut(r))
            throw InputError("--replays", "'" + r + "' is held out of tuning (give it to "
                                                    "--eval-replays)");
    const auto eval = checkReplays(o.evalReplays, "--eval-replays");
    for (const std::string& r : eval)
        if (std::find(tuning.begin(), tuning.end(), r) != tuning.end())
            throw InputError("--eval-replays",
                             "'" + r + "' is a tuning replay too: evaluation replays are apart");
    parseOracleKind(o.oracle, "--oracle");
    if (parseBackend(o.backend, "--backend") == Backend::Glfw)
        throw InputError("--backend", "tune runs headless: auto, egl or osmesa");
    if (o.sampler != "tpe" && o.sampler != "nsga2")
        throw InputError("--sampler", "expected tpe or nsga2, got '" + o.sampler + "'");
    if (o.trials < 0 || o.trials > 100000) throw InputError("--trials", "expected 0 to 100000");
    if (o.jobs < 1 || o.jobs > 64) throw InputError("--jobs", "expected 1 to 64");
    if (o.maxFrames < 1) throw InputError("--max-frames", "must be at least 1");
    if (o.evalMaxFrames == 0 || o.evalMaxFrames < -1)
        throw InputError("--eval-max-frames", "must be at least 1");
    if (o.seed < -1) throw InputError("--seed", "must be 0 or more");
    for (char c : o.study)
        if (!(std::isalnum(static_cast<unsigned char>(c)) || c == '-' || c == '_' || c == '.'))
            throw InputError("--study", "'" + o.study + "': letters, digits, '-', '_' and '.' only");
    std::error_code ec;
    fs::create_directories(o.out, ec);
    if (ec || !fs::is_directory(o.out) || access(o.out.c_str(), W_OK | X_OK) != 0)
        throw InputError("--out", "cannot create or write the folder '" + o.out + "'");
}

// Debian's Python (the one python3-optuna installs into), else the first on PATH.
std::string python() { return access("/usr/bin/python3", X_OK) == 0 ? "/usr/bin/python3" : "python3"; }

// `o` as the study's summary shows its command: the options given, as typed.
[[noreturn]] void runTune(const TuneOptions& o, const std::string& commandLine) {
    checkOptions(o);
    const std::string script = findDataFile("ambience-tune.py");
    if (script.empty())
        throw RunFailure("tune: ambience-tune.py found neither beside the executable nor in its "
                         "installed data folder");
    char self[4096] = {};
    const ssize_t n = readlink("/proc/self/exe", self, sizeof(self) - 1);
    if (n <= 0) throw RunFailure("tune: cannot find its own executable");
    const std::string exe(self, std::size_t(n));
    std::vector<std::string> args = {python(),
                                     script,
                                     "--ambience",
                                     exe,
                                     "--params",
                                     o.params,
                                     "--replays",
                                     o.replays,
                                     "--eval-replays",
                                     o.evalReplays,
                                     "--oracle",
                                     o.oracle,
                                     "--out",
                                     fs::absolute(o.out).lexically_normal().string(),
                                     "--study",
                                     o.study,
                                     "--sampler",
                                     o.sampler,
                                     "--backend",
                                     o.backend,
                                     "--trials",
                                     std::to_string(o.trials),
                                     "--jobs",
                                     std::to_string(o.jobs),
                                     "--max-frames",
                                     std::to_string(o.maxFrames),
                                     "--eval-max-frames",
                                     std::to_string(o.evalMaxFrames > 0 ? o.evalMaxFrames
                                                                        : o.maxFrames)};
    if (!o.storage.empty()) args.insert(args.end(), {"--storage", o.storage});
    if (o.seed >= 0) args.insert(args.end(), {"--seed", std::to_string(o.seed)});
    if (o.noEval) args.push_back("--no-eval");
    args.insert(args.end(), {"--command", commandLine});
    std::vector<char*> argv;
    for (std::string& a : args) argv.push_back(a.data());
    argv.push_back(nullptr);
    std::fflush(stdout);
    std::fflush(stderr);
    ::execvp(argv[0], argv.data());
    throw RunFailure(std::string("tune: cannot start ") + argv[0] + ": " + std::strerror(errno) +
                     " (Debian: apt-get install python3-optuna python3-sklearn)");
}

}  // namespace

void addTuneCommand(CLI::App& app) {
    auto* cmd = app.add_subcommand(
        "tune", "a multi-objective Optuna study of the volume's settings: error and ambience ms "
                "a frame, the Pareto front as settings files, re-measured on held-out replays");
    auto o = std::make_shared<TuneOptions>();
    cmd->add_option("--params", o->params,
                    "comma-separated keys of the volume's settings file to tune, each KEY (the "
                    "schema's range) or KEY=LO:HI (narrower) (default: the keys the removed "
                    "coordinate descent stepped over)");
    cmd->add_option("--replays", o->replays,
                    std::string("tuning replays, names or files (default ") + kDefaultReplays +
                        "; never the held-out ones)");
    cmd->add_option("--eval-replays", o->evalReplays,
                    std::string("replays the front and the defaults are measured on again after "
                                "the study (default ") +
                        kDefaultEvalReplays + ")");
    cmd->add_option("--oracle", o->oracle,
                    "reference (the error at the drawn normal against the full-scene oracle, the "
                    "default) or self (the coarse self-oracle: quick studies)");
    cmd->add_option("--trials", o->trials,
                    "trials this command adds to the study (default 40; 0: only write the "
                    "outputs)");
    cmd->add_option("--jobs", o->jobs, "trials run side by side on this machine (default 1)");
    cmd->add_option("--max-frames", o->maxFrames,
                    "frames of each tuning run (default 600)");
    cmd->add_option("--eval-max-frames", o->evalMaxFrames,
                    "frames of each evaluation run (default: --max-frames)");
    cmd->add_option("--out", o->out,
                    "output folder: the study's SQLite file, runs, front/, CSV files, plots, "
                    "summary.md (default out/tune)");
    cmd->add_option("--storage", o->storage,
                    "Optuna storage URL shared by every worker of the study (default "
                    "sqlite:///<out>/study.db; e.g. postgresql://host/db for other machines)");
    cmd->add_option("--study", o->study, "the study's name in the storage (default ambience)");
    cmd->add_option("--sampler", o->sampler,
                    "tpe (multi-objective TPE, the default: fits small budgets) or nsga2");
    cmd->add_option("--seed", o->seed, "the sampler's seed (default: none)");
    cmd->add_flag("--no-eval", o->noEval,
                  "add trials only: no outputs, no evaluation (a worker on another machine)");
    cmd->add_option("--backend", o->backend, "auto, egl or osmesa (default auto)");
    cmd->callback([o, cmd] {
        std::string line = "ambience tune";
        for (const auto* opt : cmd->get_options()) {
            if (opt->count() == 0 || opt->get_name() == "--help") continue;
            line += " " + opt->get_name();
            if (opt->get_type_size() == 0) continue;
            for (const std::string& value : opt->results()) {
                if (value.empty())
                    throw InputError(opt->get_name(), "an empty value (name what it means)");
                const bool plain = value.find_first_not_of(
                                       "abcdefghijklmnopqrstuvwxyzABCDEFGHIJKLMNOPQRSTUVWXYZ"
                                       "0123456789-_.,:=/+@%") == std::string::npos;
                line += plain ? " " + value : " '" + value + "'";
            }
        }
        runTune(*o, line);
    });
}

}  // namespace amb
