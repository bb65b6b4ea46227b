#!/usr/bin/python3
"""Plots of a `vio sweep` folder (run by `vio sweep`; needs numpy and matplotlib).

Reads SWEEP_DIR/results.csv and the plot data `vio sweep` writes under
SWEEP_DIR/plots/data/<dataset>/ (groundtruth.csv and <policy>_<window>.csv:
the estimate after position + yaw alignment, with its position error), and
writes into SWEEP_DIR/plots/:

  trajectories_<dataset>.png    top view (x-y) of every run against ground truth, equal axes
  position_error_<dataset>.png  position error over time, one line per run
  ate_vs_cost.png               ATE RMSE against estimator time per frame, per policy and window

usage: plot_sweep.py --sweep_dir SWEEP_DIR
"""
import argparse
import csv
import math
import os
import sys

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import matplotlib.ticker  # noqa: E402
import numpy as np  # noqa: E402

DPI = 90


def read_results(sweep_dir):
    with open(os.path.join(sweep_dir, "results.csv"), newline="") as f:
        return list(csv.DictReader(f))


def read_columns(path):
    data = np.genfromtxt(path, delimiter=",", names=True)
    return np.atleast_1d(data)


def number(text):
    return float(text) if text not in ("", None) else math.nan


def run_styles(rows):
    """Line style per run: colour by window size (dark = small), dash pattern by policy."""
    windows = sorted({int(row["window"]) for row in rows})
    policies = list(dict.fromkeys(row["policy"] for row in rows))
    dashes = ["-", "--", ":", "-."]
    colours = plt.cm.viridis(np.linspace(0.0, 0.85, max(len(windows), 1)))
    return {
        (policy, window): {"color": colours[windows.index(window)], "ls": dashes[policies.index(policy) % 4]}
        for policy in policies
        for window in windows
    }


def runs_of(data_dir, rows, dataset):
    """(label, style, data) of every run of `dataset` with plot data, in results.csv order."""
    styles = run_styles(rows)
    runs = []
    for row in rows:
        if row["dataset"] != dataset:
            continue
        path = os.path.join(data_dir, f"{row['policy']}_{row['window']}.csv")
        if os.path.exists(path):
            label = f"{row['policy']} w={row['window']}"
            runs.append((label, styles[(row["policy"], int(row["window"]))], read_columns(path)))
    return runs


def wide_range(values, ratio=20.0):
    """True when the positive values span more than `ratio` (then a log axis reads better)."""
    values = [v for v in values if math.isfinite(v) and v > 0]
    return len(values) > 1 and max(values) > ratio * min(values)


def plain_log_axis(axis):
    """Log-scale ticks written as plain numbers (0.02, 0.05, 1, 200), not powers of ten;
    the 2s and 5s between decades only when the axis spans less than three decades."""

    def minor(value, _):
        low, high = sorted(axis.get_view_interval())
        few_decades = low > 0 and high / low < 1000
        return f"{value:g}" if few_decades and f"{value:g}".lstrip("0.")[:1] in "25" else ""

    axis.set_major_formatter(matplotlib.ticker.FuncFormatter(lambda v, _: f"{v:g}"))
    axis.set_minor_formatter(matplotlib.ticker.FuncFormatter(minor))


def plot_trajectories(dataset, groundtruth, runs, out_path):
    """Axes fit the ground truth (plus a margin), so one diverged run cannot hide the others."""
    fig, ax = plt.subplots(figsize=(8.4, 5.6))
    x, y = groundtruth["x_m"], groundtruth["y_m"]
    margin = max(0.15 * max(np.ptp(x), np.ptp(y)), 0.5)
    xlim, ylim = (x.min() - margin, x.max() + margin), (y.min() - margin, y.max() + margin)
    ax.plot(x, y, color="black", lw=2.2, label="ground truth")
    for label, style, run in runs:
        inside = np.all((run["x_m"] >= xlim[0]) & (run["x_m"] <= xlim[1]) &
                        (run["y_m"] >= ylim[0]) & (run["y_m"] <= ylim[1]))
        ax.plot(run["x_m"], run["y_m"], lw=1.2, label=label if inside else f"{label} (leaves the plot)", **style)
    ax.plot(x[0], y[0], "o", color="black", ms=6, label="start")
    ax.set_xlim(*xlim)
    ax.set_ylim(*ylim)
    ax.set_aspect("equal", adjustable="datalim")
    ax.set_xlabel("x [m]")
    ax.set_ylabel("y [m]")
    ax.set_title(f"{dataset}: top view, estimates aligned in position + yaw")
    ax.grid(True, alpha=0.3)
    ax.legend(loc="upper left", bbox_to_anchor=(1.02, 1.0), fontsize=8)
    fig.tight_layout()
    fig.savefig(out_path, dpi=DPI)
    plt.close(fig)


