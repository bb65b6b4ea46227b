#!/usr/bin/env bash
# Regenerates docs/results.md, the figures the README quotes: accuracy and time
# per frame of batch, SWF(10) and MSCKF(10), without and with the local map
# (K=4), on the hybrid EuRoC sequences
# (`vio simulate --from`, `vio sweep`, `vio eval` in SE3 and pos+yaw), the
# speed table of tools/bench.sh, the front ends on the real image pairs, the
# Monte Carlo consistency of SWF(10) and MSCKF(10), the fresh-clone `tools/demo.sh`
# and `vio verify`. Reads the
# shared data only ($VIO_DATA_DIR, default ../shared/data beside the repository).
#
# usage: tools/results.sh [--quick] [--cache=DIR] [--output=FILE]
#   --quick   minutes instead of about half an hour: the first 30 s of V2_01 only,
#             tools/bench.sh --quick on a 5 s rendering, 3 short Monte Carlo seeds,
#             no fresh-clone tools/demo.sh
#   --cache   datasets and runs (default ${VIO_RESULTS_CACHE:-/tmp/vio_results});
#             its generated folders are cleared at the start, so nothing stale is reused
#   --output  the Markdown written (default docs/results.md)
# BUILD_DIR selects the build (default build/); `vio` is built there first.
# Run it with `nice` on a shared machine: times are wall clock inside `vio run`.
set -euo pipefail
root="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
cd "$root"
data="${VIO_DATA_DIR:-../shared/data}"
euroc="$data/euroc"
cache="${VIO_RESULTS_CACHE:-/tmp/vio_results}"
output="docs/results.md"
quick=0
for arg in "$@"; do
  case "$arg" in
    --quick) quick=1 ;;
    --cache=*) cache="${arg#--cache=}" ;;
    --output=*) output="${arg#--output=}" ;;
    -h|--help) sed -n '2,16p' "$0"; exit 0 ;;
    *) echo "results.sh: unknown argument '$arg' (see --help)" >&2; exit 2 ;;
  esac
done
for seq in V2_01_easy V1_02_medium MH_04_difficult V1_01_easy_micro V1_01_easy_flight10; do
  [ -d "$euroc/$seq/mav0" ] || { echo "results.sh: $euroc/$seq/mav0 not found (set VIO_DATA_DIR)" >&2; exit 1; }
done
build="${BUILD_DIR:-build}"
vio="$build/bin/vio"
config="config/euroc_stereo.yaml"
fragments="$cache/fragments"
mkdir -p "$cache"
rm -rf "$fragments" "$cache/hybrid" "$cache/sweep_hybrid" "$cache/eval" "$cache/bench" "$cache/real" \
  "$cache/montecarlo" "$cache/verify"
mkdir -p "$fragments" "$cache/eval" "$cache/real" "$cache/verify"
started=$SECONDS
# The commit measured (documentation changes do not count as changes of what runs).
commit="$(git rev-parse --short HEAD 2>/dev/null || echo unknown)"
git diff --quiet HEAD -- . ':!docs' ':!README.md' 2>/dev/null || commit="$commit (with uncommitted changes)"
echo "results: building vio ($build)"
BUILD_DIR="$build" tools/build.sh vio >/dev/null

