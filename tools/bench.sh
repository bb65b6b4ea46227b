#!/usr/bin/env bash
# One benchmark command: ms per frame and peak memory of every policy on the
# hybrid V2_01 from features, and of the image front ends on a short rendered
# V2_01, each a `vio run` on one core (taskset -c 0 when available) under
# /usr/bin/time -v. Prints one table.
#
# usage: tools/bench.sh [--quick] [--rows=ROW,...] [--repeat=N] [--cache=DIR] [--rendered_s=S]
#   --quick       rows swf10, msckf10 and klt only
#   --rows        a subset of: swf5 swf10 swf30 swf50 msckf10 ekf keyframe brisk klt
#   --repeat      runs per row (default 1): ms/frame and the stage times are then the
#                 medians and ms_range the fastest and slowest run (a shared
#                 machine's speed drifts by 15-35 % between hours)
#   --cache       where the generated datasets and the runs go (default
#                 ${VIO_BENCH_CACHE:-/tmp/vio_bench}); datasets are reused when present
#   --rendered_s  seconds of V2_01 rendered for the front-end rows (default 20)
# Environment: EUROC (default ../shared/data/euroc beside the repository) holds V2_01_easy;
# BUILD_DIR (default build/) the Release build; the script builds `vio` there.
set -euo pipefail
root="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
build="${BUILD_DIR:-$root/build}"
euroc="${EUROC:-$root/../shared/data/euroc}"
cache="${VIO_BENCH_CACHE:-/tmp/vio_bench}"
rows="swf5,swf10,swf30,swf50,msckf10,ekf,keyframe,brisk,klt"
rendered_s=20
repeat=1
for arg in "$@"; do
  case "$arg" in
    --quick) rows="swf10,msckf10,klt" ;;
    --rows=*) rows="${arg#--rows=}" ;;
    --cache=*) cache="${arg#--cache=}" ;;
    --rendered_s=*) rendered_s="${arg#--rendered_s=}" ;;
    --repeat=*) repeat="${arg#--repeat=}" ;;
    -h|--help) sed -n '2,18p' "$0"; exit 0 ;;
    *) echo "bench.sh: unknown argument '$arg' (see --help)" >&2; exit 2 ;;
  esac
done
case "$repeat" in ''|*[!0-9]*|0) echo "bench.sh: --repeat must be a positive integer, got '$repeat'" >&2; exit 2 ;; esac
source_dir="$euroc/V2_01_easy"
[ -d "$source_dir/mav0" ] || { echo "bench.sh: $source_dir/mav0 not found (set EUROC)" >&2; exit 1; }
mkdir -p "$cache"
echo "bench: cache $cache"

BUILD_DIR="$build" "$root/tools/build.sh" vio >/dev/null
vio="$build/bin/vio"
pin=()
if command -v taskset >/dev/null && taskset -c 0 true 2>/dev/null; then pin=(taskset -c 0); fi

# The first `seconds` of a EuRoC folder (every CSV cut at the first camera
# stamp + seconds; calibration copied), for a short rendered sequence.
trim_euroc() {
  local from="$1" to="$2" seconds="$3"
  local t0 t1
  t0=$(awk -F, 'NR == 2 {print $1}' "$from/mav0/cam0/data.csv")
  t1=$(awk -v t0="$t0" -v s="$seconds" 'BEGIN {printf "%.0f", t0 + s * 1e9}')
  (cd "$from" && find mav0 -name '*.yaml') | while read -r f; do
    mkdir -p "$to/$(dirname "$f")"; cp "$from/$f" "$to/$f"
  done
  (cd "$from" && find mav0 -name 'data.csv') | while read -r f; do
    awk -F, -v t1="$t1" 'NR == 1 || $1 + 0 <= t1 + 0' "$from/$f" > "$to/$f"
  done
}

hybrid="$cache/hybrid_V2_01"
if [ ! -f "$hybrid/mav0/features0/data.csv" ]; then
  echo "bench: generating $hybrid (hybrid V2_01 from features)"
  "$vio" simulate --from="$source_dir" --output_dir="$hybrid" >/dev/null 2>&1
fi
needs_images=0
case ",$rows," in *,brisk,*|*,klt,*) needs_images=1 ;; esac
rendered="$cache/rendered_V2_01_${rendered_s}s_textured"  # stored PNGs, real textures
if [ "$needs_images" -eq 1 ] && [ ! -d "$rendered/mav0/cam1/data" ]; then
  echo "bench: rendering $rendered (first ${rendered_s} s of V2_01, images)"
  trim_euroc "$source_dir" "$cache/V2_01_first_${rendered_s}s" "$rendered_s"
  # The real textures from EUROC (the default --texture_dir is relative to the current folder).
  "$vio" simulate --from="$cache/V2_01_first_${rendered_s}s" --camera=images --output_dir="$rendered" \
    --texture_dir="$euroc/V1_01_easy_micro,$euroc/V1_01_easy_flight10" >/dev/null 2>&1
