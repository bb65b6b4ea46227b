#!/usr/bin/env python3
"""Per-frame cost of `vio run` over a long run, with and without the local map.

usage: tools/plot_local_map_cost.py --out=PNG LABEL=RUN_DIR [LABEL=RUN_DIR ...]

Reads each RUN_DIR/timing.csv (`vio run`'s per-frame stages and sizes) and draws
against the time since the first frame: the total ms/frame (wall clock, a 10 s
running median) and the states, landmarks and residual blocks in the cost
(deterministic; residual blocks a 10 s running mean).
"""
import argparse
import csv

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402


def read(run_dir):
    with open(run_dir + "/timing.csv") as f:
        rows = [r for r in csv.reader(f) if r and not r[0].startswith("#")]
    t = np.array([int(r[0]) for r in rows], dtype=np.float64)
    total = np.array([float(r[5]) for r in rows])
    states = np.array([int(r[7]) for r in rows])
    landmarks = np.array([int(r[8]) for r in rows])
    residuals = np.array([int(r[10]) for r in rows], dtype=np.float64)
    return (t - t[0]) * 1e-9, total, states, landmarks, residuals


def running(t, y, span_s, statistic):
    out = np.empty_like(y)
    lo = 0
    for i in range(len(t)):
        while t[i] - t[lo] > span_s:
            lo += 1
        out[i] = statistic(y[lo:i + 1])
    return out


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--out", required=True)
    parser.add_argument("--title", default="")
    parser.add_argument("runs", nargs="+", help="LABEL=RUN_DIR")
    args = parser.parse_args()
    fig, (ax, ax_states, ax_landmarks, ax_residuals) = plt.subplots(4, 1, figsize=(8, 10), sharex=True)
    for item in args.runs:
        label, run_dir = item.rsplit("=", 1)
        t, total, states, landmarks, residuals = read(run_dir)
        ax.plot(t / 60.0, running(t, total, 10.0, np.median), label=label)
        ax_states.plot(t / 60.0, states, label=label, linewidth=0.6)
        ax_landmarks.plot(t / 60.0, landmarks, label=label, linewidth=0.6)
        ax_residuals.plot(t / 60.0, running(t, residuals, 10.0, np.mean), label=label)
    ax.set_ylabel("ms/frame, wall\n(10 s running median)")
    ax_states.set_ylabel("states in the cost")
    ax_landmarks.set_ylabel("landmarks in the cost")
    ax_residuals.set_ylabel("residual blocks in the cost\n(10 s running mean)")
    ax_residuals.set_xlabel("time [min]")
    for a in (ax, ax_states, ax_landmarks, ax_residuals):
        a.set_ylim(bottom=0)
        a.grid(True, alpha=0.3)
    ax.legend()
    if args.title:
        ax.set_title(args.title)
    fig.tight_layout()
    fig.savefig(args.out, dpi=100)


if __name__ == "__main__":
    main()
