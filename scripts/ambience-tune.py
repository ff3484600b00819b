#!/usr/bin/python3
"""The study behind `ambience tune`: a multi-objective Optuna study of the volume's settings.

Usage (through `ambience tune`, which checks the options first; docs/TUNING.md "Tuning with
Optuna"):

  ambience-tune.py --ambience EXE --params LIST --replays LIST --eval-replays LIST
                   --oracle reference|self --out DIR --study NAME --sampler tpe|nsga2
                   --trials N --jobs N --max-frames N --eval-max-frames N [--storage URL]
                   [--seed N] [--no-eval] [--backend B] [--command TEXT]

Two objectives, both minimised, averaged over the tuning replays:
  error  the mean error against the oracle: with --oracle reference the terrain witnesses'
         error at the drawn normal (report.json measurement.reference.drawn.error.mean), with
         --oracle self the self-oracle's error (measurement.error.mean);
  ms     the ambience's milliseconds a frame (report.json ambience.ambience_ms.median).

Each trial writes its settings file and runs `ambience run` on every tuning replay with the
command line `ambience bench` gives such a run (taken from `ambience bench --emit`, so the two
cannot drift apart), its own --config and --out put in. The first runs of a folder measure the
defaults and save the oracles; the trials read them. The study lives in --storage (default
sqlite:///DIR/study.db): the same command again adds --trials more; other machines join with
the same --storage and --study (each with its own --out and --no-eval).

Outputs in --out: trials.csv, front.csv, front/NN.json (settings files for run --config),
front.png, importance.png, eval.csv and summary.md.

Exit codes: 0 done; 1 the study failed (no trial completed, a run tool missing); 2 bad input
(one line naming the option).

Sections:
  [1] Options and the settings schema
  [2] Run command lines (from ambience bench --emit)
  [3] Measuring a settings point
  [4] The study
  [5] Outputs: CSV files, front files, plots, evaluation, summary
  [6] Self-test (ambience-tune.py --self-test EXE: ctest tune_script)
  [7] Main
"""

import argparse
import concurrent.futures
import csv
import datetime
import json
import math
import os
import shlex
import socket
import subprocess
import sys
import threading
import time

PROG = "ambience tune"


class InputProblem(Exception):
    """Bad input: one line naming the option, exit code 2."""


class RunProblem(Exception):
    """A run of the study failed: the trial fails, the study goes on."""


def say(text):
    print(f"tune: {text}", file=sys.stderr, flush=True)


# ---- [1] Options and the settings schema ---------------------------------------------------

def parse_args(argv):
    p = argparse.ArgumentParser(prog=PROG, add_help=True)
    p.add_argument("--ambience", required=True)
    p.add_argument("--params", required=True)
    p.add_argument("--replays", required=True)
    p.add_argument("--eval-replays", required=True)
    p.add_argument("--oracle", default="reference")
    p.add_argument("--out", required=True)
    p.add_argument("--storage", default="")
    p.add_argument("--study", default="ambience")
    p.add_argument("--sampler", default="tpe")
    p.add_argument("--trials", type=int, default=40)
    p.add_argument("--jobs", type=int, default=1)
    p.add_argument("--max-frames", type=int, default=600)
    p.add_argument("--eval-max-frames", type=int, default=0)
    p.add_argument("--seed", type=int, default=None)
    p.add_argument("--backend", default="auto")
    p.add_argument("--no-eval", action="store_true")
    p.add_argument("--command", default="")
    return p.parse_args(argv)


def split_list(text):
    return [item.strip() for item in text.split(",") if item.strip()]


def read_schema(exe):
    out = subprocess.run([exe, "settings", "--json"], capture_output=True, text=True)
    if out.returncode != 0:
        raise RunProblem(f"{exe} settings --json failed: {out.stderr.strip()}")
    return {k["key"]: k for k in json.loads(out.stdout)["volume"]}


class Param:
    """A key the study tunes: its name in the settings file, its kind and range."""

    def __init__(self, spec, lo=None, hi=None):
        self.key = spec["key"]
        self.kind = spec["kind"]
        self.default = spec["default"]
        self.lo = spec.get("min") if lo is None else lo
        self.hi = spec.get("max") if hi is None else hi
        self.log = bool(spec.get("logarithmic")) and self.kind != "switch" and self.lo > 0

    def suggest(self, trial):
        if self.kind == "switch":
            return trial.suggest_categorical(self.key, [False, True])
        if self.kind == "integer":
            return trial.suggest_int(self.key, int(self.lo), int(self.hi), log=self.log)
        return trial.suggest_float(self.key, float(self.lo), float(self.hi), log=self.log)

    def distribution(self):
        import optuna

        if self.kind == "switch":
            return optuna.distributions.CategoricalDistribution([False, True])
        if self.kind == "integer":
            return optuna.distributions.IntDistribution(int(self.lo), int(self.hi), log=self.log)
        return optuna.distributions.FloatDistribution(float(self.lo), float(self.hi), log=self.log)

    def contains(self, value):
        return self.kind == "switch" or self.lo <= value <= self.hi

    def range_text(self):
        if self.kind == "switch":
            return "false, true"
        return f"{self.lo:g} to {self.hi:g}" + (" (log)" if self.log else "")


