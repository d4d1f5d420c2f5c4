#!/usr/bin/env bash
# Set up, then run the main job on the built-in demo (or the scene file given):
# - with a display: the interactive viewer, rtta-view;
# - without one: headless (EGL) snapshots of every mode, with the pads and pistons hidden
#   inside the caliper in focus, and the per-object atlas export, into out/demo/.
set -euo pipefail
cd "$(dirname "$0")/.."
if [ -n "${DISPLAY:-}${WAYLAND_DISPLAY:-}" ]; then
  bash scripts/setup.sh viewer
  exec .venv/bin/rtta-view "$@"
fi
bash scripts/setup.sh
mkdir -p out
focus=()
[ $# -eq 0 ] && focus=(--focus pad_inner pad_outer piston_1 piston_2)
.venv/bin/rtta snapshot "$@" --all-modes out/demo "${focus[@]}"
.venv/bin/rtta export "$@" --out out/demo/atlas
echo "no display: wrote out/demo/*.png (std, sprites, transparent, ghosted, ghosted-ao) and out/demo/atlas/;"
echo "for the interactive viewer run this with a display (or: xvfb-run bash scripts/run.sh)"
