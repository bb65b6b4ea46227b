#!/usr/bin/env bash
# Builds the Docker image (Dockerfile: build stage + slim runtime stage) and
# tests it: the runtime image is at most MAX_MB (400) MB, and inside it
# `vio --help`, `vio simulate`, `vio run` and a two-run `vio sweep` (which
# draws its plots with the image's Python and matplotlib) work end to end.
#
# usage: tools/docker_test.sh [--no-build]      (--no-build: test the existing image)
#   IMAGE  the tag to build and test (default: vio)
#   BASE   the Debian 12 base image (default: debian:bookworm; when it is not
#          present and cannot be pulled, a minimal one is made with
#          debootstrap and imported as vio-base:bookworm)
# Needs a running Docker daemon; without one it says how to start one and
# exits 77. Docker builds are CPU heavy: it runs them with `nice -n 15`.
set -euo pipefail
root="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
image="${IMAGE:-vio}"
base="${BASE:-debian:bookworm}"
max_mb="${MAX_MB:-400}"
build=1
[ "${1:-}" = "--no-build" ] && build=0

say() { echo "docker_test: $*"; }
fail() { echo "docker_test: FAILED: $*" >&2; exit 1; }

if ! command -v docker >/dev/null; then
  echo "docker_test: SKIPPED: no docker client. Install the engine with: tools/install_deps.sh docker" >&2
  exit 77
fi
if ! docker info >/dev/null 2>&1; then
  cat >&2 <<'EOF'
docker_test: SKIPPED: no Docker daemon is running. To start one (as root):
  tools/install_deps.sh docker                                  # docker.io and debootstrap
  dockerd --storage-driver=vfs > /var/log/dockerd.log 2>&1 &    # vfs: works in any container or VM
then run tools/docker_test.sh again. Without a reachable registry the Debian 12 base image is made
with debootstrap (a few minutes).
EOF
  exit 77
fi

# Like Debian's slim images: no documentation, manual pages or translations
# (47 MB of the 127 MB of a minbase bookworm), and dpkg told to skip them.
slim_rootfs() {
  rm -rf "$1"/var/cache/apt/archives/*.deb "$1"/var/lib/apt/lists/* \
    "$1"/usr/share/doc/* "$1"/usr/share/man/* "$1"/usr/share/locale/* "$1"/usr/share/info/*
  printf '%s\n' 'path-exclude /usr/share/doc/*' 'path-include /usr/share/doc/*/copyright' \
    'path-exclude /usr/share/man/*' 'path-exclude /usr/share/locale/*' 'path-exclude /usr/share/info/*' \
    > "$1"/etc/dpkg/dpkg.cfg.d/vio-slim
}

# The base image: present, pulled, or made with debootstrap.
if ! docker image inspect "$base" >/dev/null 2>&1 && ! docker pull -q "$base" >/dev/null 2>&1; then
  base=vio-base:bookworm
  if ! docker image inspect "$base" >/dev/null 2>&1; then
    command -v debootstrap >/dev/null || fail "no base image and no debootstrap: tools/install_deps.sh docker"
    rootfs="$(mktemp -d /tmp/vio_rootfs.XXXXXX)"
    say "no registry: making $base with debootstrap (minbase bookworm) in $rootfs"
    nice -n 15 debootstrap --variant=minbase bookworm "$rootfs" http://deb.debian.org/debian > "$rootfs.log" 2>&1 ||
      fail "debootstrap failed (log: $rootfs.log)"
    slim_rootfs "$rootfs"
    tar -C "$rootfs" -c . | docker import - "$base" >/dev/null
    rm -rf "$rootfs" "$rootfs.log"
  fi
fi

if [ "$build" -eq 1 ]; then
  say "building $image from $base (both stages; log: /tmp/vio_docker_build.log)"
  start=$SECONDS
  DOCKER_BUILDKIT=0 nice -n 15 docker build --build-arg BASE="$base" -t "$image" "$root" \
    > /tmp/vio_docker_build.log 2>&1 || { tail -n 30 /tmp/vio_docker_build.log >&2; fail "docker build"; }
  say "built in $(( (SECONDS - start) / 60 )) min $(( (SECONDS - start) % 60 )) s"
fi

size_bytes="$(docker image inspect -f '{{.Size}}' "$image")"
size_mb=$((size_bytes / 1000000))
say "image $image: $size_mb MB (limit $max_mb MB)"
[ "$size_mb" -le "$max_mb" ] || fail "the image is $size_mb MB, more than $max_mb MB"

work="$(mktemp -d /tmp/vio_docker_test.XXXXXX)"
trap 'rm -rf "$work"' EXIT
in_image() { docker run --rm -v "$work:/results" "$image" "$@"; }
in_image --help | grep -q "^  run " || fail "vio --help inside the image does not list 'run'"
say "vio simulate inside the image"
in_image simulate --output_dir=/results/data --duration_s=15 --seed=2 > "$work/simulate.log" ||
  fail "vio simulate: $(tail -n 5 "$work/simulate.log")"
say "vio run inside the image"
in_image run --dataset=/results/data --output_dir=/results/run --config=/opt/vio/config/euroc_stereo.yaml \
  > "$work/run.log" || fail "vio run: $(tail -n 5 "$work/run.log")"
grep -q '"status": "ok"' "$work/run/summary.json" || fail "vio run did not end ok: $(cat "$work/run.log")"
grep "^status\|^ATE \[m\]" "$work/run.log" | sed 's/^/  /'
say "vio sweep with plots inside the image"
in_image sweep --datasets=/results/data --runs=swf:5,msckf:5 --jobs=2 --output_dir=/results/sweep \
  > "$work/sweep.log" || fail "vio sweep: $(tail -n 5 "$work/sweep.log")"
for f in results.csv report.md plots/ate_vs_cost.png plots/trajectories_data.png; do
  [ -s "$work/sweep/$f" ] || fail "vio sweep in the image wrote no $f: $(tail -n 5 "$work/sweep.log")"
done
say "PASSED: $image is $size_mb MB; simulate, run and sweep (with plots) work inside it"
