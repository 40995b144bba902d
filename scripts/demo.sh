#!/usr/bin/env bash
# The demo command: on a fresh Debian 12 machine it installs everything (apt as root or via sudo,
# then .venv), then exports the built-in objects and runs the ray-cast/collision smoke check.
# Output in demo_out/ (or the folder given as the first argument): models/, gallery.png, smoke.json.
set -euo pipefail
cd "$(dirname "$0")/.."
bash scripts/install-system-deps.sh
bash scripts/setup-python.sh
. .venv/bin/activate
mgn demo --out "${1:-demo_out}"
