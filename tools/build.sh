#!/usr/bin/env bash
# Configures and builds the project (Release) into build/. Used by demo.sh,
# test.sh and the Dockerfile; BUILD_DIR overrides the folder, JOBS the
# parallelism, CMAKE_ARGS adds configure options.
#
# usage: build.sh [--progress] [TARGET...]   (default: every target)
#   --progress  a line per 10 % of the build, and for each step that starts
#               30 s or more after the last line, instead of the compiler lines;
#               the whole output is in BUILD_DIR/build.log (printed on failure)
set -euo pipefail
root="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
build="${BUILD_DIR:-$root/build}"
jobs="${JOBS:-$(nproc)}"
progress=0
if [ "${1:-}" = "--progress" ]; then progress=1; shift; fi
targets=()
for target in "$@"; do targets+=(--target "$target"); done

read -r -a cmake_args <<< "${CMAKE_ARGS:-}"
[ "$progress" -eq 1 ] && echo "build: configuring with CMake (Release, Ninja) in $build"
cmake -S "$root" -B "$build" -G Ninja -DCMAKE_BUILD_TYPE=Release "${cmake_args[@]}" >/dev/null
if [ "$progress" -eq 0 ]; then
  exec cmake --build "$build" -j "$jobs" "${targets[@]}"
fi

# Ninja's status line is "@@finished/total@@ what"; print it every 10 %.
log="$build/build.log"
report() {
  local last=0 last_time=$SECONDS finished total percent
  while IFS= read -r line; do
    echo "$line" >> "$log"
    [[ "$line" =~ ^@@([0-9]+)/([0-9]+)@@ ]] || continue
    finished=${BASH_REMATCH[1]} total=${BASH_REMATCH[2]}
    percent=$((100 * finished / total))
    if [ "$finished" -gt 0 ] && { [ "$percent" -ge $((last + 10)) ] || [ "$finished" -eq "$total" ] ||
                                  [ $((SECONDS - last_time)) -ge 30 ]; }; then
      last=$percent last_time=$SECONDS
      echo "build: ${percent}% (${finished}/${total} steps, $((SECONDS - started)) s)"
    fi
  done
}
started=$SECONDS
: > "$log"
if ! NINJA_STATUS="@@%f/%t@@ " cmake --build "$build" -j "$jobs" "${targets[@]}" 2>&1 | report; then
  echo "build: FAILED; the last lines of $log:" >&2
  tail -n 40 "$log" >&2
  exit 1
fi
echo "build: done in $((SECONDS - started)) s (${*:-every target}; log: $log)"
