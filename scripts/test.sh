#!/usr/bin/env bash
# Set up, then run the whole test suite (GL tests run headless on Mesa llvmpipe through EGL;
# the viewer's window tests start their own Xvfb).
set -euo pipefail
cd "$(dirname "$0")/.."
bash scripts/setup.sh test        # the base install carries the viewer: its tests run without any viewer extra
.venv/bin/ruff check rtta viewer tests scripts
.venv/bin/ruff format --check rtta viewer tests scripts   # the tree as `ruff format` leaves it
.venv/bin/lint-imports              # the layers and no-cycle contracts in pyproject.toml
.venv/bin/basedpyright              # types, basic mode, over rtta and viewer ([tool.basedpyright] in pyproject.toml)
exec .venv/bin/pytest "$@"          # -m "not slow", -m "not viewer", -m gl: see the markers in pyproject.toml
