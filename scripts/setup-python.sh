#!/usr/bin/env bash
# Creates the virtual environment .venv (if missing) and installs mgn into it with the test
# extras, the dev extra (the pinned checkers scripts/test.sh runs) and the learn extra (PyTorch:
# the CPU build torch==2.13.0 is installed first, so that pip keeps it instead of a CUDA build).
# Builds the C++ extension (scikit-build-core); takes about a minute on 2 cores.
set -euo pipefail
cd "$(dirname "$0")/.."
PYTHON="${PYTHON:-python3}"
if [ ! -x .venv/bin/python ]; then
  "$PYTHON" -m venv .venv
fi
. .venv/bin/activate
python -m pip install --quiet --upgrade pip
python -m pip install --quiet "torch==2.13.0"
python -m pip install --quiet ".[test,dev,learn]"
python -c "import mgn; print('mgn', mgn.__version__, 'installed in .venv')"
