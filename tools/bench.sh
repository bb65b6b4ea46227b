#!/usr/bin/env bash
# One benchmark command: ms per frame and peak memory of every policy on the
# hybrid V2_01 from features, of the image front ends on a short rendered
# V2_01, and of KLT + MSCKF(10) on the shared real EuRoC pairs, each a
# `vio run` on one core (taskset -c 0 when available) under /usr/bin/time -v;
# the real rows also on two cores (taskset -c 0,1: the image pipeline's two
# threads). Prints one table, the ratios of its rows, then each stage's ms per
# frame and share (build, solve, marginalize, front end, decode) and, with
# --baseline, each stage's ratio against the baseline's paired runs.
#
# usage: tools/bench.sh [--quick] [--rows=ROW,...] [--repeat=N] [--cache=DIR] [--rendered_s=S]
#                       [--baseline=VIO] [--real_loops=N]
#   --quick       rows swf10, msckf10, klt and real_micro only
#   --rows        a subset of: swf5 swf10 swf30 swf50 msckf10 ekf keyframe brisk klt real_micro real_flight
#                 (real_micro: the 95 static pairs V1_01_easy_micro, the configuration's start; real_flight: the 10 pairs
#                 in flight V1_01_easy_flight10, ground-truth start; both read in place from EUROC)
#   --baseline    another vio binary (e.g. an older build) run on the image, SWF and MSCKF rows too, each of
#                 its runs right after the same run of this build; the ratios compare the two
#   --real_loops  runs of each real row (default 3; the real clips are short, so they are run again: each
#                 run is one clip, the figures are the medians over the runs)
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
rows="swf5,swf10,swf30,swf50,msckf10,ekf,keyframe,brisk,klt,real_micro,real_flight"
rendered_s=20
repeat=1
baseline=""
real_loops=3
for arg in "$@"; do
  case "$arg" in
    --quick) rows="swf10,msckf10,klt,real_micro" ;;
    --baseline=*) baseline="${arg#--baseline=}" ;;
    --real_loops=*) real_loops="${arg#--real_loops=}" ;;
    --rows=*) rows="${arg#--rows=}" ;;
    --cache=*) cache="${arg#--cache=}" ;;
    --rendered_s=*) rendered_s="${arg#--rendered_s=}" ;;
    --repeat=*) repeat="${arg#--repeat=}" ;;
    -h|--help) sed -n '2,28p' "$0"; exit 0 ;;
    *) echo "bench.sh: unknown argument '$arg' (see --help)" >&2; exit 2 ;;
  esac
done
case "$repeat" in ''|*[!0-9]*|0) echo "bench.sh: --repeat must be a positive integer, got '$repeat'" >&2; exit 2 ;; esac
case "$real_loops" in ''|*[!0-9]*|0) echo "bench.sh: --real_loops must be a positive integer, got '$real_loops'" >&2; exit 2 ;; esac
if [ -n "$baseline" ] && [ ! -x "$baseline" ]; then echo "bench.sh: --baseline=$baseline is no executable" >&2; exit 2; fi
source_dir="$euroc/V2_01_easy"
[ -d "$source_dir/mav0" ] || { echo "bench.sh: $source_dir/mav0 not found (set EUROC)" >&2; exit 1; }
mkdir -p "$cache"
echo "bench: cache $cache"

BUILD_DIR="$build" "$root/tools/build.sh" vio >/dev/null
vio="$build/bin/vio"
pin=()
if command -v taskset >/dev/null && taskset -c 0 true 2>/dev/null; then pin=(taskset -c 0); fi
# The configuration for the --baseline binary: without the keys it does not know (no --KEY= in its
# `run --help`) and the values outside the choices its help lists ({a|b}): it keeps its defaults there.
if [ -n "$baseline" ]; then
  "$baseline" run --help > "$cache/baseline_help.txt" 2>&1 || true
  python3 - "$root/config/euroc_stereo.yaml" "$cache/baseline_help.txt" > "$cache/baseline_config.yaml" <<'PY'
