#!/usr/bin/env bash
# The one test command: on a fresh Debian 12 machine it installs the system packages (apt, as
# root or via sudo), creates .venv with mgn installed, builds the C++ tests, and runs them all:
# ctest (GoogleTest, mgn-cli, the find_package(mgn) consumer), then pytest.
set -euo pipefail
cd "$(dirname "$0")/.."
bash scripts/install-system-deps.sh
bash scripts/setup-python.sh
. .venv/bin/activate
cmake -S . -B build/cpp -G Ninja -DCMAKE_BUILD_TYPE=Release -DMGN_BUILD_TESTS=ON >/dev/null
cmake --build build/cpp
ctest --test-dir build/cpp --output-on-failure
python -m pytest
