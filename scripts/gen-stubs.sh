#!/usr/bin/env bash
# Regenerates python/mgn/_core/ (the committed type stubs of the compiled core: __init__.pyi and
# one <module>.pyi per submodule mgn._core.<module>) from the importable extension. Run after
# changing a binding. Usage: scripts/gen-stubs.sh [DEST] (default python/mgn/_core);
# tests/python/test_stubs.py writes them to a temporary DEST and compares with the committed ones.
# PYTHON (default: python) is the interpreter that imports mgn._core and runs the tools.
set -euo pipefail
cd "$(dirname "$0")/.."
PYTHON="${PYTHON:-python}"
dest="${1:-python/mgn/_core}"
# The generator's version is pinned (its output changes between versions), as in the dev extra.
"$PYTHON" -c "import pybind11_stubgen" 2>/dev/null ||
  "$PYTHON" -m pip install --quiet "pybind11-stubgen==3.0.0"
out=$(mktemp -d)
trap 'rm -rf "$out"' EXIT
"$PYTHON" -m pybind11_stubgen mgn._core -o "$out" --numpy-array-wrap-with-annotated >/dev/null
stubs="$out/mgn/_core"
# Pointer arguments defaulting to nullptr accept None: say so (mypy checks the callers).
sed -E -i 's/: ([A-Za-z_.]+) = None,/: \1 | None = None,/' "$stubs"/*.pyi
# The project's ruff settings (import order, line length), whatever DEST is.
"$PYTHON" -m ruff check --config pyproject.toml --fix --quiet "$stubs" >/dev/null 2>&1 || true
"$PYTHON" -m ruff format --config pyproject.toml --quiet "$stubs"
rm -rf "$dest"
mkdir -p "$dest"
cp "$stubs"/*.pyi "$dest"/
echo "updated $dest"
