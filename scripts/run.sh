#!/usr/bin/env bash
# Set up, then run the main job on the built-in demo: the per-object atlas export
# (headless, EGL) into out/demo/. Extra arguments go to `rtta export`.
set -euo pipefail
cd "$(dirname "$0")/.."
bash scripts/setup.sh
.venv/bin/rtta export --out out/demo "$@"
echo "open out/demo/std_color.png (direct render) and out/demo/atlas_color_*.png (every part, unoccluded)"
