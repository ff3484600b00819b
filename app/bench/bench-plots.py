#!/usr/bin/env python3
"""Plots of a benchmark run of `ambience bench`: speed against error for every ambience method.

Usage: python3 bench-plots.py DIR

Reads DIR/results.csv (one row per replay x method x parameter point) and, for every row whose
status is "ok", DIR/<run_dir>/measure.csv (one row per measured frame). Writes PNG files into
DIR and prints the path of each file written, one a line. Errors are relative L2 distances of
the applied irradiance to a fresh capture (the oracle), so 0.1 is 10 %; see docs/ARCHITECTURE.md,
"Measuring speed against error".

Exit codes: 0 success; 2 bad usage, or results.csv missing or without any "ok" row; 3 matplotlib
is not installed (Debian: python3-matplotlib).

Sections:
  [1] Method colours and figure settings
  [2] Reading the CSV files
  [3] Shared helpers (axis scales, formatting)
  [4] Pareto front per replay       -> pareto-<replay>.png
  [5] Error against camera speed    -> error-vs-speed.png
  [6] Error over time per replay    -> error-over-time-<replay>.png
  [7] Error by witness ring         -> error-by-ring.png
  [8] Error budget (reference)      -> error-budget.png
  [9] Main
"""

import argparse
import csv
import math
import os
import re
import sys

try:
    import matplotlib

    matplotlib.use("Agg")  # files only: no display is needed or wanted
    import matplotlib.pyplot as plt
    from matplotlib import ticker
    import numpy as np
except ImportError as error:
    sys.stderr.write(
        f"bench-plots: cannot import matplotlib ({error}); install python3-matplotlib\n"
    )
    sys.exit(3)

# ---------------------------------------------------------------------------------------------
# [1] Method colours and figure settings
# ---------------------------------------------------------------------------------------------

# One colour and marker per method, the same in every plot. "volume" is the method of the
# thesis; the others are the baselines of the same harness.
METHOD_ORDER = ["volume", "nearest", "grid", "reactive", "object", "hemisphere", "constant"]
METHOD_COLOURS = {
    "volume": "#d62728",
    "nearest": "#1f77b4",
    "grid": "#2ca02c",
    "reactive": "#9467bd",
    "object": "#ff7f0e",
    "hemisphere": "#8c564b",
    "constant": "#7f7f7f",
}
METHOD_MARKERS = {
    "volume": "*",
    "nearest": "o",
    "grid": "s",
    "reactive": "D",
    "object": "^",
    "hemisphere": "v",
    "constant": "X",
}
# Methods not known above get these, in sorted name order, so a new method is still stable.
SPARE_COLOURS = ["#17becf", "#bcbd22", "#e377c2", "#393b79", "#637939", "#843c39"]
SPARE_MARKERS = ["P", "h", "<", ">", "p", "d"]

FIGURE_SIZE_IN = (8.0, 5.0)
MAX_MEASURE_BYTES = 256 << 20  # a measure.csv larger than this is not read
DPI = 110
DEFAULT_POINT = "default"
RING_COUNT = 4
RING_NAMES = [
    "ring 0\ncamera ground point",
    "ring 1\nnear patch corners",
    "ring 2\nmiddle patch corners",
    "ring 3\nfar patch corners",
]


def method_label(method):
    return "volume (ours)" if method == "volume" else method


def method_style(method, all_methods):
    """Colour and marker of a method; unknown methods take spares in sorted name order."""
    if method in METHOD_COLOURS:
        return METHOD_COLOURS[method], METHOD_MARKERS[method]
    unknown = sorted(m for m in all_methods if m not in METHOD_COLOURS)
    index = unknown.index(method) if method in unknown else 0
    return SPARE_COLOURS[index % len(SPARE_COLOURS)], SPARE_MARKERS[index % len(SPARE_MARKERS)]


def ordered_methods(methods):
    """Known methods in the fixed order, then unknown ones by name."""
    methods = set(methods)
    known = [m for m in METHOD_ORDER if m in methods]
    return known + sorted(methods - set(METHOD_ORDER))


# ---------------------------------------------------------------------------------------------
# [2] Reading the CSV files
# ---------------------------------------------------------------------------------------------

