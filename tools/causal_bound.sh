#!/usr/bin/env bash
# The exact solve of the data up to each frame (docs/local-map.md, "Online
# against batch"): batch solved over the frames up to T, for T = START,
# START+STEP, ... to the end of the recording, keeping only the pose of the
# frame at T. That pose is the maximum a posteriori estimate from every
# measurement up to T: the reference for an online estimator (one that writes
# frame T's pose at frame T), as batch's final solve is for a smoother. Each
# cut is the dataset's own files truncated at T (the same measurements as the
# whole recording): any EuRoC ASL folder with features0 or images.
#   tools/causal_bound.sh DATASET OUT [STEP_S] [TRAJECTORY...]
# Writes OUT/causal.txt (TUM, one pose per cut; resumable) and prints ATE
# (SE3) of it and, at the same timestamps, of each TRAJECTORY given (e.g. the
# final batch solve and an online window's trajectory.txt).
# VIO overrides the binary, CONFIG the configuration (default
# config/euroc_stereo.yaml), START the first cut (default 4 s).
set -euo pipefail
root="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
vio="${VIO:-${BUILD_DIR:-$root/build}/bin/vio}"
config="${CONFIG:-$root/config/euroc_stereo.yaml}"
if [ $# -lt 2 ]; then sed -n '2,15p' "$0" | sed 's/^# \{0,1\}//'; exit 2; fi
dataset="$(cd "$1" && pwd)"; out="$2"; step="${3:-2}"; shift $(( $# < 3 ? $# : 3 ))
[ -f "$dataset/mav0/cam0/data.csv" ] || { echo "causal_bound: $dataset has no mav0/cam0/data.csv" >&2; exit 2; }
mkdir -p "$out"; out="$(cd "$out" && pwd)"

cut() {  # END_NS -> $out/cut: the dataset with its rows after END_NS dropped
  local src="$dataset/mav0" dst="$out/cut/mav0" entry
  rm -rf "$out/cut"; mkdir -p "$dst"
  for entry in "$src"/*; do
    local name; name="$(basename "$entry")"
    if [ -f "$entry/data.csv" ] && [ "$name" != state_groundtruth_estimate0 ]; then
      mkdir -p "$dst/$name"
      for f in "$entry"/*; do [ "$(basename "$f")" = data.csv ] || ln -s "$f" "$dst/$name/"; done
      awk -F, -v end="$1" '/^#/ || $1 <= end' "$entry/data.csv" > "$dst/$name/data.csv"
    else
      ln -s "$entry" "$dst/$name"
    fi
  done
}

first_ns="$(awk -F, '!/^#/ {print $1; exit}' "$dataset/mav0/cam0/data.csv")"
last_ns="$(awk -F, '!/^#/ {t = $1} END {print t}' "$dataset/mav0/cam0/data.csv")"
touch "$out/causal.txt"
for t_s in $(seq "${START:-4}" "$step" $(( (last_ns - first_ns) / 1000000000 ))); do
  end_ns=$(( first_ns + t_s * 1000000000 ))
  grep -q "^# cut $t_s\$" "$out/causal.txt" && continue
  cut "$end_ns"
  nice "$vio" run --dataset="$out/cut" --config="$config" --policy=batch --output_dir="$out/run" \
    >"$out/run.log" 2>&1 || { echo "causal_bound: batch over the first $t_s s failed (see $out/run.log)" >&2; exit 1; }
  { echo "# cut $t_s"; grep -v '^#' "$out/run/trajectory.txt" | tail -1; } >> "$out/causal.txt"
  echo "cut at $t_s s: done"
done
rm -rf "$out/cut"

ate() {  # TRAJECTORY -> "rmse poses"
  "$vio" eval --estimate="$1" --groundtruth="$dataset" --alignment=se3 --json="$1.se3.json" >/dev/null 2>&1 &&
    python3 -c "import json,sys; a=json.load(open(sys.argv[1]))['ate']; print('%.4f m over %d poses' % (a['rmse_m'], a['num_poses']))" "$1.se3.json"
}
grep -v '^#' "$out/causal.txt" | awk '{print $1}' > "$out/times.txt"
echo "ATE se3, best causal estimate (batch up to each frame): $(ate "$out/causal.txt")"
i=0
for trajectory in "$@"; do
  i=$(( i + 1 ))
  # The frame nearest each cut within 10 ms: a run's stamps move with its time offset estimate.
  awk 'NR == FNR {t[n++] = $1; next} !/^#/ {
         for (k = 0; k < n; ++k) { d = $1 - t[k]; if (d < 0) d = -d; if (d < 0.01 && (!(k in best) || d < bd[k])) { best[k] = $0; bd[k] = d } }
       } END {for (k = 0; k < n; ++k) if (k in best) print best[k]}' "$out/times.txt" "$trajectory" > "$out/same_times_$i.txt"
  echo "ATE se3, $trajectory at the same frames: $(ate "$out/same_times_$i.txt")"
done