def parse_params(text, schema):
    params = []
    for item in split_list(text):
        key, _, rng = item.partition("=")
        if key not in schema:
            raise InputProblem(f"--params: unknown setting '{key}'")
        if key == "facesPerFrame":
            raise InputProblem("--params: 'facesPerFrame' is the capture budget the study holds "
                               "fixed")
        if rng:
            lo, _, hi = rng.partition(":")
            try:
                params.append(Param(schema[key], float(lo), float(hi)))
            except ValueError:
                raise InputProblem(f"--params: '{item}': expected KEY or KEY=LO:HI")
        else:
            params.append(Param(schema[key]))
    if not params:
        raise InputProblem(f"--params: no key named in '{text}'")
    return params


def settings_file(values):
    """The settings file (as `run --config` reads it) of {key: value}: nested by the dots."""
    root = {}
    for key, value in values.items():
        at = root
        parts = key.split(".")
        for part in parts[:-1]:
            at = at.setdefault(part, {})
        at[parts[-1]] = value
    return root


# ---- [2] Run command lines (from ambience bench --emit) ------------------------------------

def run_templates(args, replays, folder, max_frames):
    """{replay name: argv} of the default point's run of each replay, as `ambience bench` runs
    it: `bench --emit` writes each run's command line (command.txt) without running it. The
    oracles of those lines live in folder/oracle, shared by every run made from them."""
    cmd = [args.ambience, "bench", "--emit", folder, "--replays", ",".join(replays),
           "--methods", "volume", "--oracle", args.oracle, "--max-frames", str(max_frames),
           "--backend", args.backend]
    out = subprocess.run(cmd, capture_output=True, text=True)
    if out.returncode == 2:
        raise InputProblem(out.stderr.strip().replace("ambience: error: ", ""))
    if out.returncode != 0:
        raise RunProblem(f"bench --emit failed: {out.stderr.strip()}")
    templates = {}
    runs = os.path.join(folder, "runs")
    for name in sorted(os.listdir(runs)):
        if not name.endswith("__volume__default"):
            continue
        with open(os.path.join(runs, name, "command.txt")) as f:
            argv = shlex.split(f.read())
        replay = argv[argv.index("--replay") + 1]
        stem = os.path.splitext(os.path.basename(replay))[0]
        templates[stem] = argv
    for r in replays:
        stem = os.path.splitext(os.path.basename(r))[0]
        if stem not in templates:
            raise RunProblem(f"bench --emit gave no run of '{r}'")
    return [(os.path.splitext(os.path.basename(r))[0], templates[os.path.splitext(
        os.path.basename(r))[0]]) for r in replays]


def with_option(argv, option, value):
    a = list(argv)
    a[a.index(option) + 1] = value
    return a


# ---- [3] Measuring a settings point --------------------------------------------------------

def objective_values(report, oracle):
    m = report.get("measurement", {})
    if oracle == "reference":
        error = m.get("reference", {}).get("drawn", {}).get("error", {}).get("mean")
    else:
        error = m.get("error", {}).get("mean")
    ms = report.get("ambience", {}).get("ambience_ms", {}).get("median")
    if not isinstance(error, (int, float)) or not math.isfinite(error):
        raise RunProblem("the report has no error (too few frames for a measurement?)")
    if not isinstance(ms, (int, float)) or not math.isfinite(ms):
        raise RunProblem("the report has no ambience_ms")
    return float(error), float(ms)


def fake_values(values):
    """A made-up objective for the script's unit tests only (AMBIENCE_TUNE_FAKE=1): smooth in
    every tuned key, two objectives that pull apart, no run."""
    keys = sorted(values)
    x = [float(values[k]) for k in keys]
    error = 0.2 + sum(1.0 / (1.0 + abs(v)) for v in x) / max(1, len(x)) * 0.1
    ms = 1.0 + sum(abs(v) for v in x) / max(1, len(x)) * 0.01
    return error, ms


