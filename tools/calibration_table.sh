#!/usr/bin/env bash
# A rig that is not EuRoC-perfect (docs/calibration.md): each shared hybrid
# sequence simulated clean, with its camera stamps -30/-15/+15/+30 ms off the
# IMU's (`vio simulate --time_offset_ms`) and with sensor.yaml's camera-IMU
# extrinsics off by 1 deg / 1.5 cm and 2 deg / 3 cm (`--extrinsic_error_deg/_m`,
# axis and direction from the default seed), each run with swf and msckf 10 and
# default flags, the extrinsic errors also with the probe (--extrinsics_probe_s=30). Prints a Markdown table: the clean run's ATE (SE3) and, for each
# error, the run's ATE against the clean run's / the time offset's final error
# [ms] / the rig's rotation error at the end [deg] (the calibration folder the
# run writes, or the sensor.yaml it read, against the sequence's own sensor.yaml,
# the truth of hybrid data).
#   tools/calibration_table.sh [OUT]     (default OUT: out/calibration; resumable)
# DATA overrides the EuRoC folder (default ../shared/data/euroc), VIO the binary,
# JOBS the parallel runs (default 2), SEQUENCES the sequences.
set -euo pipefail
root="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
out="${1:-$root/out/calibration}"
data="${DATA:-$root/../shared/data/euroc}"
vio="${VIO:-${BUILD_DIR:-$root/build}/bin/vio}"
config="$root/config/euroc_stereo.yaml"
read -r -a sequences <<< "${SEQUENCES:-V2_01_easy V1_02_medium MH_04_difficult}"
mkdir -p "$out/data" "$out/runs"
declare -A case_flags=([clean]="" [td-30]="--time_offset_ms=-30" [td-15]="--time_offset_ms=-15"
                       [td+15]="--time_offset_ms=15" [td+30]="--time_offset_ms=30"
                       [rig1]="--extrinsic_error_deg=1 --extrinsic_error_m=0.015"
                       [rig2]="--extrinsic_error_deg=2 --extrinsic_error_m=0.03")
datasets=(clean td-30 td-15 td+15 td+30 rig1 rig2)
# A case: a dataset, and the run's flags beyond the defaults.
cases=(clean td-30 td-15 td+15 td+30 rig1 rig2 rig1+probe rig2+probe)
declare -A run_flags=([rig1+probe]="--extrinsics_probe_s=30" [rig2+probe]="--extrinsics_probe_s=30")
declare -A case_titles=([td-30]="-30 ms" [td-15]="-15 ms" [td+15]="+15 ms" [td+30]="+30 ms"
                        [rig1]="1 deg / 1.5 cm" [rig2]="2 deg / 3 cm"
                        [rig1+probe]="1 deg / 1.5 cm, probe" [rig2+probe]="2 deg / 3 cm, probe")

simulate() {  # SEQ CASE
  local dir="$out/data/$1_$2"
  [ -f "$dir/mav0/features0/data.csv" ] && return
  # shellcheck disable=SC2086
  nice "$vio" simulate --from="$data/$1" ${case_flags[$2]} --output_dir="$dir" >/dev/null
}
run() {  # SEQ CASE POLICY
  local dir="$out/runs/$1_$2_$3"
  [ -f "$dir/summary.json" ] && return
  # shellcheck disable=SC2086
  nice "$vio" run --dataset="$out/data/$1_${2%+probe}" --config="$config" --policy="$3" --window_size=10 \
    ${run_flags[$2]:-} --output_dir="$dir" >"$dir.log" 2>&1 || true
}
# shellcheck source=tools/table_lib.sh
source "$root/tools/table_lib.sh"   # queue, ate

jobs=()
for seq in "${sequences[@]}"; do
  for d in "${datasets[@]}"; do queue simulate "$seq" "$d"; done
done
wait
jobs=()
for seq in "${sequences[@]}"; do
  for c in "${cases[@]}"; do
    for policy in swf msckf; do queue run "$seq" "$c" "$policy"; done
  done
done
wait

# The run's status, its time offset's error against the simulated one [ms] and
# its rig's rotation error [deg]: the written cam0 T_BS against the sequence's.
errors() {  # RUN_DIR DATASET_DIR SEQ
  python3 - "$1" "$2" "$data/$3/mav0/cam0/sensor.yaml" <<'EOF'
import json, math, re, sys
run, dataset, truth_yaml = sys.argv[1:4]
s = json.load(open(run + "/summary.json"))
truth_offset = 0.0
for line in open(dataset + "/mav0/rig_truth.yaml"):
    if line.startswith("time_offset_ms:"):
        truth_offset = float(line.split(":")[1].split("#")[0])
offset = s.get("calibration", {}).get("time_offset_ms")
offset_error = "%+.2f" % (offset - truth_offset) if offset is not None else "-"
def rotation(path):
    text = open(path).read()
    block = re.search(r"T_BS:.*?data:\s*\[([^\]]*)\]", text, re.S)
    v = [float(x) for x in block.group(1).replace("\n", " ").split(",")]
    return [v[0:3], v[4:7], v[8:11]]
try:  # the rig the run wrote, else the one it read (the state off, nothing written)
    try:
        a = rotation(run + "/calibration/mav0/cam0/sensor.yaml")
    except OSError:
        a = rotation(dataset + "/mav0/cam0/sensor.yaml")
    b = rotation(truth_yaml)
    trace = sum(a[i][k] * b[i][k] for i in range(3) for k in range(3))  # trace(A^T B)
    rig = "%.2f" % math.degrees(math.acos(max(-1.0, min(1.0, (trace - 1) / 2))))
except (OSError, AttributeError, ValueError):
    rig = "-"
print(s["status"], offset_error, rig)
EOF
}

header="| sequence | policy | clean: ATE se3 [cm] / offset [ms] / rig [deg] |"
rule="|---|---|---|"
for c in "${cases[@]:1}"; do header+=" ${case_titles[$c]} |"; rule+="---|"; done
echo "$header"
echo "$rule"
for seq in "${sequences[@]}"; do
  for policy in swf msckf; do
    gt="$out/data/${seq}_clean/mav0/state_groundtruth_estimate0/data.csv"
    clean=$(ate "$out/runs/${seq}_clean_${policy}/trajectory.txt" "$gt")
    read -r status offset rig < <(errors "$out/runs/${seq}_clean_${policy}" "$out/data/${seq}_clean" "$seq")
    clean_cm=$(python3 -c "import sys; print('%.3f' % (100*float(sys.argv[1])))" "$clean")
    row="| $seq | $policy(10) | $clean_cm / $offset / $rig$([ "$status" = ok ] || echo " ($status)") |"
    for c in "${cases[@]:1}"; do
      dir="$out/runs/${seq}_${c}_${policy}"
      a=$(ate "$dir/trajectory.txt" "$gt")
      read -r status offset rig < <(errors "$dir" "$out/data/${seq}_${c%+probe}" "$seq")
      ratio=$(python3 -c "import sys; a,b=float(sys.argv[1]),float(sys.argv[2]); print('%.2fx' % (a/b) if b==b and b>0 and a==a else 'n/a')" "$a" "$clean")
      row+=" $ratio / $offset / $rig$([ "$status" = ok ] || echo " ($status)") |"
    done
    echo "$row"
  done
done
