#!/usr/bin/env bash
# Quick start, command 1: install what is missing, build `vio` (Release, only
# the targets the demo needs; tools/test.sh builds everything), simulate a
# 30 s stereo-inertial flight through a room, run the estimator on it with a
# progress bar, compare three estimators with `vio sweep` (table, plots,
# report), and end with a short summary and the next commands to try.
# OUT overrides the output folder (default: out/demo), BUILD_DIR the build.
set -euo pipefail
root="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
out="${OUT:-$root/out/demo}"
build="${BUILD_DIR:-$root/build}"
vio="$build/bin/vio"
config="$root/config/euroc_stereo.yaml"
started=$SECONDS

step() { printf '\n== %s/5 %s  (%d s so far)\n' "$1" "$2" $((SECONDS - started)); }

step 1 "installing the Debian packages that are missing (nothing when all are there)"
"$root/tools/install_deps.sh"

step 2 "building vio (Release, only what the demo needs)"
"$root/tools/build.sh" --progress vio

step 3 "simulating a 30 s flight through a room: $out/synthetic_30s"
rm -rf "$out/synthetic_30s" "$out/run" "$out/sweep"
mkdir -p "$out"
"$vio" simulate --output_dir="$out/synthetic_30s" --duration_s=30 --seed=1

step 4 "running the estimator (sliding window filter, 10 states): $out/run"
"$vio" run --dataset="$out/synthetic_30s" --config="$config" --output_dir="$out/run" > "$out/run.log"

step 5 "comparing SWF(5), SWF(10) and MSCKF(10) with vio sweep: $out/sweep"
"$vio" sweep --datasets="$out/synthetic_30s" --runs=swf:5,swf:10,msckf:10 --jobs=2 --config="$config" \
  --output_dir="$out/sweep"

/usr/bin/python3 - "$out" "$root" $((SECONDS - started)) "$vio" <<'EOF'
import json, os, sys
out, root, seconds, vio_path = sys.argv[1], sys.argv[2], int(sys.argv[3]), sys.argv[4]
s = json.load(open(os.path.join(out, "run", "summary.json")))
ate = s.get("evaluation", {}).get("ate", {}).get("rmse_m")
def rel(path):
    """`path` relative to the current folder, or absolute when that is shorter to read."""
    relative = os.path.relpath(path, os.getcwd())
    return os.path.abspath(path) if relative.startswith("../..") else relative
print(f"\n== done in {seconds // 60} min {seconds % 60} s")
ate_text = f"ATE {ate:.3f} m (after position + yaw alignment)" if ate is not None else "no ATE (no ground truth)"
print(f"SWF(10) on the simulated flight: {s['status']}, {s['frames_estimated']}/{s['frames']} frames, {ate_text},"
      f" {s['ms_per_frame']:.1f} ms per frame = {s['real_time_factor']:.1f}x real time")
print(f"  run files      {rel(os.path.join(out, 'run'))}/: trajectory.txt summary.json timing.csv config.yaml")
print(f"  comparison     {rel(os.path.join(out, 'sweep', 'report.md'))} (table and plots),"
      f" {rel(os.path.join(out, 'sweep', 'results.csv'))}")
print(f"  plots          {rel(os.path.join(out, 'sweep', 'plots'))}/*.png")
vio = rel(vio_path)
data = rel(os.path.join(root, "..", "shared", "data", "euroc", "V2_01_easy"))
print("next:")
for command, what in [
    (f"{vio} --help", "the commands; `vio run --help`: every flag of a run"),
    (f"{vio} run --dataset={rel(os.path.join(out, 'synthetic_30s'))} --output_dir=out/msckf --policy=msckf",
     "another estimator on the same flight"),
    (f"{vio} simulate --from={data} --output_dir=out/hybrid", "a real EuRoC flight with a simulated camera"),
    (f"{vio} verify", "the paper's filter = optimization theorems, checked"),
    ("tools/test.sh", "build everything and run the test suite"),
]:
    print(f"  {command}\n      {what}")
EOF