fi

# One row: name, dataset, description, then the run's flags; `repeat` runs,
# each in its own folder, summarized by their medians.
run_row() {
  local name="$1" dataset="$2" what="$3"; shift 3
  local out="$cache/runs/$name"
  rm -rf "$out"; mkdir -p "$out"
  local k
  for ((k = 1; k <= repeat; ++k)); do
    local run="$out/run_$k"
    mkdir -p "$run"
    if ! "${pin[@]}" /usr/bin/time -v -o "$run/time.txt" "$vio" run --dataset="$dataset" --output_dir="$run" \
        --config="$root/config/euroc_stereo.yaml" "$@" >"$run/log.txt" 2>&1; then
      printf '%-10s %-44s failed (%s)\n' "$name" "$what" "$run/log.txt"; return
    fi
  done
  python3 - "$out" "$name" "$what" "$repeat" <<'EOF'
import json, re, statistics, sys
out, name, what, repeat = sys.argv[1], sys.argv[2], sys.argv[3], int(sys.argv[4])
runs = [f"{out}/run_{k}" for k in range(1, repeat + 1)]
summaries = [json.load(open(run + "/summary.json")) for run in runs]
rss_kb = max(int(re.search(r"Maximum resident set size \(kbytes\): (\d+)", open(run + "/time.txt").read()).group(1))
             for run in runs)
ms = [t["ms_per_frame"] for t in summaries]
s = summaries[0]
ate = s.get("evaluation", {}).get("ate", {}).get("rmse_m")
def median_of(values, width):
    ok = all(isinstance(v, (int, float)) for v in values)
    return f"{statistics.median(values):{width}.1f}" if ok else f"{'-':>{width}}"
front = median_of([t.get("frontend", {}).get("stage_ms", {}).get("frontend") for t in summaries], 8)
front_cpu = median_of([t.get("frontend", {}).get("cpu_ms", {}).get("frontend") for t in summaries], 9)
decode_cpu = median_of([t.get("frontend", {}).get("cpu_ms", {}).get("decode") for t in summaries], 10)
ms_range = f"{min(ms):.2f}-{max(ms):.2f}"
print(f"{name:<10} {what:<44} {s['frames_estimated']:>6} {statistics.median(ms):8.2f} {ms_range:>13} {front} "
      f"{front_cpu} {decode_cpu} "
      f"{rss_kb / 1024:8.1f} {max(t.get('peak_memory_mb', 0) for t in summaries):8.1f} "
      + (f"{ate:8.4f}" if ate is not None else f"{'-':>8}") + f" {s['status']}")
EOF
}

echo "bench: one core (${pin[*]:-no taskset}), Release vio, config/euroc_stereo.yaml"
printf '%-10s %-44s %6s %8s %13s %8s %9s %10s %8s %8s %8s %s\n' row what frames ms/frame ms_range front_ms \
  front_cpu decode_cpu rss_MB run_MB ate_m status
IFS=, read -r -a selected <<< "$rows"
for row in "${selected[@]}"; do
  case "$row" in
    swf5|swf10|swf30|swf50)
      run_row "$row" "$hybrid" "SWF(${row#swf}), hybrid V2_01 features" --frontend=features --policy=swf \
        --window_size="${row#swf}" ;;
    msckf10) run_row "$row" "$hybrid" "MSCKF(10), hybrid V2_01 features" --frontend=features --policy=msckf \
        --window_size=10 ;;
    ekf) run_row "$row" "$hybrid" "EKF marginalize_unseen, hybrid V2_01" --frontend=features --policy=ekf \
        --ekf_landmarks=marginalize_unseen ;;
    keyframe) run_row "$row" "$hybrid" "keyframe(10), hybrid V2_01 features" --frontend=features \
        --policy=keyframe --window_size=10 ;;
    brisk|klt) run_row "$row" "$rendered" "$row + MSCKF(10), rendered V2_01 ${rendered_s} s" --frontend="$row" \
        --policy=msckf --window_size=10 ;;
    *) echo "bench.sh: unknown row '$row'" >&2; exit 2 ;;
  esac
done
echo "ms/frame: vio run's processing time per estimated frame, the median of $repeat run(s) (ms_range: fastest-slowest);"
echo "front_ms: the front end's share (image rows, wall clock: on one core it absorbs the read-ahead's decoding);"
echo "front_cpu, decode_cpu: CPU time of the front end's thread and of the image reading and decoding (read-ahead"
echo "thread), per frame;"
echo "rss_MB: peak RSS from /usr/bin/time -v; run_MB: the peak vio run reports (getrusage); both the largest over the"
echo "runs, in $cache/runs/ROW/run_K"