RESULT_NUMBER_COLUMNS = [
    "error_mean",
    "ambience_ms_median",
    "budget_total_rms",
    "budget_truncation",
    "budget_capture",
    "budget_spacing",
    "budget_schedule",
]
BUDGET_TERMS = [
    ("budget_truncation", "a: SH order-2 truncation", "#4c72b0"),
    ("budget_capture", "b: capture resolution and scene", "#55a868"),
    ("budget_spacing", "c: spacing and interpolation", "#c44e52"),
    ("budget_schedule", "d: schedule, staleness, blending (c + d without a lattice)", "#8172b2"),
]
MEASURE_COLUMNS = [
    "time_s",
    "time_of_day_h",
    "speed_mps",
    "error_mean",
    "error_ring0",
    "error_ring1",
    "error_ring2",
    "error_ring3",
]


def warn(message):
    sys.stderr.write(f"bench-plots: {message}\n")


def parse_number(text):
    """A finite float, or None for an empty, unparsable or non-finite field."""
    if text is None:
        return None
    text = text.strip()
    if not text:
        return None
    try:
        value = float(text)
    except ValueError:
        return None
    return value if math.isfinite(value) else None


def read_results(path):
    """Rows of results.csv as dicts; numeric columns parsed (None when missing)."""
    with open(path, newline="", encoding="utf-8") as file:
        reader = csv.DictReader(file)
        rows = []
        for line_number, raw in enumerate(reader, start=2):
            row = {
                "line": line_number,
                "replay": (raw.get("replay") or "").strip(),
                "method": (raw.get("method") or "").strip(),
                "point": (raw.get("point") or "").strip() or DEFAULT_POINT,
                "status": (raw.get("status") or "").strip().lower(),
                "run_dir": (raw.get("run_dir") or "").strip(),
            }
            for column in RESULT_NUMBER_COLUMNS:
                row[column] = parse_number(raw.get(column))
            if not row["replay"] or not row["method"]:
                warn(f"{path}:{line_number}: row without replay or method, ignored")
                continue
            rows.append(row)
    return rows


def read_measure(path):
    """Columns of a measure.csv as lists of float-or-None, all of the same length.

    A missing or empty file gives empty lists (with a warning for a missing file), so callers
    only ever see empty series, never an exception.
    """
    series = {column: [] for column in MEASURE_COLUMNS}
    if not os.path.isfile(path):
        warn(f"{path}: missing, method shown without per-frame data")
        return series
    # A run folder may have been in other hands (bench --collect): a link could lead anywhere.
    if os.path.islink(path) or os.path.getsize(path) > MAX_MEASURE_BYTES:
        warn(f"{path}: a symbolic link or larger than {MAX_MEASURE_BYTES} bytes, not read")
        return series
    with open(path, newline="", encoding="utf-8") as file:
        for raw in csv.DictReader(file):
            for column in MEASURE_COLUMNS:
                series[column].append(parse_number(raw.get(column)))
    return series


def load_measures(directory, ok_rows):
    """measure.csv of every ok row, keyed by id(row); each file read once."""
    by_path = {}
    measures = {}
    for row in ok_rows:
        if not row["run_dir"]:
            warn(f"results.csv:{row['line']}: ok row without run_dir")
            measures[id(row)] = {column: [] for column in MEASURE_COLUMNS}
            continue
        path = os.path.join(directory, row["run_dir"], "measure.csv")
        if path not in by_path:
            by_path[path] = read_measure(path)
        measures[id(row)] = by_path[path]
    return measures


def default_rows(ok_rows):
    """The default-parameter ok row of each (replay, method); the first one if repeated."""
    chosen = {}
    for row in ok_rows:
        if row["point"] != DEFAULT_POINT:
            continue
        key = (row["replay"], row["method"])
        if key in chosen:
            warn(f"results.csv:{row['line']}: second default row for {key}, ignored")
            continue
        chosen[key] = row
    return chosen


def paired(series, x_column, y_column):
    """(x, y) pairs of a measure where both values are present."""
    return [
        (x, y)
        for x, y in zip(series[x_column], series[y_column])
        if x is not None and y is not None
    ]


# ---------------------------------------------------------------------------------------------
# [3] Shared helpers
# ---------------------------------------------------------------------------------------------


def file_name_part(text):
    """A replay name made safe as part of a file name."""
    safe = re.sub(r"[^A-Za-z0-9._-]+", "_", text).strip("._")
    return safe or "replay"


def percent_text(fraction):
    return f"{fraction * 100:.3g} %"


