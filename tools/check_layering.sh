#!/usr/bin/env bash
# Checks that dependencies point one way: every `#include "vio/<lib>/..."` in
# a library's folder names that library or one it may use (docs/design.md, "Library layout").
# Prints each violation as file:line and exits 1 when there is any.
set -euo pipefail
root="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"

# library folder -> the libraries its code may include (itself included)
declare -A allowed=(
  [marginalization]="marginalization"
  [estimator]="estimator marginalization"
  [frontend]="frontend estimator marginalization"
  [tools/dataset]="dataset estimator frontend marginalization"
  [tools/simulator]="simulator dataset estimator frontend marginalization"
  [tools/evaluation]="evaluation dataset estimator frontend marginalization"
  [tools/sweep]="sweep evaluation dataset estimator frontend marginalization"
  [tools/verify]="verify estimator marginalization"
  [tools/cli]="cli sweep verify evaluation simulator dataset estimator frontend marginalization"
)

violations=0
for folder in "${!allowed[@]}"; do
  [ -d "$root/$folder" ] || { echo "check_layering: no folder $folder" >&2; exit 2; }
  while IFS=: read -r file line text; do
    [[ "$text" =~ \#include\ \"vio/([a-z_]+)/ ]] && lib="${BASH_REMATCH[1]}"
    if [[ " ${allowed[$folder]} " != *" $lib "* ]]; then
      echo "${file#"$root"/}:$line: $folder may not include vio/$lib/ (allowed: ${allowed[$folder]})"
      violations=$((violations + 1))
    fi
  done < <(grep -rnE '#include "vio/[a-z_]+/' "$root/$folder" --include='*.h' --include='*.cc' || true)
done

# Every library folder under tools/ must be listed above.
for cmake in "$root"/tools/*/CMakeLists.txt; do
  folder="tools/$(basename "$(dirname "$cmake")")"
  [ -n "${allowed[$folder]:-}" ] || { echo "$folder: library not listed in tools/check_layering.sh"; violations=$((violations + 1)); }
done

if [ "$violations" -gt 0 ]; then
  echo "check_layering: $violations include(s) against the layering" >&2
  exit 1
fi
echo "check_layering: ${#allowed[@]} libraries, every include points down"
