#!/usr/bin/env bash
# Shared set-up for ./run.sh and ./test.sh: install the Debian packages that are missing
# (apt-get update at most once), then configure and build fdem in ./build with every core.
# Source it; it defines FDEM_BUILD (the build folder) and FDEM_BIN (the fdem executable).
# FDEM_BUILD_TARGET (optional): build only that target (./run.sh builds "fdem": the tests are half the build).
set -euo pipefail
FDEM_ROOT=$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)
FDEM_BUILD=${FDEM_BUILD:-$FDEM_ROOT/build}
FDEM_PACKAGES=(build-essential cmake ninja-build libeigen3-dev libgmsh-dev catch2 libtomlplusplus-dev
               python3-numpy python3-scipy python3-matplotlib python3-pytest python3-vtk9 slurm-wlm munge)

fdem_install_missing() {
  local missing=() p
  for p in "${FDEM_PACKAGES[@]}"; do
    dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed" || missing+=("$p")
  done
  [ ${#missing[@]} -eq 0 ] && return 0
  echo "fdem setup: installing ${missing[*]}" >&2
  local sudo=""
  [ "$(id -u)" -ne 0 ] && sudo="sudo"
  $sudo apt-get update -qq
  DEBIAN_FRONTEND=noninteractive $sudo apt-get install -y -qq --no-install-recommends "${missing[@]}" >/dev/null
}

fdem_build() {
  local jobs
  jobs=$(nproc 2>/dev/null || echo 2)
  cmake -S "$FDEM_ROOT" -B "$FDEM_BUILD" -G Ninja -DCMAKE_BUILD_TYPE=Release >/dev/null
  cmake --build "$FDEM_BUILD" --parallel "$jobs" ${FDEM_BUILD_TARGET:+--target "$FDEM_BUILD_TARGET"} -- ${FDEM_BUILD_QUIET:+--quiet}
}

fdem_install_missing
fdem_build
FDEM_BIN=$FDEM_BUILD/fdem/fdem
export FDEM_BUILD FDEM_BIN FDEM_ROOT