def set_error_axis(axis, values, label, force_log=False):
    """Relative errors in percent on the y axis; log when they span more than a decade."""
    positive = [v for v in values if v is not None and v > 0]
    use_log = force_log or (len(positive) >= 2 and max(positive) > 10 * min(positive))
    formatter = ticker.FuncFormatter(lambda v, _: percent_text(v))
    if use_log and positive:
        axis.set_yscale("log")
        # Ticks at 1-2-5 per decade while that still leaves room for the labels, so a plot
        # spanning one or two decades still has several labelled ticks.
        decades = math.log10(max(positive) / min(positive))
        subs = (1.0, 2.0, 5.0) if decades <= 3.0 else (1.0,)
        axis.yaxis.set_major_locator(ticker.LogLocator(base=10.0, subs=subs))
        axis.yaxis.set_minor_formatter(ticker.NullFormatter())
    axis.yaxis.set_major_formatter(formatter)
    axis.set_ylabel(label)


def place_legend(axis, **options):
    """Legend to the right of the axes, where it never hides data."""
    axis.legend(fontsize=8, loc="upper left", bbox_to_anchor=(1.01, 1.0), borderaxespad=0.0,
                **options)


def set_cost_axis(axis, costs):
    """Cost per frame in ms on the x axis: symlog when zero-cost methods share the plot with
    costly ones, log when all costs are positive and span decades, linear otherwise."""
    positive = [c for c in costs if c > 0]
    has_zero = any(c <= 0 for c in costs)
    spans_decades = len(positive) >= 2 and max(positive) > 30 * min(positive)
    if positive and has_zero:
        # The linear region around zero reaches up to the decade of the cheapest costly point,
        # so near-zero methods sit at the left edge and the costly ones keep a log scale.
        linear_threshold = 10 ** math.floor(math.log10(min(positive)))
        axis.set_xscale("symlog", linthresh=linear_threshold, linscale=0.6)
        axis.set_xlim(left=-0.15 * linear_threshold, right=max(positive) * 2.0)
    elif spans_decades and not has_zero:
        axis.set_xscale("log")
    axis.xaxis.set_major_formatter(ticker.FuncFormatter(lambda v, _: f"{v:g}"))


def new_figure():
    return plt.subplots(figsize=FIGURE_SIZE_IN, dpi=DPI)


def save(figure, directory, name, written):
    path = os.path.join(directory, name)
    # A link planted at a plot's name is replaced, never written through.
    if os.path.islink(path):
        os.unlink(path)
    figure.savefig(path, dpi=DPI)
    plt.close(figure)
    written.append(path)
    print(path, flush=True)


def show_empty(axis, message):
    axis.text(0.5, 0.5, message, transform=axis.transAxes, ha="center", va="center", color="0.4")


def hours_text(hours):
    """A time of day in hours as HH:MM (wrapped to one day)."""
    minutes = int(round((hours % 24.0) * 60.0)) % (24 * 60)
    return f"{minutes // 60:02d}:{minutes % 60:02d}"


# ---------------------------------------------------------------------------------------------
# [4] Pareto front per replay
# ---------------------------------------------------------------------------------------------


def pareto_front(points):
    """Points (cost, error) not beaten by any point of at most the same cost, by cost."""
    front = []
    best_error = math.inf
    for cost, error in sorted(points):
        if error < best_error:
            front.append((cost, error))
            best_error = error
    return front


