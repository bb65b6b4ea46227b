#!/usr/bin/env bash
# Installs whatever this project needs that is missing, from Debian 12's
# archive only. Idempotent: quiet and fast (a dpkg query) when all is present.
# Used by tools/demo.sh, tools/test.sh, .ci/run and the Dockerfile.
set -euo pipefail

PACKAGES=(
  build-essential cmake ninja-build pkg-config
  libceres-dev libeigen3-dev libopencv-dev
  libgoogle-glog-dev libgflags-dev libyaml-cpp-dev
  libgtest-dev libgmock-dev libbenchmark-dev
  librosbag-storage-dev libsensor-msgs-dev
  python3 python3-numpy python3-matplotlib
)

missing=()
for pkg in "${PACKAGES[@]}"; do
  if ! dpkg-query -W -f='${Status}' "$pkg" 2>/dev/null | grep -q "install ok installed"; then
    missing+=("$pkg")
  fi
done
[ ${#missing[@]} -eq 0 ] && exit 0

echo "install_deps: installing ${missing[*]}" >&2
SUDO=""
if [ "$(id -u)" -ne 0 ]; then
  command -v sudo >/dev/null || { echo "install_deps: need root or sudo to install: ${missing[*]}" >&2; exit 1; }
  SUDO=sudo
fi
export DEBIAN_FRONTEND=noninteractive
$SUDO apt-get update -qq
$SUDO apt-get install -y -qq --no-install-recommends "${missing[@]}" >/dev/null