import re, sys
help_text = open(sys.argv[2]).read()
for line in open(sys.argv[1]):
    m = re.match(r"^\s+(\w+):\s*([^#\s]*)", line)
    if m:
        entry = re.search(r"^\s+--" + m.group(1) + r"=.*\n(.*)$", help_text, re.M)
        if not entry:
            continue
        choices = re.search(r"\{([^}]*)\}\s*$", entry.group(1))
        if choices and m.group(2).strip('"') not in choices.group(1).split("|"):
            continue
    sys.stdout.write(line)
PY
fi
pin2=()
if command -v taskset >/dev/null && taskset -c 0,1 true 2>/dev/null; then pin2=(taskset -c 0,1); fi

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
# each in its own folder, summarized by their medians. The binary is $row_vio
# ($vio unless set), the pinning $row_pin (one core unless set, as words);
# with --baseline, image, SWF and MSCKF rows pass row_compare=1 and each run is followed by
# the baseline's (row NAME@base; flags it does not know are left out).
run_row() {
  local name="$1" dataset="$2" what="$3"; shift 3
  local binary="${row_vio:-$vio}" runs="${row_repeat:-$repeat}"
  local pinning=("${pin[@]}")
  [ -n "${row_pin:-}" ] && read -r -a pinning <<< "$row_pin"
  local out="$cache/runs/$name" base_out="$cache/runs/$name@base"
  rm -rf "$out" "$base_out"; mkdir -p "$out"
  local compare=0
  [ -n "$baseline" ] && [ "${row_compare:-0}" -eq 1 ] && compare=1 && mkdir -p "$base_out"
  local k failed=""
  for ((k = 1; k <= runs; ++k)); do
    mkdir -p "$out/run_$k"
    "${pinning[@]}" /usr/bin/time -v -o "$out/run_$k/time.txt" "$binary" run --dataset="$dataset" \
      --output_dir="$out/run_$k" --config="$root/config/euroc_stereo.yaml" "$@" >"$out/run_$k/log.txt" 2>&1 ||
      failed="$out/run_$k/log.txt"
    [ "$compare" -eq 1 ] || continue
    mkdir -p "$base_out/run_$k"
    local base_flags=() flag
    for flag in "$@"; do [[ "$flag" == --pipeline_threads=* ]] || base_flags+=("$flag"); done
    "${pinning[@]}" /usr/bin/time -v -o "$base_out/run_$k/time.txt" "$baseline" run --dataset="$dataset" \
      --output_dir="$base_out/run_$k" --config="$cache/baseline_config.yaml" "${base_flags[@]}" \
      >"$base_out/run_$k/log.txt" 2>&1 ||
      failed="$base_out/run_$k/log.txt"
  done
  if [ -n "$failed" ]; then printf '%-24s %-44s failed (%s)\n' "$name" "$what" "$failed"; return; fi
  summarize_row "$out" "$name" "$what" "$runs"
  ran+=("$name")
  if [ "$compare" -eq 1 ]; then summarize_row "$base_out" "$name@base" "$what (base)" "$runs"; ran+=("$name@base"); fi
  return 0
}

summarize_row() {
  python3 - "$@" <<'EOF'
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
fe_dec = median_of([t.get("frontend", {}).get("cpu_ms", {}).get("frontend", 0) +
                    t.get("frontend", {}).get("cpu_ms", {}).get("decode", 0) for t in summaries], 8)
if front_cpu.strip() == "-": fe_dec = f"{'-':>8}"
print(f"{name:<24} {what:<44} {s['frames_estimated']:>6} {statistics.median(ms):8.2f} {ms_range:>13} {front} "
      f"{front_cpu} {decode_cpu} {fe_dec} "
      f"{rss_kb / 1024:8.1f} {max(t.get('peak_memory_mb', 0) for t in summaries):8.1f} "
      + (f"{ate:8.4f}" if ate is not None else f"{'-':>8}") + f" {s['status']}")
EOF
}

echo "bench: one core (${pin[*]:-no taskset}), Release vio, config/euroc_stereo.yaml"
printf '%-24s %-44s %6s %8s %13s %8s %9s %10s %8s %8s %8s %8s %s\n' row what frames ms/frame ms_range front_ms \
  front_cpu decode_cpu fe+dec rss_MB run_MB ate_m status