def plot_pareto(directory, replay, rows, all_methods, written):
    figure, axis = new_figure()
    ok_rows = [r for r in rows if r["status"] == "ok"]
    plotted = [
        r for r in ok_rows if r["ambience_ms_median"] is not None and r["error_mean"] is not None
    ]
    missing = [r for r in ok_rows if r not in plotted]
    failed = [r for r in rows if r["status"] != "ok"]

    costs = [max(r["ambience_ms_median"], 0.0) for r in plotted]
    errors = [r["error_mean"] for r in plotted]
    if plotted:
        set_cost_axis(axis, costs)
    set_error_axis(axis, errors, "mean relative irradiance error")

    for method in ordered_methods(r["method"] for r in plotted):
        colour, marker = method_style(method, all_methods)
        own = [r for r in plotted if r["method"] == method]
        is_ours = method == "volume"
        axis.scatter(
            [max(r["ambience_ms_median"], 0.0) for r in own],
            [r["error_mean"] for r in own],
            color=colour,
            marker=marker,
            s=170 if is_ours else 50,
            edgecolors="black" if is_ours else "none",
            linewidths=0.8,
            zorder=4 if is_ours else 3,
            label=method_label(method),
        )
        # Sweep points are named so they can be found in results.csv; the default is unnamed.
        for row in own:
            if row["point"] != DEFAULT_POINT:
                axis.annotate(
                    row["point"],
                    (max(row["ambience_ms_median"], 0.0), row["error_mean"]),
                    xytext=(4, 3),
                    textcoords="offset points",
                    fontsize=7,
                    color=colour,
                )

    front = pareto_front(list(zip(costs, errors)))
    if front:
        # Step line: for a cost budget x, the lowest error any method reaches at cost <= x.
        right = max(costs) * 2.0 if max(costs) > 0 else 1.0
        xs = [c for c, _ in front] + [right]
        ys = [e for _, e in front] + [front[-1][1]]
        axis.step(
            xs,
            ys,
            where="post",
            color="black",
            linewidth=1.0,
            linestyle="--",
            alpha=0.7,
            zorder=2,
            label="Pareto front",
        )
        axis.set_xlim(right=right)

    if not plotted:
        show_empty(axis, "no ok row with both cost and error")
    notes = [f"{r['method']} {r['point']}" for r in failed]
    footnote = []
    if notes:
        footnote.append("failed (not shown): " + ", ".join(notes))
    if missing:
        footnote.append(
            "no cost or error: " + ", ".join(f"{r['method']} {r['point']}" for r in missing)
        )
    if footnote:
        text = "; ".join(footnote)
        figure.text(0.01, 0.01, text if len(text) < 140 else text[:137] + "...", fontsize=7)

    axis.set_xlabel("ambience time per frame, median [ms]")
    axis.set_title(f"Cost against error, replay {replay}")
    axis.grid(True, which="major", alpha=0.3)
    if plotted:
        place_legend(axis)
    figure.tight_layout(rect=(0, 0.03, 1, 1))
    save(figure, directory, f"pareto-{file_name_part(replay)}.png", written)


# ---------------------------------------------------------------------------------------------
# [5] Error against camera speed
# ---------------------------------------------------------------------------------------------

# Candidate bin edges in m/s: fine at walking speeds, doubling at flying speeds; extended by
# doubling beyond the last one when a replay goes faster.
SPEED_LADDER_MPS = [0.0, 0.5, 1.0, 2.0, 5.0, 10.0, 20.0, 40.0, 80.0, 160.0, 320.0]
MAX_SPEED_BINS = 8


def speed_bins(speeds):
    """Bin edges adapted to the pooled speeds: ladder edges up to the fastest frame, then
    sparse bins merged into neighbours so each holds a useful share of the frames."""
    fastest = max(speeds)
    ladder = list(SPEED_LADDER_MPS)
    while ladder[-1] <= fastest:
        ladder.append(ladder[-1] * 2.0)
    edges = [e for e in ladder if e <= fastest]
    edges.append(next(e for e in ladder if e > fastest))

    def counts(edges):
        return [
            sum(1 for s in speeds if edges[i] <= s < edges[i + 1]) for i in range(len(edges) - 1)
        ]

    minimum = max(3, math.ceil(0.03 * len(speeds)))
    while len(edges) > 2:
        bin_counts = counts(edges)
        smallest = min(range(len(bin_counts)), key=lambda i: bin_counts[i])
        if bin_counts[smallest] >= minimum and len(bin_counts) <= MAX_SPEED_BINS:
            break
        # Merge the sparsest bin with its sparser neighbour by dropping the edge between them.
        if smallest == 0:
            del edges[1]
        elif smallest == len(bin_counts) - 1:
            del edges[-2]
        elif bin_counts[smallest - 1] <= bin_counts[smallest + 1]:
            del edges[smallest]
        else:
            del edges[smallest + 1]
    return edges


