#!/usr/bin/env bash
# Set up, then run the main job on the built-in demo, headless (EGL): snapshots of every
# mode (the pads and pistons, hidden inside the caliper, in focus) and the per-object atlas
# export, into out/demo/. The interactive viewer arrives with issue 4.
set -euo pipefail
cd "$(dirname "$0")/.."
bash scripts/setup.sh
mkdir -p out
.venv/bin/rtta snapshot --all-modes out/demo --focus pad_inner pad_outer piston_1 piston_2 "$@"
.venv/bin/rtta export --out out/demo/atlas "$@"
echo "open out/demo/*.png (std, sprites, transparent, ghosted, ghosted-ao) and out/demo/atlas/"
