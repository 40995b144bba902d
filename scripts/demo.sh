#!/usr/bin/env bash
# The demo command: on a fresh Debian 12 machine it installs everything (apt as root or via sudo,
# then .venv), then generates a small dataset from the built-in objects (mgn generate, 3 scenes x
# 37 views, every label; config scripts/demo.yaml), validates it, and draws a picture and a report.
# Output in demo_out/ (or the folder given as the first argument); a second run resumes.
set -euo pipefail
cd "$(dirname "$0")/.."
bash scripts/install-system-deps.sh
bash scripts/setup-python.sh
. .venv/bin/activate
out="${1:-demo_out}"
mgn generate --out "$out" --scenes "${MGN_DEMO_SCENES:-3}" --config scripts/demo.yaml --resume
mgn validate "$out"
mgn show "$out" --scene 0 --view 0 --grasps suction --layout -o "$out/scene0_view0.png"
mgn report "$out" -o "$out/report.html"
echo "demo: $out (open $out/report.html; $out/scene0_view0.png)"
