#!/usr/bin/env bash
# The one test command: on a fresh Debian 12 machine it installs the system packages (apt, as
# root or via sudo), creates .venv with mgn installed, runs the static checks (ruff, ruff format,
# mypy, clang-format), builds the C++ tests, and runs them all: ctest
# (GoogleTest, mgn-cli, the find_package(mgn) consumer), then pytest (which also checks the import
# layers and the error classes: tests/python/test_architecture.py).
set -euo pipefail
cd "$(dirname "$0")/.."
bash scripts/install-system-deps.sh
# The wheel (pip, build/<wheel tag>) and the C++ tests (build/cpp) compile the same core sources:
# ccache lets the second build reuse the first one's objects (third_party_notes/ccache.md).
if command -v ccache >/dev/null; then
  export CMAKE_CXX_COMPILER_LAUNCHER=ccache CXX=g++ CCACHE_BASEDIR="$PWD"
fi
bash scripts/setup-python.sh
. .venv/bin/activate
# Static checks. Tools: the dev extra (pinned ruff, mypy; scripts/setup-python.sh) and Debian's
# clang-format (scripts/install-system-deps.sh). Settings: pyproject.toml and .clang-format.
ruff check python tests benchmarks
ruff format --check python tests benchmarks
mypy
find cpp bindings tests/cpp -name '*.cpp' -o -name '*.hpp' -o -name '*.h' | sort |
  xargs clang-format --dry-run -Werror
cmake -S . -B build/cpp -G Ninja -DCMAKE_BUILD_TYPE=Release -DMGN_BUILD_TESTS=ON >/dev/null
cmake --build build/cpp
ctest --test-dir build/cpp --output-on-failure
python -m pytest
