#!/usr/bin/env python3
"""The tables of docs/results.md, from the files tools/results.sh's commands write.

usage: results_tables.py hybrid RESULTS_CSV EVAL_DIR
       results_tables.py real RUNS_DIR
       results_tables.py verify VERIFY_JSON
       results_tables.py page FRAGMENTS MODE DATE COMMIT NPROC CPU SECONDS LOAD SOFTWARE
"""
import csv
import json
import os
import sys


def load_json(path):
    try:
        with open(path) as f:
            return json.load(f)
    except (OSError, ValueError):
        return None


def fmt(value, digits):
    return "-" if value is None else f"{value:.{digits}f}"


def estimator_name(policy, window):
    """batch, SWF(10), or SWF(10) + local map K=4 for the sweep's policy "swf+map4"."""
    if policy in ("batch", "ekf", "iekf"):
        return policy
    base, _, keyframes = policy.partition("+map")
    name = f"{base.upper()}({window})"
    return f"{name} + local map K={keyframes}" if keyframes else name


def hybrid(results_csv, eval_dir):
    """Accuracy and time per frame of each hybrid run: results.csv of the sweep and vio eval's JSONs."""
    print("| sequence | estimator | status | ATE SE3 [m] | ATE pos+yaw [m] | ms/frame | peak memory [MB] |")
    print("|---|---|---|---:|---:|---:|---:|")
    with open(results_csv) as f:
        for row in csv.DictReader(f):
            name = f"{row['dataset']}_{row['policy']}_{row['window']}"
            ate = {}
            for alignment in ("se3", "posyaw"):
                report = load_json(os.path.join(eval_dir, f"{name}_{alignment}.json"))
                ate[alignment] = report["ate"]["rmse_m"] if report else None
            ms = float(row["ms_per_frame"]) if row["ms_per_frame"] else None
            memory = float(row["peak_memory_mb"]) if row["peak_memory_mb"] else None
            print(f"| {row['dataset']} | {estimator_name(row['policy'], row['window'])} | {row['status']} | "
                  f"{fmt(ate['se3'], 4)} | {fmt(ate['posyaw'], 4)} | {fmt(ms, 2)} | {fmt(memory, 1)} |")


def real(runs_dir):
    """The image front ends on the real pairs: one row per run folder (CLIP_FRONTEND)."""
    print("| clip | front end | status | frames estimated | stereo features per frame (min) | row difference [px] "
          "| front end [ms/frame] | front-end CPU [ms/frame] | decoding CPU [ms/frame] | whole run [ms/frame] "
          "| ATE pos+yaw [m] |")
    print("|---|---|---|---:|---:|---:|---:|---:|---:|---:|---:|")
    for name in sorted(os.listdir(runs_dir)):
        s = load_json(os.path.join(runs_dir, name, "summary.json"))
        clip, frontend = name.rsplit("_", 1)
        if s is None:
            print(f"| {clip} | {frontend} | failed (no summary.json) | | | | | | | | |")
            continue
        fe = s.get("frontend", {})
        features = fe.get("features_per_frame", {})
        ate = s.get("evaluation", {}).get("ate", {}).get("rmse_m")
        print(f"| {clip} | {frontend} | {s['status']} | {s['frames_estimated']}/{s['frames']} | "
              f"{fmt(features.get('mean'), 0)} ({features.get('min', '-')}) | "
              f"{fmt(fe.get('stereo_row_difference_median_px'), 3)} | "
              f"{fmt(fe.get('stage_ms', {}).get('frontend'), 1)} | {fmt(fe.get('cpu_ms', {}).get('frontend'), 1)} | "
              f"{fmt(fe.get('cpu_ms', {}).get('decode'), 1)} | {fmt(s.get('ms_per_frame'), 1)} | {fmt(ate, 4)} |")


def verify(path):
    report = load_json(path)
    if report is None:
        print("`vio verify` wrote no report.")
        return
    rows = report["rows"]
    theorems = [r for r in rows if not r["control"]]
    controls = [r for r in rows if r["control"]]
    worst = max(max(r["mean_deviation"], r["covariance_deviation"]) for r in theorems)
    weakest = min(max(r["mean_deviation"], r["covariance_deviation"]) for r in controls)
    print(f"| result | theorem rows (held) | largest deviation of a theorem row | negative controls (detected) "
          f"| smallest deviation of a control | tolerance |")
    print("|---|---:|---:|---:|---:|---:|")
    print(f"| {'PASS' if report['passed'] else 'FAIL'} | {len(theorems)} ({sum(r['passed'] for r in theorems)}) | "
          f"{worst:.1e} | {len(controls)} ({sum(r['passed'] for r in controls)}) | {weakest:.1e} | "
          f"{report['tolerance']:.0e} |")