def measure(values, folder, templates, oracle):
    """Runs the settings {key: value} on every replay of `templates` into folder/<replay>/;
    returns {"error", "ms", "replays": {name: (error, ms)}} (means over the replays). A run whose
    report is there already (a measurement made before) is read back, not run again."""
    os.makedirs(folder, exist_ok=True)
    config = os.path.join(folder, "volume.json")
    text = json.dumps(settings_file(values), indent=2, sort_keys=True) + "\n"
    stale = not os.path.exists(config) or open(config).read() != text
    with open(config, "w") as f:
        f.write(text)
    per = {}
    for name, argv in templates:
        rundir = os.path.join(folder, name)
        report = os.path.join(rundir, "report.json")
        if os.environ.get("AMBIENCE_TUNE_FAKE") == "1":
            per[name] = fake_values(values)
            continue
        a = with_option(with_option(argv, "--config", config), "--out", rundir)
        line = shlex.join(a) + "\n"
        command = os.path.join(rundir, "command.txt")
        # A report made by another command line (frames, oracle, program) is made again.
        same = os.path.exists(command) and open(command).read() == line
        if stale or not same or not os.path.exists(report):
            os.makedirs(rundir, exist_ok=True)
            if os.path.exists(report):
                os.remove(report)
            with open(command, "w") as f:
                f.write(line)
            t0 = time.monotonic()
            with open(os.path.join(rundir, "log.txt"), "w") as log:
                rc = subprocess.run(a, stdout=log, stderr=subprocess.STDOUT,
                                    stdin=subprocess.DEVNULL).returncode
            with open(os.path.join(rundir, "exit-status.txt"), "w") as f:
                f.write(f"{rc} {time.monotonic() - t0:.3f}\n")
            if rc != 0 or not os.path.exists(report):
                tail = ""
                try:
                    lines = [l.strip() for l in open(os.path.join(rundir, "log.txt"))
                             if l.strip() and not l.startswith("run: frame")]
                    tail = " | ".join(lines[-2:])
                except OSError:
                    pass
                raise RunProblem(f"{name}: exit code {rc}: {tail}")
        with open(report) as f:
            per[name] = objective_values(json.load(f), oracle)
    n = len(per)
    return {"error": sum(e for e, _ in per.values()) / n,
            "ms": sum(m for _, m in per.values()) / n,
            "replays": per}


# ---- [4] The study -------------------------------------------------------------------------

STUDY_KEYS = ("params", "replays", "oracle", "max_frames")


def study_config(args, params):
    return {"params": [[p.key, p.kind, p.lo, p.hi, p.log] for p in params],
            "replays": split_list(args.replays), "oracle": args.oracle,
            "max_frames": args.max_frames}


def check_study(study, config):
    """A study keeps its parameters, replays, oracle and frames: measurements made otherwise
    would not compare."""
    saved = study.user_attrs.get("config")
    if saved is None:
        study.set_user_attr("config", config)
        return
    option = {"params": "--params", "replays": "--replays", "oracle": "--oracle",
              "max_frames": "--max-frames"}
    for key in STUDY_KEYS:
        if saved.get(key) != config.get(key):
            raise InputProblem(f"{option[key]}: the study '{study.study_name}' was made with "
                               f"{json.dumps(saved.get(key))}, not {json.dumps(config.get(key))} "
                               f"(another --study or --out starts a new one)")


def make_sampler(args):
    import optuna

    if args.sampler == "nsga2":
        return optuna.samplers.NSGAIISampler(seed=args.seed)
    return optuna.samplers.TPESampler(seed=args.seed, n_startup_trials=10, multivariate=True,
                                      constant_liar=True, warn_independent_sampling=False)


def add_defaults_trial(study, params, defaults):
    """The defaults, measured before the study, as one of its trials (once per study), so the
    sampler and the front know them; left out when a narrowed range excludes a default."""
    import optuna

    for t in study.get_trials(deepcopy=False):
        if t.user_attrs.get("defaults"):
            return
    values = {p.key: p.default for p in params}
    if not all(p.contains(values[p.key]) for p in params):
        say("a default is outside the tuned ranges: the defaults are not one of the trials")
        return
    study.add_trial(optuna.trial.create_trial(
        params=values, distributions={p.key: p.distribution() for p in params},
        values=[defaults["error"], defaults["ms"]],
        user_attrs={"defaults": True, "replays": defaults["replays"],
                    "host": socket.gethostname()}))


