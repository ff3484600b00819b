#!/usr/bin/env python3
"""Memory curve and boundedness checks of a soak run (tests/soak.sh).

    soak-plot.py RUN/report.json --replay REPLAY.json --plot FILE.png [--wall-s S]
                 [--max-anchors N] [--max-store-kB K] [--rss-growth F]
                 [--heap-growth G] [--heap-leak L]
    soak-plot.py --self-test      (each check against a synthetic run with its fault)

Draws resident memory, anchors and anchor-store bytes against simulated time (cuts marked, the
time of day beside) with Debian's matplotlib, prints the figures, and exits 1 if a check fails:
  - every frame's anchor store was scanned and held no NaN or infinity;
  - anchors and store bytes stay under the stated bounds;
  - the largest resident memory (RSS) of the second half is at most F x that of the first half;
  - the C heap in use (what the program holds; RSS also counts freed memory the heap keeps and
    the GL driver's mappings) is flat: its largest value in the second half at most G x that of
    the first, and its growth over the second half, extrapolated to the whole run, under a
    fraction L of it (the report's rows sit in one block reserved at the start, so they count
    from the first frame);
  - every camera cut (the replay's own and each jump back to its start) was seen as a teleport;
  - the time of day moved on at the replay's rate for the whole run (no jump back per pass).
"""
import argparse
import json
import math
import sys

DEFAULT_MAX_ANCHORS = 1000   # README: at most 450 on the 90 s drive, 299 on the stress flight
DEFAULT_MAX_STORE_KB = 2048  # about 0.9 kB per anchor (pool and OpenVDB trees)
DEFAULT_RSS_GROWTH = 1.1
DEFAULT_HEAP_GROWTH = 1.05
DEFAULT_HEAP_LEAK = 0.02


def load(path):
    try:
        with open(path) as f:
            return json.load(f)
    except (OSError, ValueError) as e:
        sys.exit(f"soak-plot.py: {path}: {e}")


def slope_per_minute(t_s, v):
    """Least-squares slope of v against t, per simulated minute."""
    n = len(t_s)
    if n < 2:
        return 0.0
    mt, mv = sum(t_s) / n, sum(v) / n
    den = sum((t - mt) ** 2 for t in t_s)
    return 60.0 * sum((t - mt) * (x - mv) for t, x in zip(t_s, v)) / den if den > 0 else 0.0