SECTIONS = [
    ("hybrid", "Accuracy on hybrid EuRoC",
     "Real IMU, motion and calibration of each sequence, simulated stereo features (`vio simulate --from`), "
     "the default start (`--init=auto`: these sequences start at rest, so static), `config/euroc_stereo.yaml`; one `vio run` at a time (`vio sweep --jobs=1`). "
     "ATE RMSE after SE3 alignment (the headline) and after position + yaw alignment (which keeps the ground "
     "truth's lean of about 0.65 deg against the real IMU's gravity); ms/frame is `vio run`'s processing time per "
     "frame (wall clock, the whole run for batch); peak memory as `vio run` reports it."),
    ("bench", "Speed (`tools/bench.sh`)",
     "Each row a `vio run` on one core (`taskset -c 0`) under `/usr/bin/time -v`: the policies on the whole hybrid "
     "V2_01 from features, the image front ends with MSCKF(10) on a rendered V2_01 cut to its first seconds. "
     "This machine's speed drifts by 15-35 % between hours: compare builds by paired runs, not tables."),
    ("real", "Front ends on real image pairs",
     "`V1_01_easy_micro`: 95 real static stereo pairs; `V1_01_easy_flight10`: 10 real pairs in flight, "
     "started from the ground truth (`--init=groundtruth`). Front end: wall clock per frame; front-end and "
     "decoding CPU: each thread's own CPU time."),
    ("montecarlo", "Consistency (Monte Carlo NEES)",
     "`vio sweep --seeds`: the synthetic flight simulated with noise seeds 1..N (same trajectory and room), "
     "the estimator's noise model equal to the simulator's, first-estimate Jacobians on."),
    ("demo", "The quick start's first command (`tools/demo.sh`)",
     "A fresh `git clone` of the commit measured, then `tools/demo.sh` in it under `/usr/bin/time` with the packages "
     "installed and no compiler cache (full mode only): what a new user waits for, nearly all of it the build of "
     "`vio` from scratch on both cores. Wall time depends on the machine's load (at the end, above)."),
    ("verify", "The paper's theorems (`vio verify`)",
     "Each filter step of the paper's section 4.3 (and Algorithms 3 and 4) built as a cost in the window and "
     "compared with the covariance-form filter on random problems; the controls break one side on purpose."),
]


def page(fragments, mode, date, commit, nproc, cpu, seconds, load, software):
    print("# Results\n")
    print("Generated by `tools/results.sh`; do not edit by hand: run `nice tools/results.sh` (or "
          "`tools/results.sh --quick` for a shorter check) and commit the file it writes.\n")
    print(f"- date: {date}")
    print(f"- commit: `{commit}`")
    print(f"- machine: {nproc} cores (`nproc`), {cpu}; load average at the end {load}")
    print(f"- software: {software or 'unknown'} (Debian packages)")
    print(f"- mode: {mode}; took {int(seconds) // 60} min {int(seconds) % 60} s")
    print("- data: the shared EuRoC data (`$VIO_DATA_DIR`, default `../shared/data`), read in place\n")
    print("Times are wall clock on a shared machine: upper bounds, comparable within one table only.")
    for key, title, text in SECTIONS:
        body_path = os.path.join(fragments, key + ".md")
        if not os.path.exists(body_path):
            continue
        print(f"\n## {title}\n\n{text}\n")
        with open(body_path) as f:
            print(f.read().rstrip("\n"))
        commands_path = os.path.join(fragments, key + ".cmd")
        if os.path.exists(commands_path):
            with open(commands_path) as f:
                commands = f.read().rstrip("\n")
            print(f"\nCommands (from the repository root):\n\n```sh\n{commands}\n```")


def main(argv):
    commands = {"hybrid": (hybrid, 2), "real": (real, 1), "verify": (verify, 1), "page": (page, 9)}
    if len(argv) < 2 or argv[1] not in commands or len(argv) - 2 != commands[argv[1]][1]:
        sys.stderr.write(__doc__)
        return 2
    function, _ = commands[argv[1]]
    function(*argv[2:])
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv))