def run_study(study, args, params, templates, trials_dir):
    import optuna

    lock = threading.Lock()
    done = [0]
    start = time.monotonic()

    def objective(trial):
        values = {p.key: p.suggest(trial) for p in params}
        folder = os.path.join(trials_dir, f"{trial.number:04d}")
        trial.set_user_attr("host", socket.gethostname())
        t0 = time.monotonic()
        try:
            m = measure(values, folder, templates, args.oracle)
        except RunProblem as e:
            with lock:
                done[0] += 1
                say(f"trial {trial.number} FAILED ({done[0]}/{args.trials}): {e}")
            raise
        trial.set_user_attr("replays", m["replays"])
        trial.set_user_attr("seconds", time.monotonic() - t0)
        with lock:
            done[0] += 1
            el = time.monotonic() - start
            left = el / done[0] * (args.trials - done[0])
            say(f"trial {trial.number}: error {m['error']:.4f}, {m['ms']:.2f} ms "
                f"({done[0]}/{args.trials}, {el / 60:.1f} min elapsed, {left / 60:.1f} min left)")
        return m["error"], m["ms"]

    if args.trials > 0:
        study.optimize(objective, n_trials=args.trials, n_jobs=args.jobs, catch=(RunProblem,),
                       gc_after_trial=False)
    return time.monotonic() - start


# ---- [5] Outputs: CSV files, front files, plots, evaluation, summary -----------------------

def complete_trials(study):
    import optuna

    return [t for t in study.get_trials(deepcopy=False)
            if t.state == optuna.trial.TrialState.COMPLETE and t.values is not None]


def pareto_front(trials):
    """The trials no other trial dominates (no worse in both objectives, better in one), by
    error then ms; of equal points the first."""
    front = []
    for t in trials:
        e, m = t.values
        dominated = any((o.values[0] <= e and o.values[1] <= m) and
                        (o.values[0] < e or o.values[1] < m or o.number < t.number)
                        for o in trials if o is not t)
        if not dominated:
            front.append(t)
    return sorted(front, key=lambda t: (t.values[0], t.values[1]))


def fmt(v):
    if isinstance(v, bool):
        return "true" if v else "false"
    if isinstance(v, float):
        return f"{v:.6g}"
    return str(v)


def write_csv(path, header, rows):
    with open(path, "w", newline="") as f:
        w = csv.writer(f)
        w.writerow(header)
        w.writerows(rows)


def write_trials_csv(path, study, params, replays):
    header = (["trial", "state", "defaults", "error", "ms"] + [p.key for p in params] +
              [f"error_{r}" for r in replays] + [f"ms_{r}" for r in replays] +
              ["host", "seconds"])
    rows = []
    for t in study.get_trials(deepcopy=False):
        per = t.user_attrs.get("replays", {})
        vals = t.values or [None, None]
        rows.append([t.number, t.state.name, int(bool(t.user_attrs.get("defaults"))),
                     fmt(vals[0]) if vals[0] is not None else "",
                     fmt(vals[1]) if vals[1] is not None else ""] +
                    [fmt(t.params[p.key]) if p.key in t.params else "" for p in params] +
                    [fmt(per[r][0]) if r in per else "" for r in replays] +
                    [fmt(per[r][1]) if r in per else "" for r in replays] +
                    [t.user_attrs.get("host", ""), fmt(t.user_attrs.get("seconds", ""))])
    write_csv(path, header, rows)


def write_front(out, front, params):
    folder = os.path.join(out, "front")
    os.makedirs(folder, exist_ok=True)
    for name in os.listdir(folder):
        if name.endswith(".json"):
            os.remove(os.path.join(folder, name))
    rows = []
    for i, t in enumerate(front):
        values = {p.key: t.params[p.key] for p in params if p.key in t.params}
        with open(os.path.join(folder, f"{i:02d}.json"), "w") as f:
            f.write(json.dumps(settings_file(values), indent=2, sort_keys=True) + "\n")
        rows.append([f"{i:02d}", t.number, int(bool(t.user_attrs.get("defaults"))),
                     fmt(t.values[0]), fmt(t.values[1])] + [fmt(values.get(p.key, ""))
                                                            for p in params])
    write_csv(os.path.join(out, "front.csv"),
              ["point", "trial", "defaults", "error", "ms"] + [p.key for p in params], rows)


