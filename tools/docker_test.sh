#!/usr/bin/env bash
# Builds the Docker image (Dockerfile: build stage + slim runtime stage) and
# tests it: the runtime image is at most MAX_MB (400) MB, and inside it
# `vio --help`, `vio simulate`, `vio run`, a two-run `vio sweep` (which
# draws its plots with the image's Python and matplotlib) and `vio run` on a
# ROS 2 recording (`vio convert` of rendered images to MCAP) work end to end.
#
# usage: tools/docker_test.sh [--no-build]      (--no-build: test the existing image)
#   IMAGE  the tag to build and test (default: vio)
#   BASE   the Debian 12 base image (default: debian:bookworm; when it is not
#          present and cannot be pulled, a minimal one is made with
#          debootstrap, from the Debian mirror of this machine's own apt
#          sources, and imported as vio-base:bookworm)
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

# The Debian archive this machine's apt uses: the URI of its sources' entry for
# bookworm itself (not -updates or -security), deb822 .sources files first,
# then the one-line sources.list format.
apt_mirror() {
  local f
  for f in /etc/apt/sources.list.d/*.sources; do
    [ -f "$f" ] || continue
    awk 'function flush() { if (hit && uri != "") { print uri; found = 1; exit } uri = ""; hit = 0 }
         /^[ \t]*$/ { flush(); next }
         $1 == "URIs:" { uri = $2 }
         $1 == "Suites:" { for (i = 2; i <= NF; i++) if ($i == "bookworm") hit = 1 }
         END { if (!found) flush() }' "$f"
  done
  for f in /etc/apt/sources.list /etc/apt/sources.list.d/*.list; do
    [ -f "$f" ] || continue
    sed -e 's/\[[^]]*\]//' "$f" | awk '$1 == "deb" && $3 == "bookworm" { print $2 }'
  done
}

# The base image: present, pulled, or made with debootstrap.
if ! docker image inspect "$base" >/dev/null 2>&1 && ! docker pull -q "$base" >/dev/null 2>&1; then
  base=vio-base:bookworm
  if ! docker image inspect "$base" >/dev/null 2>&1; then
    command -v debootstrap >/dev/null || fail "no base image and no debootstrap: tools/install_deps.sh docker"
    mirror="$(apt_mirror | head -n 1)"
    [ -n "$mirror" ] || fail "no bookworm entry in this machine's apt sources to take a Debian mirror from"
    rootfs="$(mktemp -d /tmp/vio_rootfs.XXXXXX)"
    say "no registry: making $base with debootstrap (minbase bookworm from $mirror) in $rootfs"
    nice -n 15 debootstrap --variant=minbase bookworm "$rootfs" "$mirror" > "$rootfs.log" 2>&1 ||
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
say "vio run on a ROS 2 recording (MCAP) inside the image"
in_image simulate --output_dir=/results/images --duration_s=8 --seed=2 --camera=images > "$work/images.log" ||
  fail "vio simulate --camera=images: $(tail -n 5 "$work/images.log")"
in_image convert --input=/results/images --output=/results/images.mcap > "$work/convert.log" ||
  fail "vio convert to MCAP: $(tail -n 5 "$work/convert.log")"
in_image run --dataset=/results/images.mcap --calibration=/results/images --output_dir=/results/run_mcap \
  > "$work/run_mcap.log" || fail "vio run on the MCAP: $(tail -n 5 "$work/run_mcap.log")"
grep -q '"status": "ok"' "$work/run_mcap/summary.json" || fail "vio run on the MCAP did not end ok: $(cat "$work/run_mcap.log")"
grep "^status\|^ATE \[m\]" "$work/run_mcap.log" | sed 's/^/  /'
say "PASSED: $image is $size_mb MB; simulate, run, sweep (with plots) and a ROS 2 recording's run work inside it"
