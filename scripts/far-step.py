#!/usr/bin/env python3
"""far-step.py — the drawn budget's far-field step of each run of a bench, split by reference
frame: drawn - drawn_fresh_far (lighting/Metrics.h DrawnBudget), the mean over the terrain
witnesses of each frame that have both, and over all of them (the summary's "far field" column).
It says when a method's far field loses against fresh captures: the warm-up (the first frames,
before its probes are in) or later (docs/HISTORY.md "Irradiance gradients, and what the
far-field term is made of").

    scripts/far-step.py BENCH_OUT [BENCH_OUT ...]   a table per folder (its runs/*/reference.csv)
    scripts/far-step.py --self-test                 checks the arithmetic on a made-up file

Exit code: 0 done, 2 a folder without runs or a reference.csv without the two columns.
"""
import csv
import glob
import io
import os
import sys


def far_steps(rows):
    """(per frame {frame: mean step}, overall mean, witnesses) of reference.csv rows."""
    by_frame = {}
    for r in rows:
        drawn, fresh = r.get("drawn", ""), r.get("drawn_fresh_far", "")
        if drawn == "" or fresh == "":
            continue
        by_frame.setdefault(int(r["frame"]), []).append(float(drawn) - float(fresh))
    steps = [s for v in by_frame.values() for s in v]
    means = {f: sum(v) / len(v) for f, v in sorted(by_frame.items())}
    return means, (sum(steps) / len(steps) if steps else float("nan")), len(steps)


def table(folder):
    runs = sorted(glob.glob(os.path.join(folder, "runs", "*", "reference.csv")))
    if not runs:
        raise ValueError(f"{folder}: no runs/*/reference.csv")
    lines = []
    for path in runs:
        with open(path, newline="") as f:
            reader = csv.DictReader(f)
            if not {"drawn", "drawn_fresh_far"} <= set(reader.fieldnames or []):
                raise ValueError(f"{path}: no drawn and drawn_fresh_far columns")
            means, mean, n = far_steps(reader)
        run = os.path.basename(os.path.dirname(path))
        frames = " ".join(f"{k}:{v:+.3f}" for k, v in means.items())
        lines.append(f"{run:48s} far {mean:+.4f} ({n} witnesses)  by frame {frames}")
    return "\n".join(lines)


def self_test():
    text = ("frame,witness,drawn,drawn_fresh_far\n"
            "0,ring_0,0.30,0.10\n0,ring_1,0.20,0.10\n"   # steps 0.2, 0.1: frame 0 mean 0.15
            "60,ring_0,0.10,0.14\n60,ring_1,,0.2\n")     # step -0.04; a row without drawn
    means, mean, n = far_steps(csv.DictReader(io.StringIO(text)))
    assert n == 3, n
    assert abs(means[0] - 0.15) < 1e-12 and abs(means[60] + 0.04) < 1e-12, means
    assert abs(mean - (0.2 + 0.1 - 0.04) / 3) < 1e-12, mean
    print("far-step: self-test passed")


def main(argv):
    if argv == ["--self-test"]:
        self_test()
        return 0
    if not argv or any(a.startswith("-") for a in argv):
        print("usage: far-step.py BENCH_OUT [BENCH_OUT ...] | --self-test", file=sys.stderr)
        return 2
    try:
        for folder in argv:
            print(f"# {folder}")
            print(table(folder))
    except (ValueError, OSError) as e:
        print(f"far-step: {e}", file=sys.stderr)
        return 2
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