def plots(out, trials, front, defaults, params, study, oracle):
    """front.png and importance.png; a line on stderr (and none of the plot) when it cannot."""
    try:
        import matplotlib

        matplotlib.use("Agg")
        import matplotlib.pyplot as plt
    except ImportError:
        return ["plots skipped: python3-matplotlib is missing"], {}
    notes = []
    fig, ax = plt.subplots(figsize=(7, 4.5), dpi=110)
    ax.scatter([t.values[1] for t in trials], [t.values[0] for t in trials], s=14,
               color="0.65", label=f"trials ({len(trials)})")
    fx = [t.values[1] for t in front]
    fy = [t.values[0] for t in front]
    order = sorted(range(len(front)), key=lambda i: fx[i])
    ax.plot([fx[i] for i in order], [fy[i] for i in order], "-o", color="tab:blue", ms=5,
            label=f"Pareto front ({len(front)})")
    for i, t in enumerate(front):
        ax.annotate(f"{i:02d}", (fx[i], fy[i]), textcoords="offset points", xytext=(4, 4),
                    fontsize=7, color="tab:blue")
    if defaults:
        ax.scatter([defaults["ms"]], [defaults["error"]], marker="*", s=140, color="tab:red",
                   zorder=5, label="defaults")
    ax.set_xlabel("ambience ms a frame (median, mean over the tuning replays)")
    ax.set_ylabel("mean error" + (" at the drawn normal (reference)" if oracle == "reference"
                                  else " (self-oracle)"))
    ax.set_title("ambience tune: error against cost")
    ax.grid(True, alpha=0.3)
    ax.legend(fontsize=8)
    fig.tight_layout()
    fig.savefig(os.path.join(out, "front.png"))
    plt.close(fig)

    importances = {}
    try:
        import optuna

        varied = [p.key for p in params
                  if len({t.params.get(p.key) for t in trials}) > 1]
        if len(trials) >= 4 and varied:
            ev = optuna.importance.FanovaImportanceEvaluator(seed=0)
            for i, name in enumerate(["error", "ms"]):
                importances[name] = optuna.importance.get_param_importances(
                    study, evaluator=ev, params=varied, target=lambda t, i=i: t.values[i])
        else:
            notes.append("importance: too few trials (or nothing varied) to weigh the keys")
    except Exception as e:  # sklearn missing, too few trials: the rest of the outputs stand
        notes.append(f"importance not computed: {type(e).__name__}: {e}")
    if importances:
        keys = [p.key for p in params if p.key in importances["error"]]
        fig, ax = plt.subplots(figsize=(7, 0.45 * len(keys) + 1.5), dpi=110)
        y = list(range(len(keys)))
        ax.barh([v - 0.2 for v in y], [importances["error"].get(k, 0) for k in keys], 0.4,
                label="error", color="tab:blue")
        ax.barh([v + 0.2 for v in y], [importances["ms"].get(k, 0) for k in keys], 0.4,
                label="ms a frame", color="tab:orange")
        ax.set_yticks(y)
        ax.set_yticklabels(keys, fontsize=8)
        ax.invert_yaxis()
        ax.set_xlabel("importance (fANOVA, share of the objective's variance)")
        ax.set_title(f"ambience tune: what matters ({len(trials)} trials)")
        ax.legend(fontsize=8)
        fig.tight_layout()
        fig.savefig(os.path.join(out, "importance.png"))
        plt.close(fig)
    return notes, importances


def evaluate(args, front, params, eval_templates, out, defaults_values):
    """The defaults and every front point measured on the evaluation replays (eval/<point>/);
    a point measured before (the same settings) is read back."""
    points = [("defaults", None, defaults_values)]
    for i, t in enumerate(front):
        points.append((f"{i:02d}", t, {p.key: t.params[p.key] for p in params
                                       if p.key in t.params}))
    results = {}

    def one(point):
        label, trial, values = point
        folder = os.path.join(out, "eval", "defaults" if trial is None or
                              trial.user_attrs.get("defaults") else f"trial-{trial.number:04d}")
        return label, measure(values, folder, eval_templates, args.oracle)

    # The defaults first: their runs save the evaluation replays' oracles.
    label, m = one(points[0])
    results[label] = m
    with concurrent.futures.ThreadPoolExecutor(max_workers=args.jobs) as pool:
        futures = [pool.submit(one, p) for p in points[1:]]
        for f in futures:
            try:
                label, m = f.result()
                results[label] = m
            except RunProblem as e:
                say(f"evaluation run failed: {e}")
    return points, results


def write_eval(out, points, results, defaults_tune, eval_replays):
    header = (["point", "trial", "tune_error", "tune_ms", "eval_error", "eval_ms",
               "error_moved", "ms_moved"] + [f"error_{r}" for r in eval_replays] +
              [f"ms_{r}" for r in eval_replays])
    rows = []
    for label, trial, _ in points:
        m = results.get(label)
        tune = defaults_tune if trial is None else {"error": trial.values[0],
                                                    "ms": trial.values[1]}
        if m is None:
            rows.append([label, "" if trial is None else trial.number, fmt(tune["error"]),
                         fmt(tune["ms"]), "failed", "", "", ""])
            continue
        rows.append([label, "" if trial is None else trial.number, fmt(tune["error"]),
                     fmt(tune["ms"]), fmt(m["error"]), fmt(m["ms"]),
                     fmt(m["error"] - tune["error"]), fmt(m["ms"] - tune["ms"])] +
                    [fmt(m["replays"][r][0]) for r in eval_replays] +
                    [fmt(m["replays"][r][1]) for r in eval_replays])
    write_csv(os.path.join(out, "eval.csv"), header, rows)