ran=()  # the rows of this call (the ratios use only them)
IFS=, read -r -a selected <<< "$rows"
for row in "${selected[@]}"; do
  case "$row" in
    swf5|swf10|swf30|swf50)
      row_compare=1 run_row "$row" "$hybrid" "SWF(${row#swf}), hybrid V2_01 features" --frontend=features --policy=swf \
        --window_size="${row#swf}" ;;
    msckf10) row_compare=1 run_row "$row" "$hybrid" "MSCKF(10), hybrid V2_01 features" --frontend=features --policy=msckf \
        --window_size=10 ;;
    ekf) run_row "$row" "$hybrid" "EKF marginalize_unseen, hybrid V2_01" --frontend=features --policy=ekf \
        --ekf_landmarks=marginalize_unseen ;;
    keyframe) run_row "$row" "$hybrid" "keyframe(10), hybrid V2_01 features" --frontend=features \
        --policy=keyframe --window_size=10 ;;
    brisk|klt) row_compare=1 run_row "$row" "$rendered" "$row + MSCKF(10), rendered V2_01 ${rendered_s} s" \
        --frontend="$row" --policy=msckf --window_size=10 ;;
    real_micro|real_flight)
      # micro: the configuration's start (auto; a baseline binary keeps its own, static), which the clip's
      # first second of IMU, not quite still, would make late with static; flight10: too short to start
      # any other way than from the ground truth.
      if [ "$row" = real_micro ]; then clip=V1_01_easy_micro init=() short=micro
      else clip=V1_01_easy_flight10 init=(--init=groundtruth) short=flight10; fi
      if [ ! -d "$euroc/$clip/mav0/cam0/data" ]; then echo "$row: $euroc/$clip not found (skipped)"; continue; fi
      row_compare=1 row_repeat="$real_loops" run_row "${row}_1core" "$euroc/$clip" \
        "KLT+MSCKF(10) real $short, 1 core" --frontend=klt --policy=msckf --window_size=10 "${init[@]}" \
        --pipeline_threads=1
      if [ "${#pin2[@]}" -gt 0 ]; then
        row_compare=1 row_repeat="$real_loops" row_pin="${pin2[*]}" run_row "${row}_2cores" "$euroc/$clip" \
          "KLT+MSCKF(10) real $short, 2 cores" --frontend=klt --policy=msckf --window_size=10 "${init[@]}" \
          --pipeline_threads=2
      fi ;;
    *) echo "bench.sh: unknown row '$row'" >&2; exit 2 ;;
  esac
done
echo "ms/frame: vio run's processing time per estimated frame, the median of $repeat run(s) (ms_range: fastest-slowest);"
echo "  (real rows: the median over the --real_loops=$real_loops runs);"
echo "front_ms: the front end's share, wall clock (its pyramids included when they are built on its thread; an older"
echo "binary's on one core also absorbs its read-ahead thread's decoding);"
echo "front_cpu, decode_cpu: CPU time of the front end (tracking and pyramids, whichever thread built them) and of the"
echo "image reading and decoding, per frame;"
echo "rss_MB: peak RSS from /usr/bin/time -v; run_MB: the peak vio run reports (getrusage); both the largest over the"
echo "runs, in $cache/runs/ROW/run_K"
echo "fe+dec: front_cpu + decode_cpu, the CPU the images cost per frame whatever else the machine runs;"
echo "ROW@base: the --baseline binary, each run right after the same run of this build"
python3 - "$cache/runs" "${ran[@]}" <<'EOF'
import glob, json, os, re, statistics, sys
runs, ran = sys.argv[1], set(sys.argv[2:])
def rows(name):
    summaries = []
    if name not in ran: return summaries
    for path in sorted(glob.glob(f"{runs}/{name}/run_*/summary.json")):
        summaries.append(json.load(open(path)))
    return summaries
def median(name, get):
    values = [get(s) for s in rows(name)]
    values = [v for v in values if v is not None]
    return statistics.median(values) if values else None