def plot_error_vs_speed(directory, defaults, measures, all_methods, written):
    figure, axis = new_figure()
    samples = {}  # method -> [(speed_mps, error_mean)]
    for (_, method), row in defaults.items():
        pairs = paired(measures[id(row)], "speed_mps", "error_mean")
        samples.setdefault(method, []).extend((max(s, 0.0), e) for s, e in pairs)
    samples = {m: p for m, p in samples.items() if p}
    methods = ordered_methods(samples)

    if not methods:
        show_empty(axis, "no measured frames with speed and error")
        set_error_axis(axis, [], "mean relative irradiance error per frame")
    else:
        edges = speed_bins([s for pairs in samples.values() for s, _ in pairs])
        bin_count = len(edges) - 1

        def bin_of(speed):
            for i in range(bin_count):
                if speed < edges[i + 1]:
                    return i
            return bin_count - 1

        width = 0.8 / len(methods)
        all_values = []
        for index, method in enumerate(methods):
            colour, marker = method_style(method, all_methods)
            per_bin = [[] for _ in range(bin_count)]
            for speed, error in samples[method]:
                per_bin[bin_of(speed)].append(error)
            xs, medians, lows, highs = [], [], [], []
            for i, errors in enumerate(per_bin):
                if not errors:
                    continue
                low, median, high = np.percentile(errors, [5, 50, 95])
                xs.append(i - 0.4 + width * (index + 0.5))
                medians.append(median)
                lows.append(median - low)
                highs.append(high - median)
                all_values.extend([low, median, high])
            is_ours = method == "volume"
            axis.errorbar(
                xs,
                medians,
                yerr=[lows, highs],
                color=colour,
                marker=marker,
                markersize=9 if is_ours else 5,
                markeredgecolor="black" if is_ours else colour,
                linewidth=1.8 if is_ours else 0.9,
                elinewidth=1.2,
                capsize=2,
                zorder=4 if is_ours else 3,
                label=method_label(method),
            )
        # Frames per bin of the method with the most there (methods share the replays, so
        # this is the frame count of the bin, not multiplied by the number of methods).
        labels = []
        for i in range(bin_count):
            count = max(sum(1 for s, _ in pairs if bin_of(s) == i) for pairs in samples.values())
            labels.append(f"{edges[i]:g}-{edges[i + 1]:g}\n({count} frames)")
        axis.set_xticks(range(bin_count))
        axis.set_xticklabels(labels, fontsize=8)
        axis.set_xlim(-0.5, bin_count - 0.5)
        set_error_axis(axis, all_values, "mean relative irradiance error per frame", True)
        place_legend(axis, title="median,\n5-95 % whisker", title_fontsize=8)
    axis.set_xlabel("camera speed bin [m/s] (default parameters, all replays)")
    axis.set_title("Error against camera speed")
    axis.grid(True, which="major", axis="y", alpha=0.3)
    figure.tight_layout()
    save(figure, directory, "error-vs-speed.png", written)


# ---------------------------------------------------------------------------------------------
# [6] Error over time per replay
# ---------------------------------------------------------------------------------------------


def time_of_day_mapping(pairs):
    """A linear map time_s -> time of day [h], or None when the clock is not linear in the
    replay time (then the title states the range instead). Wraps past midnight are unwrapped."""
    pairs = sorted(pairs)
    if len(pairs) < 2:
        return None
    times = [t for t, _ in pairs]
    hours = []
    offset = 0.0
    for _, hour in pairs:
        if hours and hour + offset < hours[-1] - 12.0:
            offset += 24.0
        hours.append(hour + offset)
    if times[-1] - times[0] <= 0:
        return None
    slope, intercept = np.polyfit(times, hours, 1)
    residual = max(abs(h - (slope * t + intercept)) for t, h in zip(times, hours))
    # A visible secondary axis needs the clock to move (> 1 minute over the replay) linearly.
    if slope * (times[-1] - times[0]) < 1.0 / 60.0 or residual > 1.0 / 60.0:
        return None
    return slope, intercept