def write_summary(out, args, params, study, trials, front, defaults, points, results, wall_s,
                  notes, importances, command):
    lines = [f"# ambience tune: study '{study.study_name}'", ""]
    lines.append(f"Command: `{command}`")
    lines.append("")
    lines.append(f"Tuning replays: {args.replays}; {args.max_frames} frames each; oracle "
                 f"{args.oracle} (error: " +
                 ("the terrain witnesses' error at the drawn normal against the reference"
                  if args.oracle == "reference" else "the self-oracle's error") +
                 "); cost: the ambience's ms a frame (median), both the mean over the replays.")
    lines.append(f"Trials: {len(study.get_trials(deepcopy=False))} in the study, {len(trials)} "
                 f"complete; this command's trials took {wall_s / 60:.1f} min of wall time "
                 f"on {args.jobs} job(s). Sampler: {args.sampler}.")
    lines.append("")
    lines.append("| key | range |")
    lines.append("|---|---|")
    for p in params:
        lines.append(f"| `{p.key}` | {p.range_text()} |")
    lines.append("")
    lines.append("## Pareto front (tuning replays)")
    lines.append("")
    lines.append("`front/NN.json` is point NN as a settings file (`ambience run --config`).")
    lines.append("")
    lines.append("| point | trial | error | ms | " + " | ".join(f"`{p.key}`" for p in params) +
                 " |")
    lines.append("|---|---|---|---|" + "---|" * len(params))
    if defaults:
        lines.append("| defaults | " + ("-" if defaults.get("trial") is None
                                         else str(defaults["trial"])) +
                     f" | {defaults['error']:.4f} | {defaults['ms']:.2f} | " +
                     " | ".join(fmt(p.default) for p in params) + " |")
    for i, t in enumerate(front):
        lines.append(f"| {i:02d} | {t.number} | {t.values[0]:.4f} | {t.values[1]:.2f} | " +
                     " | ".join(fmt(t.params.get(p.key, "")) for p in params) + " |")
    lines.append("")
    lines.append("![the front](front.png)")
    if importances:
        lines.append("")
        lines.append("## What matters (fANOVA importance)")
        lines.append("")
        lines.append("| key | error | ms |")
        lines.append("|---|---|---|")
        for p in params:
            if p.key in importances["error"]:
                lines.append(f"| `{p.key}` | {importances['error'][p.key]:.2f} | "
                             f"{importances['ms'].get(p.key, 0):.2f} |")
        lines.append("")
        lines.append("![importances](importance.png)")
    if points:
        lines.append("")
        lines.append(f"## Held out: re-measured on {args.eval_replays} "
                     f"({args.eval_max_frames} frames each)")
        lines.append("")
        lines.append("| point | trial | tuning error | tuning ms | eval error | eval ms | "
                     "error moved | ms moved |")
        lines.append("|---|---|---|---|---|---|---|---|")
        for label, trial, _ in points:
            m = results.get(label)
            te, tm = ((defaults["error"], defaults["ms"]) if trial is None
                      else (trial.values[0], trial.values[1]))
            if m is None:
                lines.append(f"| {label} | | {te:.4f} | {tm:.2f} | failed | | | |")
                continue
            lines.append(f"| {label} | {'' if trial is None else trial.number} | {te:.4f} | "
                         f"{tm:.2f} | {m['error']:.4f} | {m['ms']:.2f} | "
                         f"{m['error'] - te:+.4f} | {m['ms'] - tm:+.2f} |")
        d = results.get("defaults")
        best = results.get("00") if front else None
        lines.append("")
        if d and best:
            better = best["error"] <= d["error"]
            cheaper = best["ms"] <= d["ms"]
            verdict = ("yes" if better and cheaper else "no")
            lines.append(
                f"The front's lowest-error point (00, trial {front[0].number}) on the held-out "
                f"replays: error {best['error']:.4f} against the defaults' {d['error']:.4f} "
                f"({'at most' if better else 'more than'} theirs), {best['ms']:.2f} ms against "
                f"{d['ms']:.2f} ({'no more' if cheaper else 'more'}). At least as accurate as the "
                f"defaults at no more cost: **{verdict}**. (ms a frame is wall time on the "
                f"machine that ran it, and moves with its load.)")
        else:
            lines.append("The held-out comparison is incomplete (a run failed): see eval.csv.")
    for n in notes:
        lines.append("")
        lines.append(n)
    lines.append("")
    with open(os.path.join(out, "summary.md"), "w") as f:
        f.write("\n".join(lines))


