#!/usr/bin/python3
"""Plots and report of a `vio sweep` folder (run by `vio sweep`; needs numpy and matplotlib).

Reads SWEEP_DIR/results.csv, SWEEP_DIR/results.md and the plot data `vio sweep` writes under
SWEEP_DIR/plots/data/<dataset>/ (groundtruth.csv and <policy>_<window>.csv: the estimate after
position + yaw alignment, with its position error), and writes:

  plots/trajectories_<dataset>.png    top view (x-y) of every run over the ground truth, equal axes,
                                      and a zoom on the stretch where the runs are furthest apart
  plots/position_error_<dataset>.png  position error over time, one line per run
  plots/ate_vs_cost.png               ATE RMSE against estimator time per frame, per policy and window
  plots/nees.png                      (Monte Carlo sweeps, plots/data/nees/<policy>_<window>.csv) the
                                      pose NEES over time, mean over the seeds, per configuration, with
                                      its 95% chi-square band
  report.md                           the results table and every plot in one page

Every run keeps one colour, marker and line style in all plots (colour per run, marker and
dashes per policy).

usage: plot_sweep.py --sweep_dir SWEEP_DIR
"""
import argparse
import csv
import math
import os
import sys

import matplotlib

matplotlib.use("Agg")
import matplotlib.patches  # noqa: E402
import matplotlib.pyplot as plt  # noqa: E402
import matplotlib.ticker  # noqa: E402
import numpy as np  # noqa: E402

DPI = 90
ALIGNMENT = "estimates aligned to the ground truth in position + yaw"
DATASET_FILLS = ("full", "none", "left", "bottom")  # ATE-against-cost marker fill per dataset
GROUND_TRUTH = {"color": "0.55", "lw": 5.0, "alpha": 0.45, "solid_capstyle": "round", "zorder": 1}
POLICY_LOOKS = [("o", "-"), ("s", "--"), ("^", "-."), ("D", ":"), ("v", (0, (5, 1, 1, 1))), ("P", (0, (1, 1)))]


def read_results(sweep_dir):
    with open(os.path.join(sweep_dir, "results.csv"), newline="") as f:
        return list(csv.DictReader(f))


def read_columns(path):
    data = np.genfromtxt(path, delimiter=",", names=True)
    return np.atleast_1d(data)


def number(text):
    return float(text) if text not in ("", None) else math.nan


def run_key(row):
    return (row["policy"], int(row["window"]))


def run_label(policy, window):
    return f"{policy} w={window}"


def run_styles(rows):
    """Style per (policy, window): a colour of its own (tab10 in the order of the
    first appearance, sorted by policy then window), marker and dashes per policy."""
    keys = sorted({run_key(row) for row in rows}, key=lambda k: (k[0], k[1]))
    policies = list(dict.fromkeys(policy for policy, _ in keys))
    palette = plt.cm.tab10.colors if len(keys) <= 10 else plt.cm.tab20.colors
    styles = {}
    for i, (policy, window) in enumerate(keys):
        marker, dashes = POLICY_LOOKS[policies.index(policy) % len(POLICY_LOOKS)]
        styles[(policy, window)] = {"color": palette[i % len(palette)], "marker": marker, "ls": dashes}
    return styles


def runs_of(data_dir, rows, dataset, styles):
    """(label, style, data) of every run of `dataset` with plot data, in results.csv order."""
    runs = []
    for row in rows:
        if row["dataset"] != dataset:
            continue
        path = os.path.join(data_dir, f"{row['policy']}_{row['window']}.csv")
        if os.path.exists(path):
            runs.append((run_label(*run_key(row)), styles[run_key(row)], read_columns(path)))
    return runs