def plot_error_over_time(directory, replay, defaults, measures, all_methods, written):
    figure, axis = new_figure()
    rows = {m: r for (rp, m), r in defaults.items() if rp == replay}
    all_errors = []
    clock = []
    without_frames = []
    drawn = False
    for method in ordered_methods(rows):
        series = measures[id(rows[method])]
        pairs = sorted(paired(series, "time_s", "error_mean"))
        clock.extend(paired(series, "time_s", "time_of_day_h"))
        if not pairs:
            without_frames.append(method)
            continue
        colour, _ = method_style(method, all_methods)
        is_ours = method == "volume"
        axis.plot(
            [t for t, _ in pairs],
            [e for _, e in pairs],
            color=colour,
            linewidth=1.8 if is_ours else 0.9,
            alpha=1.0 if is_ours else 0.85,
            zorder=4 if is_ours else 3,
            label=method_label(method),
        )
        all_errors.extend(e for _, e in pairs)
        drawn = True

    set_error_axis(axis, all_errors, "mean relative irradiance error per frame", drawn)
    axis.set_xlabel("replay time [s]")
    title = f"Error over time, replay {replay} (default parameters)"
    mapping = time_of_day_mapping(clock)
    if mapping is not None:
        slope, intercept = mapping
        top = axis.secondary_xaxis(
            "top", functions=(lambda t: slope * t + intercept, lambda h: (h - intercept) / slope)
        )
        top.xaxis.set_major_formatter(ticker.FuncFormatter(lambda h, _: hours_text(h)))
        top.set_xlabel("time of day [hh:mm]")
    elif clock:
        hours = [h for _, h in clock]
        low, high = min(hours), max(hours)
        if high - low < 1.0 / 60.0:
            title += f"\ntime of day {hours_text(low)}"
        else:
            title += f"\ntime of day {hours_text(low)} to {hours_text(high)}"
    axis.set_title(title)
    if drawn:
        place_legend(axis)
    else:
        show_empty(axis, "no measured frames with time and error")
    if without_frames:
        figure.text(0.01, 0.01, "no measured frames: " + ", ".join(without_frames), fontsize=7)
    axis.grid(True, which="major", alpha=0.3)
    figure.tight_layout(rect=(0, 0.03 if without_frames else 0, 1, 1))
    save(figure, directory, f"error-over-time-{file_name_part(replay)}.png", written)


# ---------------------------------------------------------------------------------------------
# [7] Error by witness ring
# ---------------------------------------------------------------------------------------------


def plot_error_by_ring(directory, defaults, measures, all_methods, written):
    figure, axis = new_figure()
    # Mean over frames within each replay first, then over replays, so a long replay does not
    # outweigh a short one.
    per_method = {}  # method -> [ring] -> [mean per replay]
    for (_, method), row in defaults.items():
        series = measures[id(row)]
        rings = per_method.setdefault(method, [[] for _ in range(RING_COUNT)])
        for ring in range(RING_COUNT):
            values = [v for v in series[f"error_ring{ring}"] if v is not None]
            if values:
                rings[ring].append(sum(values) / len(values))
    means = {
        m: [sum(v) / len(v) if v else None for v in rings] for m, rings in per_method.items()
    }
    methods = [m for m in ordered_methods(means) if any(v is not None for v in means[m])]

    if not methods:
        show_empty(axis, "no measured frames with ring errors")
        set_error_axis(axis, [], "mean relative irradiance error")
    else:
        width = 0.8 / len(methods)
        values = [v for m in methods for v in means[m] if v is not None]
        for index, method in enumerate(methods):
            colour, _ = method_style(method, all_methods)
            xs = [ring - 0.4 + width * (index + 0.5) for ring in range(RING_COUNT)]
            heights = [v if v is not None else 0.0 for v in means[method]]
            is_ours = method == "volume"
            axis.bar(
                xs,
                heights,
                width=width * 0.95,
                color=colour,
                edgecolor="black" if is_ours else "none",
                linewidth=1.0,
                label=method_label(method),
            )
        set_error_axis(axis, values, "mean relative irradiance error")
        if axis.get_yscale() == "log":
            positive = [v for v in values if v > 0]
            axis.set_ylim(bottom=min(positive) / 2.0, top=max(positive) * 1.5)
        axis.set_xticks(range(RING_COUNT))
        axis.set_xticklabels(RING_NAMES, fontsize=8)
        axis.set_xlim(-0.5, RING_COUNT - 0.5)
        place_legend(axis)
    axis.set_xlabel("witness points (default parameters; mean over frames, then over replays)")
    axis.set_title("Error by distance from the camera")
    axis.grid(True, which="major", axis="y", alpha=0.3)
    figure.tight_layout()
    save(figure, directory, "error-by-ring.png", written)


# ---------------------------------------------------------------------------------------------
# [8] Error budget (reference oracle)
# ---------------------------------------------------------------------------------------------


def budget_rows(ok_rows):
    """Per (replay, method) the row carrying the full error budget: the first with a spacing
    term (its runs captured the ideal volume), else the first with any budget."""
    chosen = {}
    for row in ok_rows:
        if row["budget_total_rms"] is None:
            continue
        key = (row["replay"], row["method"])
        has_spacing = row["budget_spacing"] is not None
        if key not in chosen or (has_spacing and chosen[key]["budget_spacing"] is None):
            chosen[key] = row
    return chosen