# ---- [6] Self-test -------------------------------------------------------------------------

def self_test(exe):
    """The script's own checks (ctest tune_script): the front, the settings files, and a study
    with a made-up objective (AMBIENCE_TUNE_FAKE, no runs) that resumes and runs two jobs."""
    import tempfile

    problems = []

    def check(cond, what):
        if not cond:
            problems.append(what)

    class T:
        def __init__(self, number, e, m):
            self.number, self.values = number, [e, m]

    pts = [T(0, 1, 5), T(1, 2, 3), T(2, 3, 4), T(3, 2, 3), T(4, 4, 1), T(5, 1, 6)]
    check([t.number for t in pareto_front(pts)] == [0, 1, 4],
          f"pareto_front: {[t.number for t in pareto_front(pts)]}, expected [0, 1, 4]")
    check(settings_file({"store.blendTime_s": 2.0, "facesPerFrame": 1, "store.levels": 4}) ==
          {"store": {"blendTime_s": 2.0, "levels": 4}, "facesPerFrame": 1},
          "settings_file does not nest the keys by their dots")
    with tempfile.TemporaryDirectory(prefix="ambience-tune-test.") as tmp:
        out = os.path.join(tmp, "study")
        base = ["--ambience", exe, "--params", "scheduler.horizon_s=1:6,store.reachCells,"
                "scheduler.corridorCells", "--replays", "highway-drive", "--eval-replays",
                "hairpin-flight-held-out", "--oracle", "self", "--out", out, "--max-frames", "10",
                "--seed", "5"]
        os.environ["AMBIENCE_TUNE_FAKE"] = "1"
        try:
            rc1 = main(base + ["--trials", "6", "--jobs", "2"])
            rc2 = main(base + ["--trials", "3"])
        finally:
            del os.environ["AMBIENCE_TUNE_FAKE"]
        check(rc1 == 0 and rc2 == 0, f"the fake studies exited {rc1} and {rc2}")
        with open(os.path.join(out, "trials.csv")) as f:
            rows = list(csv.DictReader(f))
        check(len(rows) == 10, f"trials.csv has {len(rows)} trials, expected 1 + 6 + 3")
        check(sum(r["defaults"] == "1" for r in rows) == 1, "not one defaults trial")
        keys = ["scheduler.horizon_s", "store.reachCells", "scheduler.corridorCells"]
        drawn = [tuple(r[k] for k in keys) for r in rows]
        check(len(set(drawn)) == len(drawn), "a resumed study drew a trial's parameters again")
        for r in rows:
            h = float(r["scheduler.horizon_s"])
            check(1 <= h <= 6, f"trial {r['trial']}: horizon {h} outside 1 to 6")
            c = float(r["scheduler.corridorCells"])
            check(0.01 <= c <= 100, f"trial {r['trial']}: corridorCells {c} outside the schema")
        vals = [(float(r["error"]), float(r["ms"])) for r in rows]
        with open(os.path.join(out, "front.csv")) as f:
            front = list(csv.DictReader(f))
        fronts = sorted(os.listdir(os.path.join(out, "front")))
        check(fronts == [f"{i:02d}.json" for i in range(len(front))],
              f"front files {fronts} against {len(front)} rows of front.csv")
        for p in front:
            e, m = float(p["error"]), float(p["ms"])
            check(not any(a <= e and b <= m and (a < e or b < m) for a, b in vals),
                  f"front point {p['point']} is dominated")
        for e, m in vals:
            check(any(float(p["error"]) <= e and float(p["ms"]) <= m for p in front),
                  f"trial ({e}, {m}) is not covered by the front")
        for name in ("summary.md", "eval.csv", "front.png", "importance.png"):
            check(os.path.isfile(os.path.join(out, name)), f"no {name}")
        # A study keeps its replays.
        rc3 = main(base[:-8] + ["--replays", "low-flight", "--eval-replays",
                                "hairpin-flight-held-out", "--oracle", "self", "--out", out,
                                "--max-frames", "10", "--trials", "1"])
        check(rc3 == 2, f"another --replays on the same study exited {rc3}, expected 2")
    for p in problems:
        print(f"self-test: {p}", file=sys.stderr)
    print("self-test: " + ("FAILED" if problems else "passed"), file=sys.stderr)
    return 1 if problems else 0


# ---- [7] Main ------------------------------------------------------------------------------