def cpu(s, key): return s.get("frontend", {}).get("cpu_ms", {}).get(key)
def fe_dec_cpu(s): return (cpu(s, "frontend") or 0) + (cpu(s, "decode") or 0)
def fe_dec_wall(s): return s.get("frontend", {}).get("stage_ms", {}).get("frontend", 0) + (cpu(s, "decode") or 0)
def ms(s): return s["ms_per_frame"]
def rtf(s): return s.get("real_time_factor")
def rss(name):
    if name not in ran: return None
    sizes = [int(re.search(r"Maximum resident set size \(kbytes\): (\d+)", open(p).read()).group(1))
             for p in glob.glob(f"{runs}/{name}/run_*/time.txt")]
    return max(sizes) / 1024 if sizes else None
print("ratios (medians of this call's runs):")
for build in ("", "@base"):
    swf10, swf50, msckf10 = (median(r + build, ms) for r in ("swf10", "swf50", "msckf10"))
    if swf10 and swf50: print(f"  SWF(50) / SWF(10) ms/frame{build}: {swf50 / swf10:.2f}")
    if swf10 and msckf10: print(f"  MSCKF(10) / SWF(10) ms/frame{build}: {msckf10 / swf10:.2f} (target <= 0.5)")
    if rss("msckf10" + build): print(f"  MSCKF(10) peak RSS{build}: {rss('msckf10' + build):.1f} MB (target <= 80)")
for row in ("swf5", "swf10", "swf30", "swf50", "msckf10"):  # run k of this build against run k of the baseline
    pairs = list(zip(rows(row), rows(row + "@base")))
    if pairs:
        ratios = [ms(new) / ms(base) for new, base in pairs]
        print(f"  {row} / {row}@base ms/frame, paired runs: median {statistics.median(ratios):.3f} "
              f"({', '.join(f'{r:.3f}' for r in ratios)})")
# Each stage's ms per frame and share of the row's ms/frame (medians over the runs): the estimator's
# stages from stage_ms_per_frame, the front end's (tracking; prepare: pyramids and FAST) and the decoding's
# CPU from frontend.cpu_ms; "rest"
# is what the row's ms/frame holds beyond them (reading features, output, waiting for a core).
stages = ("propagate", "build", "solve", "marginalize")
def stage_ms(s, key):
    if key in stages: return s.get("stage_ms_per_frame", {}).get(key, 0.0)
    return cpu(s, key) or 0.0
print("stages, ms per frame (share of ms/frame):")
print(f"  {'row':<24} " + " ".join(f"{k:>17}" for k in stages + ("frontend", "prepare", "decode", "rest")))
for name in sorted(ran):
    total = median(name, ms)
    values = [median(name, lambda s, k=k: stage_ms(s, k)) for k in stages + ("frontend", "prepare", "decode")]
    values.append(total - sum(values))
    print(f"  {name:<24} " + " ".join(f"{v:8.3f} ({100 * v / total:4.1f} %)" for v in values))
for name in sorted(ran):  # each stage of this build against the baseline's, median of the paired runs
    pairs = list(zip(rows(name), rows(name + "@base"))) if not name.endswith("@base") else []
    if not pairs: continue
    ratio = lambda k: statistics.median([stage_ms(new, k) / stage_ms(base, k) for new, base in pairs
                                         if stage_ms(base, k) > 0] or [float("nan")])
    print(f"  {name} / {name}@base per stage, paired runs: " +
          ", ".join(f"{k} {ratio(k):.3f}" for k in stages + ("frontend", "prepare", "decode")) +
          f", ms/frame {statistics.median([ms(new) / ms(base) for new, base in pairs]):.3f}")
for row in ("real_micro", "real_flight"):
    one, two = f"{row}_1core", f"{row}_2cores"
    if not rows(one): continue
    for label, get in (("CPU: front_cpu + decode_cpu", fe_dec_cpu), ("front_ms (wall) + decode_cpu", fe_dec_wall)):
        new, base = median(one, get), median(one + "@base", get)
        if new is not None and base:
            print(f"  {row}, one core, front end + decoding, {label}: {new:.2f} / {base:.2f} ms = {new / base:.2f}x "
                  f"the baseline")
    for name in (one, one + "@base", two, two + "@base"):
        if rows(name):
            print(f"  {name}: {median(name, ms):.2f} ms/frame, {median(name, rtf):.2f}x real time")
EOF