def plot_error_budget(directory, ok_rows, written):
    """Squared terms stacked per replay and method, the squared total as a marker: where they
    meet, the terms add up as squares."""
    chosen = budget_rows(ok_rows)
    if not chosen:
        return
    replays = sorted({replay for replay, _ in chosen})
    methods = ordered_methods({method for _, method in chosen})
    figure, axis = plt.subplots(figsize=(max(8.0, 1.2 * len(replays) * len(methods) / 3), 5.0))
    width = 0.8 / len(methods)
    labelled = set()
    for r_index, replay in enumerate(replays):
        for m_index, method in enumerate(methods):
            row = chosen.get((replay, method))
            if row is None:
                continue
            x = r_index - 0.4 + width * (m_index + 0.5)
            bottom = 0.0
            for column, label, colour in BUDGET_TERMS:
                value = row[column]
                if value is None:
                    continue
                height = value * value
                axis.bar(x, height, width=width * 0.9, bottom=bottom, color=colour,
                         edgecolor="black" if method == "volume" else "none", linewidth=0.8,
                         label=None if label in labelled else label)
                labelled.add(label)
                bottom += height
            total = row["budget_total_rms"]
            axis.plot([x], [total * total], marker="_", markersize=14, color="black",
                      label=None if "total" in labelled else "total² (method against reference)")
            labelled.add("total")
            axis.text(x, 0.0, method_label(method), rotation=90, fontsize=6, ha="center",
                      va="bottom", color="white")
    # A method that blows up (a stale daylight probe against a night oracle reads as thousands)
    # would flatten the rest: the axis ends above the largest total of 1.2 or less, and bars
    # beyond it are marked with their total.
    totals = [row["budget_total_rms"] for row in chosen.values()]
    sane = [t * t for t in totals if t <= 1.2]
    top = 1.15 * max(sane) if sane else None
    if top is not None:
        axis.set_ylim(0.0, top)
        for r_index, replay in enumerate(replays):
            for m_index, method in enumerate(methods):
                row = chosen.get((replay, method))
                if row is not None and row["budget_total_rms"] ** 2 > top:
                    x = r_index - 0.4 + width * (m_index + 0.5)
                    axis.text(x, top * 0.98, f"{row['budget_total_rms']:.3g}", rotation=90,
                              fontsize=6, ha="center", va="top")
    axis.set_xticks(range(len(replays)))
    axis.set_xticklabels(replays, fontsize=8)
    axis.set_ylabel("squared relative error (RMS over witnesses)²")
    axis.set_title("Error budget against the reference (ours outlined)")
    axis.grid(True, axis="y", alpha=0.3)
    place_legend(axis)
    figure.tight_layout()
    save(figure, directory, "error-budget.png", written)


# ---------------------------------------------------------------------------------------------
# [9] Main
# ---------------------------------------------------------------------------------------------


def main():
    parser = argparse.ArgumentParser(description="Plots of an `ambience bench` run directory.")
    parser.add_argument("directory", help="run directory holding results.csv")
    arguments = parser.parse_args()
    directory = arguments.directory

    results_path = os.path.join(directory, "results.csv")
    if not os.path.isfile(results_path):
        warn(f"{results_path}: not found; nothing to plot")
        return 2
    rows = read_results(results_path)
    ok_rows = [r for r in rows if r["status"] == "ok"]
    if not ok_rows:
        warn(f"{results_path}: no row with status ok ({len(rows)} rows); nothing to plot")
        return 2

    measures = load_measures(directory, ok_rows)
    defaults = default_rows(ok_rows)
    all_methods = {r["method"] for r in rows}
    replays = sorted({r["replay"] for r in rows})
    written = []

    for replay in replays:
        plot_pareto(directory, replay, [r for r in rows if r["replay"] == replay], all_methods,
                    written)
    plot_error_vs_speed(directory, defaults, measures, all_methods, written)
    for replay in replays:
        if any(rp == replay for rp, _ in defaults):
            plot_error_over_time(directory, replay, defaults, measures, all_methods, written)
    plot_error_by_ring(directory, defaults, measures, all_methods, written)
    plot_error_budget(directory, ok_rows, written)
    return 0


if __name__ == "__main__":
    sys.exit(main())
