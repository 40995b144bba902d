#!/usr/bin/env bash
# Regenerates python/mgn/_core/ (the committed type stubs of the compiled core: __init__.pyi and
# one <module>.pyi per submodule mgn._core.<module>) from the installed extension. Run after
# changing a binding; tests/python/test_stubs.py checks them against the compiled core.
set -euo pipefail
cd "$(dirname "$0")/.."
python -m pip install --quiet pybind11-stubgen
out=$(mktemp -d)
pybind11-stubgen mgn._core -o "$out" --numpy-array-wrap-with-annotated
rm -rf python/mgn/_core
mkdir -p python/mgn/_core
cp "$out"/mgn/_core/*.pyi python/mgn/_core/
rm -rf "$out"
# Pointer arguments defaulting to nullptr accept None: say so (mypy checks the callers).
sed -E -i 's/: ([A-Za-z_.]+) = None,/: \1 | None = None,/' python/mgn/_core/*.pyi
ruff check --fix --quiet python/mgn/_core >/dev/null 2>&1 || true
ruff format python/mgn/_core >/dev/null 2>&1 || true
echo "updated python/mgn/_core/"