def window_max_slope_per_minute(t_s, v, windows=20):
    """A leak's slope, robust to a one-time step: the maxima of `windows` equal runs of frames,
    and the median of the slopes between every pair of them (Theil-Sen), per simulated minute.
    A steady leak moves every window's maximum up, so every pair shows it; a step that happens
    once (a cache that fills, a pool that doubles) changes only the pairs that straddle it,
    fewer than half of them while it sits in the first or last quarter of the span."""
    n = len(t_s)
    if n < 2 * windows:
        return slope_per_minute(t_s, v)
    points = []
    for w in range(windows):
        a, b = w * n // windows, (w + 1) * n // windows
        points.append((0.5 * (t_s[a] + t_s[b - 1]), max(v[a:b])))
    slopes = sorted((q[1] - p[1]) / (q[0] - p[0]) for i, p in enumerate(points)
                    for q in points[i + 1:] if q[0] > p[0])
    if not slopes:
        return 0.0
    m = len(slopes)
    return 60.0 * (slopes[m // 2] if m % 2 else 0.5 * (slopes[m // 2 - 1] + slopes[m // 2]))


def less_rows(report):
    """RSS less the report's own rows so far (an estimate without the allocator's overhead)."""
    row_kB = report["memory"]["reportRowBytes"] / 1024.0
    return [r["rss_kB"] - (i + 1) * row_kB for i, r in enumerate(report["frames"])]


def figures(report, replay):
    rows = report["frames"]
    t = [r["time_s"] for r in rows]
    rss = [r["rss_kB"] for r in rows]
    rss_less_rows = less_rows(report)
    heap = [r.get("heap_kB", 0) for r in rows]
    half = len(rows) // 2
    amb = report.get("ambience", {})
    mem = report["memory"]
    # Unwrapped advance of the time of day over the run.
    advance_h = 0.0
    for a, b in zip(rows, rows[1:]):
        advance_h += (b["timeOfDay_h"] - a["timeOfDay_h"]) % 24.0
    rate = replay["timeOfDay"]["rate"]
    replay_cuts = sum(1 for s in replay["samples"] if s[-1])
    return {
        "frames": len(rows),
        "loops": report["loops"],
        "simulated_min": (t[-1] + report["frameStep_s"]) / 60.0 if rows else 0.0,
        "anchors_max": amb.get("anchorsMax", 0),
        "store_bytes_max": amb.get("bytesMax", 0),
        "store_scans": amb.get("storeScans", 0),
        "store_finite": amb.get("storeFinite", False),
        "rejected_probes": amb.get("rejectedProbes", 0),
        "teleports": amb.get("teleports", 0),
        "camera_cuts": report["cameraCuts"],
        "expected_cuts": report["loops"] * replay_cuts + report["loops"] - 1,
        "rss_start_kB": mem["rssStart_kB"],
        "rss_end_kB": mem["rssEnd_kB"],
        "rss_max_kB": mem["rss_kB"]["max"],
        "rss_peak_kB": mem["rssPeak_kB"],
        "rss_first_half_max_kB": max(rss[:half] or [0]),
        "rss_second_half_max_kB": max(rss[half:] or [0]),
        "rss_second_half_slope_kB_per_min": slope_per_minute(t[half:], rss[half:]),
        # The report keeps a row per frame until the end: RSS less those rows is the rest.
        "report_row_bytes": mem["reportRowBytes"],
        "report_rows_kB_per_min": mem["reportRowBytes"] / 1024.0 * 60.0 / report["frameStep_s"],
        "rss_less_rows_first_half_max_kB": max(rss_less_rows[:half] or [0]),
        "rss_less_rows_second_half_max_kB": max(rss_less_rows[half:] or [0]),
        "rss_less_rows_second_half_slope_kB_per_min":
            slope_per_minute(t[half:], rss_less_rows[half:]),
        "heap_start_kB": heap[0],
        "heap_end_kB": heap[-1],
        "heap_first_half_max_kB": max(heap[:half] or [0]),
        "heap_second_half_max_kB": max(heap[half:] or [0]),
        "heap_second_half_slope_kB_per_min": slope_per_minute(t[half:], heap[half:]),
        "heap_second_half_robust_slope_kB_per_min":
            window_max_slope_per_minute(t[half:], heap[half:]),
        "time_of_day_start_h": rows[0]["timeOfDay_h"] if rows else 0.0,
        "time_of_day_advance_h": advance_h,
        "time_of_day_expected_h": rate * (t[-1] - t[0]) / 3600.0 if rows else 0.0,
    }


def checks(f, args):
    failures = []
    if not (f["store_finite"] is True and f["store_scans"] == f["frames"]):
        failures.append(f"anchor store: finite={f['store_finite']}, "
                        f"{f['store_scans']} scans for {f['frames']} frames")
    if f["anchors_max"] > args.max_anchors:
        failures.append(f"anchors reached {f['anchors_max']} (bound {args.max_anchors})")
    if f["store_bytes_max"] > args.max_store_kB * 1024:
        failures.append(f"store bytes reached {f['store_bytes_max']} "
                        f"(bound {args.max_store_kB} kB)")
    # Resident memory less the report's own rows (which the run keeps by design, a row a frame:
    # report_rows_kB_per_min) is what must stay bounded.
    if f["rss_less_rows_second_half_max_kB"] > args.rss_growth * f["rss_less_rows_first_half_max_kB"]:
        failures.append(f"resident memory grew: second half max (less the report's rows) "
                        f"{f['rss_less_rows_second_half_max_kB']:.0f} kB > {args.rss_growth} x "
                        f"first half max {f['rss_less_rows_first_half_max_kB']:.0f} kB")
    heap0 = f["heap_first_half_max_kB"]
    if heap0 <= 0:
        print("soak: the heap in use is unknown here (not glibc): heap checks skipped")
    else:
        if f["heap_second_half_max_kB"] > args.heap_growth * heap0:
            failures.append(f"heap in use grew: second half max {f['heap_second_half_max_kB']} "
                            f"kB > {args.heap_growth} x first half max {heap0} kB")
        slope = f["heap_second_half_robust_slope_kB_per_min"]
        growth = slope * f["simulated_min"]
        if growth > args.heap_leak * heap0:
            failures.append(f"heap in use leaks: {slope:.1f} kB per simulated minute over the "
                            f"second half (Theil-Sen over window maxima), {growth:.0f} kB over "
                            f"the run > {args.heap_leak} x {heap0} kB")
    if f["camera_cuts"] != f["expected_cuts"] or f["teleports"] != f["camera_cuts"]:
        failures.append(f"cuts: {f['camera_cuts']} in the run (expected {f['expected_cuts']}), "
                        f"{f['teleports']} teleports seen")
    if not math.isclose(f["time_of_day_advance_h"], f["time_of_day_expected_h"],
                        rel_tol=1e-6, abs_tol=1e-6):
        failures.append(f"time of day moved {f['time_of_day_advance_h']:.4f} h, expected "
                        f"{f['time_of_day_expected_h']:.4f} h")
    return failures


def plot(report, f, path):
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    rows = report["frames"]
    t_min = [r["time_s"] / 60.0 for r in rows]
    cuts = [r["time_s"] / 60.0 for r in rows if r["cut"]]
    fig, axes = plt.subplots(4, 1, figsize=(10, 9), sharex=True,
                             gridspec_kw={"height_ratios": [3, 2, 2, 1]})
    series = [
        ([r["rss_kB"] / 1024.0 for r in rows], "memory [MB]", "tab:red"),
        ([r["anchors"] for r in rows], "anchors", "tab:blue"),
        ([r["anchorBytes"] / 1024.0 for r in rows], "anchor store [kB]", "tab:green"),
        ([r["timeOfDay_h"] for r in rows], "time of day [h]", "tab:orange"),
    ]
    for ax, (values, label, colour) in zip(axes, series):
        ax.plot(t_min, values, color=colour, linewidth=0.8)
        ax.set_ylabel(label)
        ax.grid(alpha=0.3)
    axes[0].plot(t_min, [v / 1024.0 for v in less_rows(report)], color="tab:red", alpha=0.5,
                 linewidth=0.8, linestyle="--")
    axes[0].plot(t_min, [r.get("heap_kB", 0) / 1024.0 for r in rows], color="tab:purple",
                 linewidth=0.8)
    axes[0].legend(["resident (RSS)", "RSS less the report's own rows", "C heap in use"],
                   loc="lower right", fontsize=8)
    axes[0].set_ylim(bottom=0)
    axes[1].set_ylim(bottom=0)
    axes[2].set_ylim(bottom=0)
    axes[3].set_ylim(0, 24)
    axes[3].set_yticks([0, 6, 12, 18, 24])
    if cuts:
        axes[1].plot(cuts, [0] * len(cuts), "|", color="black", markersize=8,
                     label=f"camera cuts ({len(cuts)})")
        axes[1].legend(loc="upper right", fontsize=8)
    axes[-1].set_xlabel("simulated time [min]")
    axes[0].set_title(
        f"Soak: {f['simulated_min']:.0f} simulated min, {f['frames']} frames "
        f"({report['frameStep_s'] * 1000:.0f} ms apart); "
        f"RSS {f['rss_start_kB'] / 1024:.0f} -> {f['rss_end_kB'] / 1024:.0f} MB "
        f"(max {f['rss_max_kB'] / 1024:.0f}); anchors max {f['anchors_max']}; "
        f"store finite: {f['store_finite']}", fontsize=9)
    fig.tight_layout()
    fig.savefig(path, dpi=100)


def synthetic(frames=600, loops=3, leak_kB_per_frame=0.0, nan_at=None, drop_cut=False,
              reset_time_of_day=False, step_at=None, step_kB=0.0, rows_kB=0.1):
    """A report and replay as a soak run writes them, for --self-test: a 2 s replay at 0.1 s
    frames with one cut of its own; a 200 MB process of which 80 MB heap, 0.1 kB of report rows
    a frame; a leak adds to both."""
    step_s, per_loop, rate = 0.1, frames // loops, 3600.0
    rows = []
    for i in range(frames):
        loop, j = divmod(i, per_loop)
        cut = (j == 0 and loop > 0) or j == per_loop // 2
        if drop_cut and i == per_loop:
            cut = False
        t = (j if reset_time_of_day else i) * step_s
        step = step_kB if step_at is not None and i >= step_at * frames else 0.0
        rows.append({"time_s": i * step_s, "timeOfDay_h": (6.0 + rate * t / 3600.0) % 24.0,
                     "cut": cut, "anchors": 50, "anchorBytes": 200000,
                     "rss_kB": 200000 + rows_kB * (i + 1) + leak_kB_per_frame * i + step,
                     "heap_kB": 80000 + leak_kB_per_frame * i + step})
    rss = [r["rss_kB"] for r in rows]
    cuts = sum(r["cut"] for r in rows)
    report = {"frames": rows, "loops": loops, "frameStep_s": step_s, "cameraCuts": cuts,
              "memory": {"rssStart_kB": rss[0], "rssEnd_kB": rss[-1], "rss_kB": {"max": max(rss)},
                         "rssPeak_kB": max(rss), "reportRowBytes": rows_kB * 1024},
              "ambience": {"anchorsMax": 50, "bytesMax": 200000, "storeScans": frames,
                           "storeFinite": nan_at is None, "rejectedProbes": 0,
                           "teleports": cuts}}
    samples = [[k * 0.1, False] for k in range(per_loop)]
    samples[per_loop // 2][-1] = True
    replay = {"timeOfDay": {"rate": rate}, "samples": samples}
    return report, replay


def self_test():
    """Each check passes a clean run and fails the fault it is there for."""
    limits = argparse.Namespace(max_anchors=DEFAULT_MAX_ANCHORS, max_store_kB=DEFAULT_MAX_STORE_KB,
                                rss_growth=DEFAULT_RSS_GROWTH, heap_growth=DEFAULT_HEAP_GROWTH,
                                heap_leak=DEFAULT_HEAP_LEAK)
    cases = [
        ("clean", {}, None),
        ("leak of 100 kB a frame", {"leak_kB_per_frame": 100.0}, "resident memory grew"),
        ("leak of 20 kB a frame (RSS +6 %)", {"leak_kB_per_frame": 20.0}, "heap in use grew"),
        ("leak of 4 kB a frame (RSS +1 %)", {"leak_kB_per_frame": 4.0}, "heap in use leaks"),
        ("leak of 4 kB a frame after a step", {"leak_kB_per_frame": 4.0, "step_at": 0.55,
                                               "step_kB": 2400.0}, "heap in use leaks"),
        ("a step of 3 % at 55 % of the run, flat after", {"step_at": 0.55, "step_kB": 2400.0},
         None),
        ("report rows of 1 kB a frame (RSS +30 %)", {"rows_kB": 100.0}, None),
        ("NaN in the store", {"nan_at": 10}, "anchor store"),
        ("a restart not cut", {"drop_cut": True}, "cuts"),
        ("time of day back at each restart", {"reset_time_of_day": True}, "time of day"),
    ]
    ok = True
    for name, kwargs, expect in cases:
        report, replay = synthetic(**kwargs)
        failures = checks(figures(report, replay), limits)
        found = any(expect in msg for msg in failures) if expect else not failures
        ok = ok and found
        print(f"  {'ok  ' if found else 'FAIL'} {name}: {failures or 'no failure'}")
    for key, value, expect in [("anchorsMax", DEFAULT_MAX_ANCHORS + 1, "anchors reached"),
                               ("bytesMax", DEFAULT_MAX_STORE_KB * 1024 + 1, "store bytes")]:
        report, replay = synthetic()
        report["ambience"][key] = value
        found = any(expect in m for m in checks(figures(report, replay), limits))
        ok = ok and found
        print(f"  {'ok  ' if found else 'FAIL'} {key} over its bound")
    return 0 if ok else 1


def main():
    if sys.argv[1:] == ["--self-test"]:
        sys.exit(self_test())
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("report")
    p.add_argument("--replay", required=True)
    p.add_argument("--plot", required=True)
    p.add_argument("--wall-s", type=float, default=float("nan"))
    p.add_argument("--max-anchors", type=int, default=DEFAULT_MAX_ANCHORS)
    p.add_argument("--max-store-kB", type=float, default=DEFAULT_MAX_STORE_KB)
    p.add_argument("--rss-growth", type=float, default=DEFAULT_RSS_GROWTH)
    p.add_argument("--heap-growth", type=float, default=DEFAULT_HEAP_GROWTH)
    p.add_argument("--heap-leak", type=float, default=DEFAULT_HEAP_LEAK)
    args = p.parse_args()

    report = load(args.report)
    if not report.get("frames"):
        sys.exit(f"soak-plot.py: {args.report}: no frames")
    f = figures(report, load(args.replay))
    f["wall_s"] = args.wall_s
    plot(report, f, args.plot)
    for k, v in f.items():
        print(f"  {k}: {v:.4g}" if isinstance(v, float) else f"  {k}: {v}")
    print(f"  plot: {args.plot}")
    failures = checks(f, args)
    for msg in failures:
        print(f"soak: FAILED: {msg}", file=sys.stderr)
    if failures:
        sys.exit(1)
    print("soak: bounded, finite, every cut seen, time of day moving: ok")


if __name__ == "__main__":
    main()
