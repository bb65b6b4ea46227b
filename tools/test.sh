#!/usr/bin/env bash
# Quick start, command 2: install what is missing, build (Release), run the
# whole CTest suite. Exits non-zero on any failure.
# Real-data tests read ../shared/data (or $VIO_DATA_DIR) and skip when absent;
# the Slurm check (label slow) starts a single-node Slurm, so Slurm and munge
# are installed too.
set -euo pipefail
root="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
"$root/tools/install_deps.sh" build test plot slurm
"$root/tools/build.sh"
cd "${BUILD_DIR:-$root/build}"
ctest --output-on-failure -j "${JOBS:-$(nproc)}" "$@"