# The command as one shell line (arguments with spaces or quotes in double quotes).
show() {
  local out="" a
  for a in "$@"; do
    if [[ "$a" =~ [[:space:]\"\'\$] ]]; then
      if [[ "$a" =~ ^(--[a-z_]+=)(.*)$ ]]; then a="${BASH_REMATCH[1]}\"${BASH_REMATCH[2]}\""; else a="\"$a\""; fi
    fi
    out+="${out:+ }$a"
  done
  printf '%s\n' "$out"
}
# Runs a command and records it in the commands list of a section.
logged() {
  local list="$1"; shift
  show "$@" >> "$list"
  "$@"
}
stage() { echo "results: $1 ($((SECONDS - started)) s)"; }

# 1. Hybrid EuRoC: real IMU and motion, simulated stereo features.
hybrid_section() {
  local list="$fragments/hybrid.cmd" sequences runs cut=() datasets=()
  if [ "$quick" -eq 1 ]; then
    sequences="V2_01_easy"; runs="swf:10,msckf:10,batch:10,swf:10:4"; cut=(--from_duration_s=30)
  else
    sequences="V2_01_easy V1_02_medium MH_04_difficult"; runs="batch:10,swf:10,msckf:10,swf:10:4,msckf:10:4"
  fi
  for seq in $sequences; do
    stage "simulating hybrid $seq"
    logged "$list" "$vio" simulate --from="$euroc/$seq" "${cut[@]}" --output_dir="$cache/hybrid/$seq" >/dev/null 2>&1
    datasets+=("$cache/hybrid/$seq")
  done
  stage "sweeping $runs"
  logged "$list" "$vio" sweep --datasets="$(IFS=,; echo "${datasets[*]}")" --runs="$runs" --jobs=1 \
    --config="$config" --plots=false --output_dir="$cache/sweep_hybrid" > "$cache/sweep_hybrid.log" 2>&1 || true
  local run name
  for run in "$cache"/sweep_hybrid/runs/*/*/; do
    name="$(basename "$(dirname "$run")")_$(basename "$run")"
    for alignment in se3 posyaw; do
      logged "$list" "$vio" eval --estimate="${run}trajectory.txt" --groundtruth="$cache/hybrid/$(basename "$(dirname "$run")")" \
        --alignment="$alignment" --json="$cache/eval/${name}_$alignment.json" >/dev/null 2>&1 || true
    done
  done
  python3 tools/results_tables.py hybrid "$cache/sweep_hybrid/results.csv" "$cache/eval" > "$fragments/hybrid.md"
}

# 2. Speed: tools/bench.sh, each row on one core.
bench_section() {
  local list="$fragments/bench.cmd" flags=(--cache="$cache/bench")
  [ "$quick" -eq 1 ] && flags+=(--quick --rendered_s=5)
  stage "tools/bench.sh ${flags[*]}"
  logged "$list" env BUILD_DIR="$build" EUROC="$euroc" tools/bench.sh "${flags[@]}" > "$cache/bench.txt" 2>&1 || true
  { echo '```text'; grep -v '^bench: ' "$cache/bench.txt"; echo '```'; } > "$fragments/bench.md"
}

# 3. The front ends on the real image pairs (no IMU-free shortcut: the whole `vio run`).
real_section() {
  local list="$fragments/real.cmd" frontend
  for frontend in klt brisk; do
    stage "real pairs, $frontend"
    logged "$list" "$vio" run --dataset="$euroc/V1_01_easy_micro" --config="$config" --frontend="$frontend" \
      --output_dir="$cache/real/micro_$frontend" >/dev/null 2>&1 || true
    logged "$list" "$vio" run --dataset="$euroc/V1_01_easy_flight10" --config="$config" --frontend="$frontend" \
      --init=groundtruth --output_dir="$cache/real/flight10_$frontend" >/dev/null 2>&1 || true
  done
  python3 tools/results_tables.py real "$cache/real" > "$fragments/real.md"
}

# 4. Consistency: Monte Carlo over noise seeds of the synthetic flight, FEJ on.
montecarlo_section() {
  local list="$fragments/montecarlo.cmd" seeds=10 simulate_flags="--duration_s=60"
  [ "$quick" -eq 1 ] && { seeds=3; simulate_flags="--duration_s=15"; }
  stage "Monte Carlo, $seeds seeds"
  logged "$list" "$vio" sweep --seeds="$seeds" --simulate_flags="$simulate_flags" --runs=swf:10,msckf:10 --jobs=1 \
    --extra_flags="--imu_noise_scale=1 --huber_px=0 --fej=true" --plots=false \
    --output_dir="$cache/montecarlo" > "$cache/montecarlo.log" 2>&1 || true
  sed -n '/^## Monte Carlo/,$p' "$cache/montecarlo/results.md" | tail -n +2 | sed '/./,$!d' > "$fragments/montecarlo.md"
}

# 5. The README's first command on a fresh clone (full mode only): the build from scratch is most of it.
demo_section() {
  local list="$fragments/demo.cmd" clone="$cache/demo/clone"
  stage "tools/demo.sh on a fresh clone"
  rm -rf "$cache/demo"; mkdir -p "$cache/demo"
  git clone -q "$root" "$clone"
  echo "git clone -q . $clone && cd $clone && /usr/bin/time -f '%e %U %S' tools/demo.sh" >> "$list"
  (cd "$clone" && env -u CMAKE_ARGS -u BUILD_DIR -u OUT /usr/bin/time -f '%e %U %S' -o "$cache/demo/time.txt" \
    tools/demo.sh > "$cache/demo/log.txt" 2>&1) || { echo "results: tools/demo.sh failed: $cache/demo/log.txt" >&2; exit 1; }
  local wall user sys build summary
  read -r wall user sys < "$cache/demo/time.txt"
  build="$(sed -n 's/^build: done in \([0-9]*\) s.*/\1/p' "$cache/demo/log.txt")"
  summary="$(grep -m1 '^SWF(10) on the simulated flight' "$cache/demo/log.txt" || echo 'no summary line')"
  {
    echo "| whole demo, wall | build of vio, wall | user + sys CPU | its summary line |"
    echo "|---:|---:|---:|---|"
    printf '| %.0f s | %s s | %.0f s | %s |\n' "$wall" "$build" "$(awk -v u="$user" -v s="$sys" 'BEGIN { print u + s }')" "$summary"
  } > "$fragments/demo.md"
  rm -rf "$clone"
}

# 6. The paper's theorems through the window.
verify_section() {
  local list="$fragments/verify.cmd"
  stage "vio verify"
  logged "$list" "$vio" verify --json="$cache/verify/verify.json" >/dev/null 2>&1 || true
  python3 tools/results_tables.py verify "$cache/verify/verify.json" > "$fragments/verify.md"
}

hybrid_section
bench_section
real_section
montecarlo_section
[ "$quick" -eq 1 ] || demo_section
verify_section

cpu="$(sed -n 's/^model name[[:space:]]*: //p' /proc/cpuinfo | head -1)"
software="$(dpkg-query -W -f='${Package} ${Version}, ' libceres-dev libeigen3-dev libopencv-dev g++ 2>/dev/null || true)"
mode="full"; [ "$quick" -eq 1 ] && mode="--quick"
python3 tools/results_tables.py page "$fragments" "$mode" "$(date -u '+%Y-%m-%d %H:%M UTC')" "$commit" \
  "$(nproc)" "$cpu" "$((SECONDS - started))" "$(cut -d' ' -f1-3 /proc/loadavg)" "${software%, }" > "$output.tmp"
mv "$output.tmp" "$output"
stage "wrote $output"
