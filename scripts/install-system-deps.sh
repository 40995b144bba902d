#!/usr/bin/env bash
# Installs the Debian 12 packages mgn builds against. Idempotent and non-interactive;
# run as root (or through sudo). See ../third_party_notes/ for why each one is here.
set -euo pipefail

packages=(
  cmake ninja-build pkg-config g++ git
  python3 python3-dev python3-venv python3-pip
  libeigen3-dev
  libembree-dev
  libfcl-dev
  libassimp-dev
  libbullet-dev libbullet-extras-dev
  libnlopt-cxx-dev
  libosmesa6-dev
  libopencv-core-dev libopencv-imgproc-dev libopencv-imgcodecs-dev
  libgtest-dev libgmock-dev
  clang-format
  clang-tidy  # function size, complexity and bug-pattern checks of the C++ code (scripts/test.sh)
  ccache    # the test command's two builds of the core share objects (scripts/test.sh)
  chromium  # headless, only for the test that opens `mgn report` pages (tests/python)
)

missing=()
for p in "${packages[@]}"; do
  dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed" || missing+=("$p")
done
if [ ${#missing[@]} -eq 0 ]; then
  echo "install-system-deps: all ${#packages[@]} packages already installed"
  exit 0
fi

SUDO=""
if [ "$(id -u)" -ne 0 ]; then SUDO="sudo"; fi
export DEBIAN_FRONTEND=noninteractive
echo "install-system-deps: installing ${missing[*]}"
$SUDO apt-get update -qq
$SUDO apt-get install -y -qq --no-install-recommends "${missing[@]}" >/dev/null
echo "install-system-deps: done"