def line_style(style, num_points, markers=12):
    """Matplotlib keywords for a line: its colour and dashes, a marker every 1/`markers` of it."""
    return {"color": style["color"], "ls": style["ls"], "marker": style["marker"], "ms": 5,
            "markevery": max(1, num_points // markers), "mfc": "white", "mew": 1.2}


def wide_range(values, ratio=20.0):
    """True when the positive values span more than `ratio` (then a log axis reads better)."""
    values = [v for v in values if math.isfinite(v) and v > 0]
    return len(values) > 1 and max(values) > ratio * min(values)


def label_log_axis(axis, low, high):
    """A log axis with at least three labelled ticks written as plain numbers (0.02, 5, 200):
    every decade; also the 2s and 5s when it spans less than three decades; every digit
    when it spans less than one."""
    decades = math.log10(high / low) if low > 0 and high > low else 0.0
    subs = (1.0, 2.0, 3.0, 5.0, 7.0) if decades < 1 else (1.0, 2.0, 5.0) if decades < 3 else (1.0,)
    axis.set_major_locator(matplotlib.ticker.LogLocator(base=10, subs=subs))
    axis.set_major_formatter(matplotlib.ticker.FuncFormatter(lambda v, _: f"{v:g}"))
    axis.set_minor_locator(matplotlib.ticker.LogLocator(base=10, subs=np.arange(1, 10)))
    axis.set_minor_formatter(matplotlib.ticker.NullFormatter())


def legend_outside(ax):
    ax.legend(loc="upper left", bbox_to_anchor=(1.02, 1.0), fontsize=8, handlelength=3)


def worst_window(runs, half_width_s=4.0):
    """Time span around the moment the runs disagree most with the ground truth."""
    t_worst, e_worst = 0.0, -1.0
    for _, _, run in runs:
        k = int(np.nanargmax(run["error_m"]))
        if run["error_m"][k] > e_worst:
            t_worst, e_worst = float(run["t_s"][k]), float(run["error_m"][k])
    return t_worst - half_width_s, t_worst + half_width_s


def draw_top_view(ax, groundtruth, runs, t_span=None, markers=12):
    def part(data):
        if t_span is None:
            return data
        return data[(data["t_s"] >= t_span[0]) & (data["t_s"] <= t_span[1])]

    gt = part(groundtruth)
    ax.plot(gt["x_m"], gt["y_m"], label="ground truth", **GROUND_TRUTH)
    for label, style, run in runs:
        r = part(run)
        ax.plot(r["x_m"], r["y_m"], lw=1.3, label=label, zorder=3, **line_style(style, len(r), markers))
    ax.set_aspect("equal", adjustable="datalim")
    ax.grid(True, alpha=0.3)
    ax.set_xlabel("x [m]")
    ax.set_ylabel("y [m]")
    return gt


def plot_trajectories(dataset, groundtruth, runs, out_path):
    """Whole flight on the left (axes fit the ground truth, so one diverged run cannot hide
    the others), the 8 s around the largest error on the right, where the runs separate."""
    fig, (ax, zoom) = plt.subplots(1, 2, figsize=(13, 5.8), gridspec_kw={"width_ratios": [1.35, 1]})
    x, y = groundtruth["x_m"], groundtruth["y_m"]
    margin = max(0.08 * max(np.ptp(x), np.ptp(y)), 0.3)
    draw_top_view(ax, groundtruth, runs)
    ax.plot(x[0], y[0], "o", color="black", ms=7, zorder=5, label="start")
    ax.set_xlim(x.min() - margin, x.max() + margin)
    ax.set_ylim(y.min() - margin, y.max() + margin)
    ax.set_title("whole flight")
    t_span = worst_window(runs)
    gt = draw_top_view(zoom, groundtruth, runs, t_span, markers=8)
    if len(gt):
        pad = 0.1 * max(np.ptp(gt["x_m"]), np.ptp(gt["y_m"]), 0.5)
        ax.add_patch(matplotlib.patches.Rectangle(
            (gt["x_m"].min() - pad, gt["y_m"].min() - pad), np.ptp(gt["x_m"]) + 2 * pad,
            np.ptp(gt["y_m"]) + 2 * pad, fill=False, edgecolor="red", lw=1.5, zorder=6, label="zoomed stretch"))
        zoom.plot(gt["x_m"][0], gt["y_m"][0], ">", color="black", ms=7, zorder=5)
    zoom.set_title(f"zoom: t = {max(t_span[0], 0):.0f}-{t_span[1]:.0f} s, around the largest error")
    handles, labels = ax.get_legend_handles_labels()
    fig.legend(handles, labels, loc="center right", fontsize=8, handlelength=3)
    fig.suptitle(f"{dataset}: top view, {ALIGNMENT}")
    fig.tight_layout(rect=(0, 0, 0.87, 1))
    fig.savefig(out_path, dpi=DPI)
    plt.close(fig)


def plot_errors(dataset, runs, out_path):
    fig, ax = plt.subplots(figsize=(10, 4.2))
    for label, style, run in runs:
        ax.plot(run["t_s"], run["error_m"], lw=1.2, label=label, **line_style(style, len(run)))
    ax.set_xlabel("time since the first ground-truth sample [s]")
    medians = [float(np.median(run["error_m"])) for _, _, run in runs]
    if wide_range(medians):
        ax.set_yscale("log")
        errors = np.concatenate([run["error_m"] for _, _, run in runs])
        positive = errors[errors > 0]
        label_log_axis(ax.yaxis, positive.min(), positive.max())
        ax.set_ylabel("position error [m] (log scale)")
    else:
        ax.set_ylim(bottom=0)
        ax.set_ylabel("position error [m]")
    ax.set_title(f"{dataset}: position error over time, {ALIGNMENT}")
    ax.grid(True, which="major", alpha=0.3)
    legend_outside(ax)
    fig.tight_layout()
    fig.savefig(out_path, dpi=DPI)
    plt.close(fig)


def finish(fig, ax, out_path):
    """Grid, legend outside, saved and closed."""
    ax.grid(True, which="major", alpha=0.3)
    legend_outside(ax)
    fig.tight_layout()
    fig.savefig(out_path, dpi=DPI)
    plt.close(fig)


def plot_ate_vs_cost(rows, styles, out_path):
    """One line per (dataset, policy) through its window sizes; each point has its run's colour
    and marker and is labelled w=N."""
    series = {}
    for row in rows:
        ate, cost = number(row["ate_rmse_m"]), number(row["ms_per_frame"])
        if row["status"] == "ok" and math.isfinite(ate) and math.isfinite(cost) and cost > 0:
            series.setdefault((row["dataset"], row["policy"]), []).append((cost, ate, int(row["window"])))
    if not series:
        return False
    datasets = sorted({d for d, _ in series})
    fig, ax = plt.subplots(figsize=(9, 4.8))
    labelled = set()
    for (dataset, policy), points in sorted(series.items()):
        points.sort(key=lambda p: p[2])
        costs, ates, windows = zip(*points)
        look = styles[(policy, windows[0])]
        fill = DATASET_FILLS[datasets.index(dataset) % len(DATASET_FILLS)]
        ax.plot(costs, ates, color="0.6", ls=look["ls"], lw=1.0, zorder=1)
        for cost, ate, window in points:
            s = styles[(policy, window)]
            label = run_label(policy, window)
            ax.plot([cost], [ate], ls="none", marker=s["marker"], ms=8, color=s["color"], zorder=3,
                    fillstyle=fill, mfcalt="white", mew=1.5,
                    label=None if label in labelled else label)
            labelled.add(label)
            ax.annotate(f"w={window}", (cost, ate), textcoords="offset points", xytext=(6, 5), fontsize=8)
    if len(datasets) > 1:
        for i, dataset in enumerate(datasets):
            fill = DATASET_FILLS[i % len(DATASET_FILLS)]
            ax.plot([], [], ls="none", marker="o", ms=8, color="black", fillstyle=fill,
                    mfcalt="white", mew=1.5, label=dataset)
    costs = [c for points in series.values() for c, _, _ in points]
    ates = [a for points in series.values() for _, a, _ in points]
    ax.set_xscale("log")
    ax.set_xlim(min(costs) / 1.6, max(costs) * 1.6)
    label_log_axis(ax.xaxis, *ax.get_xlim())
    ax.set_xlabel("estimator time per frame [ms] (log scale)")
    if wide_range(ates):
        ax.set_yscale("log")
        ax.set_ylim(min(ates) / 1.5, max(ates) * 1.5)
        label_log_axis(ax.yaxis, *ax.get_ylim())
        ax.set_ylabel("ATE RMSE [m] (log scale)")
    else:
        ax.set_ylim(0, 1.2 * max(ates))
        ax.set_ylabel("ATE RMSE [m]")
    where = datasets[0] if len(datasets) == 1 else f"{len(datasets)} datasets"
    ax.set_title(f"{where}: accuracy against cost (w = window size [frames]; lower left is better)\n"
                 f"ATE after position + yaw alignment", fontsize=11)
    finish(fig, ax, out_path)
    return True


def plot_nees(nees_dir, rows, styles, out_path):
    """Run-mean pose NEES over time per configuration, the 95% band of a consistent estimator
    and the 6 it should average to; log scale (over-confident runs are orders of magnitude off)."""
    runs = []
    for key in dict.fromkeys(run_key(row) for row in rows):
        path = os.path.join(nees_dir, f"{key[0]}_{key[1]}.csv")
        if os.path.exists(path):
            runs.append((run_label(*key), styles[key], read_columns(path)))
    if not runs:
        return False
    fig, ax = plt.subplots(figsize=(10, 4.6))
    band = runs[0][2]
    ax.fill_between(band["t_s"], band["lower"], band["upper"], color="0.8", alpha=0.6, lw=0,
                    label="95% bounds (consistent)")
    ax.axhline(6.0, color="0.35", lw=1.0, ls=":", label="6 (pose dof)")
    for label, style, run in runs:
        ax.plot(run["t_s"], run["nees_pose"], lw=1.2, label=label, **line_style(style, len(run)))
    values = np.concatenate([run["nees_pose"] for _, _, run in runs] + [band["lower"], band["upper"]])
    positive = values[values > 0]
    ax.set_yscale("log")
    label_log_axis(ax.yaxis, positive.min(), positive.max())
    ax.set_xlabel("time since the first frame every run estimated [s]")
    ax.set_ylabel("pose NEES, mean over the seeds (log scale)")
    ax.set_title("Consistency: pose NEES (6 dof) over time, aligned at the first pose (position + yaw)")
    finish(fig, ax, out_path)
    return True


def write_report(sweep_dir, rows, written):
    """report.md: results.md (title, table, notes) followed by every plot."""
    results_md = os.path.join(sweep_dir, "results.md")
    table = open(results_md).read().rstrip() + "\n" if os.path.exists(results_md) else ""
    lines = [table, "## Plots", ""]
    captions = {"trajectories": "Top view", "position_error": "Position error over time",
                "nees": "Pose NEES over time"}
    for path in written:
        name = os.path.splitext(os.path.basename(path))[0]
        caption = captions.get(name) or next((f"{text}: {name[len(key) + 1:]}" for key, text in captions.items()
                                              if name.startswith(key + "_")), "ATE against time per frame")
        lines += [f"### {caption}", "", f"![{caption}](plots/{os.path.basename(path)})", ""]
    not_ok = [row for row in rows if row["status"] != "ok"]
    if not_ok:
        lines += ["Runs that are not ok are not drawn: " +
                  ", ".join(f"{r['dataset']} {run_label(*run_key(r))} ({r['status']})" for r in not_ok), ""]
    path = os.path.join(sweep_dir, "report.md")
    with open(path, "w") as f:
        f.write("\n".join(lines))
    return path


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--sweep_dir", required=True, help="the folder `vio sweep --output_dir` wrote")
    args = parser.parse_args()
    rows = read_results(args.sweep_dir)
    styles = run_styles(rows)
    plots_dir = os.path.join(args.sweep_dir, "plots")
    written = []
    for dataset in sorted({row["dataset"] for row in rows}):
        data_dir = os.path.join(plots_dir, "data", dataset)
        groundtruth_path = os.path.join(data_dir, "groundtruth.csv")
        runs = runs_of(data_dir, rows, dataset, styles)
        if not runs or not os.path.exists(groundtruth_path):
            continue
        groundtruth = read_columns(groundtruth_path)
        path = os.path.join(plots_dir, f"trajectories_{dataset}.png")
        plot_trajectories(dataset, groundtruth, runs, path)
        written.append(path)
        path = os.path.join(plots_dir, f"position_error_{dataset}.png")
        plot_errors(dataset, runs, path)
        written.append(path)
    nees_dir = os.path.join(plots_dir, "data", "nees")
    monte_carlo = os.path.isdir(nees_dir)
    path = os.path.join(plots_dir, "ate_vs_cost.png")
    # A Monte Carlo sweep: one line per configuration is enough (the first seed).
    first = [row for row in rows if row["dataset"] == rows[0]["dataset"]] if monte_carlo else rows
    if plot_ate_vs_cost(first, styles, path):
        written.append(path)
    path = os.path.join(plots_dir, "nees.png")
    if monte_carlo and plot_nees(nees_dir, rows, styles, path):
        written.append(path)
    report = write_report(args.sweep_dir, rows, written)
    print(f"{len(written)} PNGs in {plots_dir}: " + ", ".join(os.path.basename(p) for p in written) +
          f"; report: {report}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