def plot_errors(dataset, runs, out_path):
    fig, ax = plt.subplots(figsize=(9.4, 4))
    for label, style, run in runs:
        ax.plot(run["t_s"], run["error_m"], lw=1.2, label=label, **style)
    ax.set_xlabel("time since start of the sequence [s]")
    if wide_range([float(np.median(run["error_m"])) for _, _, run in runs]):
        ax.set_yscale("log")
        plain_log_axis(ax.yaxis)
        ax.set_ylabel("position error [m] (log scale)")
    else:
        ax.set_ylim(bottom=0)
        ax.set_ylabel("position error [m]")
    ax.set_title(f"{dataset}: position error after position + yaw alignment")
    ax.grid(True, which="both", alpha=0.3)
    ax.legend(loc="upper left", bbox_to_anchor=(1.02, 1.0), fontsize=8)
    fig.tight_layout()
    fig.savefig(out_path, dpi=DPI)
    plt.close(fig)


def plot_ate_vs_cost(rows, out_path):
    """One line per (dataset, policy) through its window sizes, each point labelled w=N."""
    series = {}
    for row in rows:
        ate, cost = number(row["ate_rmse_m"]), number(row["ms_per_frame"])
        if row["status"] == "ok" and math.isfinite(ate) and math.isfinite(cost):
            series.setdefault((row["dataset"], row["policy"]), []).append((cost, ate, int(row["window"])))
    if not series:
        return False
    fig, ax = plt.subplots(figsize=(8.4, 4.5))
    markers = "osD^v<>"
    for k, ((dataset, policy), points) in enumerate(sorted(series.items())):
        points.sort(key=lambda p: p[2])
        costs, ates, windows = zip(*points)
        label = policy if len({d for d, _ in series}) == 1 else f"{dataset} {policy}"
        ax.plot(costs, ates, marker=markers[k % len(markers)], lw=1.2, label=label)
        for cost, ate, window in points:
            ax.annotate(f"w={window}", (cost, ate), textcoords="offset points", xytext=(5, 4), fontsize=8)
    ax.set_xscale("log")
    plain_log_axis(ax.xaxis)
    ax.margins(x=0.12, y=0.15)
    ax.set_xlabel("estimator time per frame [ms] (log scale)")
    if wide_range([ate for points in series.values() for _, ate, _ in points]):
        ax.set_yscale("log")
        plain_log_axis(ax.yaxis)
        ax.set_ylabel("ATE RMSE [m] (log scale)")
    else:
        ax.set_ylabel("ATE RMSE [m]")
        ax.set_ylim(0, 1.15 * max(ate for points in series.values() for _, ate, _ in points))
    ax.set_title("accuracy against cost (w = window size [frames])")
    ax.grid(True, which="both", alpha=0.3)
    ax.legend(loc="upper left", bbox_to_anchor=(1.02, 1.0), fontsize=8)
    fig.tight_layout()
    fig.savefig(out_path, dpi=DPI)
    plt.close(fig)
    return True


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--sweep_dir", required=True, help="the folder `vio sweep --output_dir` wrote")
    args = parser.parse_args()
    rows = read_results(args.sweep_dir)
    plots_dir = os.path.join(args.sweep_dir, "plots")
    written = []
    for dataset in sorted({row["dataset"] for row in rows}):
        data_dir = os.path.join(plots_dir, "data", dataset)
        groundtruth_path = os.path.join(data_dir, "groundtruth.csv")
        runs = runs_of(data_dir, rows, dataset)
        if not runs or not os.path.exists(groundtruth_path):
            continue
        for name, draw in (
            ("trajectories", lambda p: plot_trajectories(dataset, read_columns(groundtruth_path), runs, p)),
            ("position_error", lambda p: plot_errors(dataset, runs, p)),
        ):
            path = os.path.join(plots_dir, f"{name}_{dataset}.png")
            draw(path)
            written.append(path)
    path = os.path.join(plots_dir, "ate_vs_cost.png")
    if plot_ate_vs_cost(rows, path):
        written.append(path)
    print(f"{len(written)} PNGs in {plots_dir}: " + ", ".join(os.path.basename(p) for p in written))
    return 0


if __name__ == "__main__":
    sys.exit(main())
