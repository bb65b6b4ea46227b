#!/usr/bin/env bash
# Installs whatever this project needs that is missing, from Debian 12's
# archive only. Idempotent: quiet and fast (a dpkg query) when all is present.
# Used by tools/demo.sh, tools/test.sh, .ci/run, the Dockerfile and the checks.
#
# usage: install_deps.sh [GROUP...]   (default: build test plot)
#   build    compilers, CMake, Ninja and the -dev packages `vio` builds against
#   test     GoogleTest, GoogleMock, Google Benchmark (the suite); node and npm, and
#            tools/ros2_testdata's pinned packages (npm ci: the ROS 2 tests' independent writer)
#   plot     Python 3 with numpy and matplotlib (tools/plot_sweep.py)
#   runtime  the shared libraries `vio` loads, and plot (the Docker runtime stage)
#   docker   the Docker engine and debootstrap (tools/docker_test.sh)
#   slurm    Slurm and munge (tools/slurm_check.sh)
# Progress lines go to stderr while packages download and install.
set -euo pipefail

packages_of() {
  case "$1" in
    build) echo build-essential cmake ninja-build pkg-config libceres-dev libeigen3-dev libopencv-dev libdeflate-dev \
                libgoogle-glog-dev libgflags-dev libyaml-cpp-dev librosbag-storage-dev libsensor-msgs-dev \
                libzstd-dev liblz4-dev libsqlite3-dev ;;
    test) echo libgtest-dev libgmock-dev libbenchmark-dev "$(command -v node > /dev/null || echo nodejs npm)" ;;
    plot) echo python3 python3-numpy python3-matplotlib ;;
    runtime) echo libceres3 libopencv-core406 libopencv-imgproc406 libopencv-imgcodecs406 \
                  libopencv-features2d406 libopencv-calib3d406 libopencv-video406 libdeflate0 \
                  libgoogle-glog0v6 libgflags2.2 libyaml-cpp0.7 \
                  librosbag-storage4d libroscpp-serialization0d librostime1d libcpp-common0d \
                  libconsole-bridge1.0 libzstd1 liblz4-1 libsqlite3-0 python3 python3-numpy python3-matplotlib ;;
    docker) echo docker.io debootstrap ;;
    slurm) echo slurm-wlm munge ;;
    *) echo "install_deps: unknown group '$1' (build, test, plot, runtime, docker, slurm)" >&2; return 1 ;;
  esac
}

# The test group's node packages (tools/ros2_testdata/package-lock.json, exact
# versions) into tools/ros2_testdata/node_modules, when missing or older than the lock file.
install_node_packages() {
  local dir
  dir="$(cd "$(dirname "${BASH_SOURCE[0]}")" && pwd)/ros2_testdata"
  [ -d "$dir/node_modules" ] && [ "$dir/node_modules" -nt "$dir/package-lock.json" ] && return 0
  command -v npm >/dev/null || { echo "install_deps: no npm to install $dir's packages" >&2; return 1; }
  echo "install_deps: npm ci in $dir" >&2
  (cd "$dir" && npm ci --no-audit --no-fund --loglevel=error >&2) && touch "$dir/node_modules"
}

groups=("$@")
[ ${#groups[@]} -eq 0 ] && groups=(build test plot)
packages=()
node_packages=0
for group in "${groups[@]}"; do
  list="$(packages_of "$group")"
  read -r -a words <<< "$list"
  packages+=("${words[@]}")
  [ "$group" = test ] && node_packages=1
done

missing=()
for pkg in "${packages[@]}"; do
  if ! dpkg-query -W -f='${Status}' "$pkg" 2>/dev/null | grep -q "install ok installed"; then
    missing+=("$pkg")
  fi
done
if [ ${#missing[@]} -eq 0 ]; then
  [ "$node_packages" -eq 0 ] || install_node_packages
  exit 0
fi

echo "install_deps: installing ${missing[*]} (and what they depend on)" >&2
SUDO=""
if [ "$(id -u)" -ne 0 ]; then
  command -v sudo >/dev/null || { echo "install_deps: need root or sudo to install: ${missing[*]}" >&2; exit 1; }
  SUDO=sudo
fi
export DEBIAN_FRONTEND=noninteractive
echo "install_deps: updating the package lists" >&2
$SUDO apt-get update -qq

# apt's status lines (dlstatus:N:PERCENT:..., pmstatus:PKG:PERCENT:...) become
# one progress line per 10 % of the download and of the installation.
report_progress() {
  local last_download=-10 last_install=-10 kind percent
  while IFS=: read -r kind _ percent _; do
    percent="${percent%%.*}"
    case "$kind" in
      dlstatus) if [ "$percent" -ge $((last_download + 10)) ]; then
                  last_download=$percent; echo "install_deps: downloading ${percent}%" >&2; fi ;;
      pmstatus) if [ "$percent" -ge $((last_install + 10)) ]; then
                  last_install=$percent; echo "install_deps: installing ${percent}%" >&2; fi ;;
    esac
  done
}
log="$(mktemp)"
if ! $SUDO apt-get install -y -qq --no-install-recommends -o APT::Status-Fd=3 "${missing[@]}" \
       3>&1 >"$log" 2>&1 | report_progress; then
  cat "$log" >&2
  rm -f "$log"
  exit 1
fi
rm -f "$log"
echo "install_deps: done" >&2
[ "$node_packages" -eq 0 ] || install_node_packages