def main(argv):
    args = parse_args(argv)
    if not args.eval_max_frames:
        args.eval_max_frames = args.max_frames
    try:
        import optuna
    except ImportError:
        print(f"ambience: error: python3-optuna is missing (Debian: apt-get install "
              "python3-optuna python3-sklearn)", file=sys.stderr)
        return 1
    optuna.logging.set_verbosity(optuna.logging.WARNING)
    import warnings

    warnings.filterwarnings("ignore", category=optuna.exceptions.ExperimentalWarning)
    out = os.path.abspath(args.out)
    os.makedirs(out, exist_ok=True)
    storage = args.storage or "sqlite:///" + os.path.join(out, "study.db")
    command = args.command or "ambience-tune.py " + shlex.join(argv)
    try:
        schema = read_schema(args.ambience)
        params = parse_params(args.params, schema)
        replays = split_list(args.replays)
        eval_replays = split_list(args.eval_replays)
        templates = run_templates(args, replays, os.path.join(out, "runs-tune"),
                                  args.max_frames)
        try:
            study = optuna.create_study(storage=storage, study_name=args.study,
                                        directions=["minimize", "minimize"],
                                        sampler=make_sampler(args), load_if_exists=True)
        except Exception as e:
            raise InputProblem(f"--storage: cannot open '{storage}': {type(e).__name__}: {e}")
        # A resumed study draws on from where it stands: the same seed again would repeat the
        # first command's random start.
        if args.seed is not None and study.get_trials(deepcopy=False):
            args.seed += len(study.get_trials(deepcopy=False))
            study.sampler = make_sampler(args)
        if len(study.directions) != 2:
            raise InputProblem(f"--study: '{args.study}' is not a two-objective study")
        check_study(study, study_config(args, params))
    except InputProblem as e:
        print(f"ambience: error: {e}", file=sys.stderr)
        return 2
    except RunProblem as e:
        print(f"ambience: error: {e}", file=sys.stderr)
        return 1

    # The defaults first, alone: their runs save the tuning replays' oracles, which every
    # trial then reads (on this machine).
    defaults_values = {p.key: p.default for p in params}
    say(f"defaults on {len(templates)} replay(s) ({args.max_frames} frames each)")
    try:
        defaults = measure(defaults_values, os.path.join(out, "defaults"), templates,
                           args.oracle)
    except RunProblem as e:
        print(f"ambience: error: the defaults' runs failed: {e}", file=sys.stderr)
        return 1
    say(f"defaults: error {defaults['error']:.4f}, {defaults['ms']:.2f} ms")
    add_defaults_trial(study, params, defaults)
    for t in study.get_trials(deepcopy=False):
        if t.user_attrs.get("defaults"):
            defaults["trial"] = t.number

    wall_s = run_study(study, args, params, templates, os.path.join(out, "trials"))
    trials = complete_trials(study)
    if args.no_eval:
        say(f"{args.trials} trial(s) added in {wall_s / 60:.1f} min; the study has "
            f"{len(trials)} complete")
        return 0
    if not trials:
        print(f"ambience: error: no trial of the study completed (see trials/*/*/log.txt)",
              file=sys.stderr)
        return 1
    front = pareto_front(trials)
    write_trials_csv(os.path.join(out, "trials.csv"), study, params,
                     [name for name, _ in templates])
    write_front(out, front, params)
    notes, importances = plots(out, trials, front, defaults, params, study, args.oracle)
    points, results = [], {}
    if eval_replays:
        eval_templates = run_templates(args, eval_replays, os.path.join(out, "runs-eval"),
                                       args.eval_max_frames)
        say(f"re-measuring the defaults and {len(front)} front point(s) on "
            f"{', '.join(eval_replays)}")
        points, results = evaluate(args, front, params, eval_templates, out, defaults_values)
        write_eval(out, points, results, defaults, [name for name, _ in eval_templates])
    write_summary(out, args, params, study, trials, front, defaults, points, results, wall_s,
                  notes, importances, command)
    print(f"tune: {len(trials)} complete trial(s), {len(front)} on the front; this command's "
          f"trials took {wall_s / 60:.1f} min")
    for i, t in enumerate(front):
        print(f"  front/{i:02d}.json  trial {t.number}: error {t.values[0]:.4f}, "
              f"{t.values[1]:.2f} ms")
    print(f"  defaults: error {defaults['error']:.4f}, {defaults['ms']:.2f} ms")
    print(f"  summary: {os.path.join(out, 'summary.md')}")
    return 0


if __name__ == "__main__":
    if len(sys.argv) == 3 and sys.argv[1] == "--self-test":
        sys.exit(self_test(sys.argv[2]))
    sys.exit(main(sys.argv[1:]))
