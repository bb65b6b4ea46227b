#!/usr/bin/env bash
# Starts in flight (docs/initialization.md): each shared hybrid sequence cut
# 10/20/30/40 s into the recording (`vio simulate --from_start_s`), run with
# swf and msckf 10 from that moving start (init auto), against the same span
# cut from a full-sequence run (static start; the cut has the full sequence's
# measurements from the cut on, so only the start differs) and against the cut sequence
# started from the ground truth (--init=groundtruth: the same features, so
# the initializer's own cost). Prints a Markdown table: frames estimated,
# status, how the run started and after how long, ATE (SE3) of the cut run, of
# the full run over the same span, their ratio, and of the ground-truth start.
#   tools/init_table.sh [OUT]     (default OUT: out/init; resumable)
# DATA overrides the EuRoC folder (default ../shared/data/euroc), VIO the binary,
# JOBS the parallel runs (default 2).
set -euo pipefail
root="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
out="${1:-$root/out/init}"
data="${DATA:-$root/../shared/data/euroc}"
vio="${VIO:-${BUILD_DIR:-$root/build}/bin/vio}"
config="$root/config/euroc_stereo.yaml"
mkdir -p "$out"
declare -A policy_flags=([swf]="--policy=swf" [msckf]="--policy=msckf --window_size=10")

simulate() {  # SEQ START
  local dir="$out/data/$1_$2"
  [ -f "$dir/mav0/features0/data.csv" ] && return
  if [ "$2" = 0 ]; then
    nice "$vio" simulate --from="$data/$1" --output_dir="$dir" >/dev/null
  else
    nice "$vio" simulate --from="$data/$1" --from_start_s="$2" --output_dir="$dir" >/dev/null
  fi
}
run() {  # SEQ START POLICY [SUFFIX FLAGS...]
  local dir="$out/runs/$1_$2_$3${4:-}"
  [ -f "$dir/summary.json" ] && return
  # shellcheck disable=SC2086
  nice "$vio" run --dataset="$out/data/$1_$2" --config="$config" ${policy_flags[$3]} "${@:5}" --output_dir="$dir" \
    >"$dir.log" 2>&1 || true
}
# shellcheck source=tools/table_lib.sh
source "$root/tools/table_lib.sh"   # queue, ate

mkdir -p "$out/runs"
jobs=()
for seq in V2_01_easy V1_02_medium MH_04_difficult; do
  for start in 0 10 20 30 40; do simulate "$seq" "$start"; done
done
for seq in V2_01_easy V1_02_medium MH_04_difficult; do
  for start in 0 10 20 30 40; do
    for policy in swf msckf; do
      queue run "$seq" "$start" "$policy"
      [ "$start" = 0 ] || queue run "$seq" "$start" "$policy" _gt --init=groundtruth
    done
  done
done
wait

echo "| sequence | start [s] | policy | frames estimated | status | init (wait) | ATE se3 [m] | full run, same span [m] | ratio | ground-truth start [m] |"
echo "|---|---|---|---|---|---|---|---|---|---|"
for seq in V2_01_easy V1_02_medium MH_04_difficult; do
  for start in 0 10 20 30 40; do
    for policy in swf msckf; do
      dir="$out/runs/${seq}_${start}_${policy}"
      gt="$out/data/${seq}_${start}/mav0/state_groundtruth_estimate0/data.csv"
      read -r frames estimated status method wait_s < <(python3 -c "
import json,sys; s=json.load(open(sys.argv[1])); i=s.get('init',{})
print(s['frames'], s['frames_estimated'], s['status'], i.get('method') or '-', '%.2f' % i.get('wait_s',0))" "$dir/summary.json")
      cut_ate=$(ate "$dir/trajectory.txt" "$gt")
      # The full run's trajectory over the cut sequence's span.
      full="$out/runs/${seq}_0_${policy}/trajectory.txt"
      first=$(awk -F, 'NR>1 && $1 !~ /^#/ {printf "%.9f\n", $1*1e-9; exit}' "$out/data/${seq}_${start}/mav0/cam0/data.csv")
      awk -v t0="$first" '$1 !~ /^#/ && $1 + 0 >= t0 - 1e-6' "$full" > "$dir/full_span.txt"
      full_ate=$(ate "$dir/full_span.txt" "$gt")
      ratio=$(python3 -c "import sys; a,b=float(sys.argv[1]),float(sys.argv[2]); print('%.2f' % (a/b) if b==b and b>0 and a==a else 'n/a')" "$cut_ate" "$full_ate")
      pct=$(python3 -c "import sys; print('%.1f' % (100*int(sys.argv[1])/max(1,int(sys.argv[2]))))" "$estimated" "$frames")
      gt_ate=-
      [ "$start" = 0 ] || gt_ate=$(ate "$out/runs/${seq}_${start}_${policy}_gt/trajectory.txt" "$gt")
      echo "| $seq | $start | $policy | $estimated/$frames ($pct%) | $status | $method ($wait_s s) | $cut_ate | $full_ate | $ratio | $gt_ate |"
    done
  done
done
