#!/usr/bin/env bash
# Starts in flight over noise draws and start offsets (docs/initialization.md,
# "Why the MSCKF's cut rows spread"): each sequence cut S, S+0.05 and S+0.10 s
# into the recording (one, two frames later: the three phases of the MSCKF's
# marginalization schedule), for noise seeds 1-3, against the full run with
# the same seed over the same span. Prints a Markdown table: per row and seed,
# ATE (SE3) of the cut run and of the full run over its span, their ratio, and
# how far the cut run's motion still differs from the full run's in its last
# part (RMS over 0.5 s displacements after the cut's first 15 s, after one
# rotation between the two; mm): ~0.5 mm when the cut converged onto the full run.
#   tools/init_phase_table.sh [OUT]     (default OUT: out/init_phase; resumable)
# DATA overrides the EuRoC folder (default ../shared/data/euroc), VIO the
# binary, JOBS the parallel runs (default 2), POLICIES (default "swf msckf"),
# SEEDS (default "1 2 3"), ROWS (default: V2_01_easy at 10 20 30 40 s,
# MH_04_difficult at 10 30 40 s; SEQ:START, space separated), OFFSETS
# (default "0 0.05 0.1").
set -euo pipefail
root="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
out="${1:-$root/out/init_phase}"
data="${DATA:-$root/../shared/data/euroc}"
vio="${VIO:-${BUILD_DIR:-$root/build}/bin/vio}"
config="$root/config/euroc_stereo.yaml"
policies="${POLICIES:-swf msckf}"
seeds="${SEEDS:-1 2 3}"
offsets="${OFFSETS:-0 0.05 0.1}"
rows="${ROWS:-V2_01_easy:10 V2_01_easy:20 V2_01_easy:30 V2_01_easy:40 MH_04_difficult:10 MH_04_difficult:30 MH_04_difficult:40}"
declare -A policy_flags=([swf]="--policy=swf" [msckf]="--policy=msckf --window_size=10")
mkdir -p "$out/runs"

starts() {  # ROW -> the cut starts of the row [s]
  # shellcheck disable=SC2086
  python3 -c "import sys; s=float(sys.argv[1]); print(' '.join('%g' % (s + float(o)) for o in sys.argv[2:]))" \
    "${1#*:}" $offsets
}
simulate() {  # SEQ START SEED
  local dir="$out/data/$1_$2_s$3" flags=()
  [ -f "$dir/mav0/features0/data.csv" ] && return
  [ "$2" = 0 ] || flags+=(--from_start_s="$2")
  [ "$3" = 1 ] || flags+=(--noise_seed="$3")
  nice "$vio" simulate --from="$data/$1" "${flags[@]}" --output_dir="$dir" >/dev/null
}
run() {  # SEQ START SEED POLICY
  local dir="$out/runs/$1_$2_s$3_$4"
  [ -f "$dir/summary.json" ] && return
  # shellcheck disable=SC2086
  nice "$vio" run --dataset="$out/data/$1_$2_s$3" --config="$config" ${policy_flags[$4]} --output_dir="$dir" \
    >"$dir.log" 2>&1 || true
}
# shellcheck source=tools/table_lib.sh
source "$root/tools/table_lib.sh"   # queue, ate
motion_difference() {  # CUT FULL_SPAN -> RMS [mm] of the 0.5 s displacement difference after the first 15 s
  python3 - "$1" "$2" <<'EOF'
import sys
import numpy as np
cut, full = (np.loadtxt(f, comments='#') for f in sys.argv[1:3])
_, i, j = np.intersect1d(np.round(cut[:, 0], 3), np.round(full[:, 0], 3), return_indices=True)
cut, full = cut[i], full[j]  # the frames both runs estimated
n = len(cut)
if n < 400:
    print('n/a')
    sys.exit()
pc, pf = cut[:n, 1:4], full[:n, 1:4]
u, _, vt = np.linalg.svd((pc - pc.mean(0)).T @ (pf - pf.mean(0)))
d = np.diag([1.0, 1.0, np.sign(np.linalg.det(vt.T @ u.T))])
rotation = vt.T @ d @ u.T
k = 10  # frames: 0.5 s at 20 Hz
diff = (rotation @ (pc[k:] - pc[:-k]).T).T - (pf[k:] - pf[:-k])
late = (cut[:n - k, 0] - cut[0, 0]) >= 15.0
print('%.1f' % (1e3 * np.sqrt(np.mean(np.sum(diff[late] ** 2, axis=1)))))
EOF
}

jobs=()
for seed in $seeds; do
  for row in $rows; do
    simulate "${row%:*}" 0 "$seed"
    for start in $(starts "$row"); do simulate "${row%:*}" "$start" "$seed"; done
  done
done
for seed in $seeds; do
  for policy in $policies; do
    for seq in $(for row in $rows; do echo "${row%:*}"; done | sort -u); do queue run "$seq" 0 "$seed" "$policy"; done
    for row in $rows; do
      for start in $(starts "$row"); do queue run "${row%:*}" "$start" "$seed" "$policy"; done
    done
  done
done
wait

echo "| sequence | start [s] | policy | seed | ATE se3 [m] | full run, same span [m] | ratio | motion difference after 15 s [mm] |"
echo "|---|---|---|---|---|---|---|---|"
for row in $rows; do
  seq="${row%:*}"
  for start in $(starts "$row"); do
    for policy in $policies; do
      for seed in $seeds; do
        dir="$out/runs/${seq}_${start}_s${seed}_${policy}"
        gt="$out/data/${seq}_${start}_s${seed}/mav0/state_groundtruth_estimate0/data.csv"
        cut_ate=$(ate "$dir/trajectory.txt" "$gt")
        first=$(awk -F, 'NR>1 && $1 !~ /^#/ {printf "%.9f\n", $1*1e-9; exit}' \
          "$out/data/${seq}_${start}_s${seed}/mav0/cam0/data.csv")
        awk -v t0="$first" '$1 !~ /^#/ && $1 + 0 >= t0 - 1e-6' \
          "$out/runs/${seq}_0_s${seed}_${policy}/trajectory.txt" >"$dir/full_span.txt"
        full_ate=$(ate "$dir/full_span.txt" "$gt")
        ratio=$(python3 -c "import sys; a,b=float(sys.argv[1]),float(sys.argv[2]); print('%.2f' % (a/b) if b==b and b>0 and a==a else 'n/a')" "$cut_ate" "$full_ate")
        echo "| $seq | $start | $policy | $seed | $cut_ate | $full_ate | $ratio | $(motion_difference "$dir/trajectory.txt" "$dir/full_span.txt") |"
      done
    done
  done
done
