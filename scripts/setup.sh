#!/usr/bin/env bash
# Set up a fresh Debian machine for rtta: system GL libraries (Mesa llvmpipe through EGL)
# when missing, a virtual environment in .venv, and rtta installed into it (not editable,
# so the tests exercise the wheel with its shaders and demo scene).
# Usage: scripts/setup.sh [EXTRAS]   (pip extras, comma-separated, e.g. "test,viewer")
# A run on a checkout that has not changed since the last one does nothing: .venv/.setup-stamp
# holds a hash of what was installed (this script, pyproject.toml, the extras, the Python,
# the source files rtta/ viewer/ shaders/ assets/), and apt and pip are skipped when it matches.
set -euo pipefail
cd "$(dirname "$0")/.."
extras="${1:-}"
STAMP=.venv/.setup-stamp
SOURCES=(rtta viewer shaders assets)

stamp() {  # the hash of everything the install depends on
  {
    echo "extras=$extras"
    .venv/bin/python --version 2>&1 || true
    cat scripts/setup.sh pyproject.toml
    if git rev-parse --is-inside-work-tree >/dev/null 2>&1; then
      git ls-files -s -- "${SOURCES[@]}"  # the tracked files' blob hashes: no file is read
      git ls-files -z -m -o --exclude-standard -- "${SOURCES[@]}" | xargs -0 -r sha256sum 2>/dev/null || true
    else
      find "${SOURCES[@]}" -type f ! -name '*.pyc' -print0 | sort -z | xargs -0 -r sha256sum
    fi
  } | sha256sum | cut -d' ' -f1
}

if [ -f "$STAMP" ] && [ -x .venv/bin/python ] && [ "$(cat "$STAMP")" = "$(stamp)" ]; then
  echo "setup: .venv is up to date (nothing changed since the last setup)"
  exit 0
fi
rm -f "$STAMP"

need_apt=()
ldconfig -p 2>/dev/null | grep -q 'libEGL.so.1 ' || need_apt+=(libegl1)
ldconfig -p 2>/dev/null | grep -q 'libEGL_mesa.so.0' || need_apt+=(libegl-mesa0)
ldconfig -p 2>/dev/null | grep -q 'libOpenGL.so.0' || need_apt+=(libopengl0)
ldconfig -p 2>/dev/null | grep -q 'libGL.so.1 ' || need_apt+=(libgl1)
ls /usr/lib/*/dri/swrast_dri.so >/dev/null 2>&1 || need_apt+=(libgl1-mesa-dri)
python3 -c 'import venv, ensurepip' 2>/dev/null || need_apt+=(python3-venv)
case ",$extras," in
  *,viewer,*|*,test,*)   # the viewer's window: X libraries, and Xvfb for tests and headless runs
    command -v Xvfb >/dev/null 2>&1 || need_apt+=(xvfb)
    ldconfig -p 2>/dev/null | grep -q 'libGLX.so.0' || need_apt+=(libglx0)
    ;;
esac
if [ ${#need_apt[@]} -gt 0 ]; then
  echo "setup: installing system packages: ${need_apt[*]}"
  SUDO=""; [ "$(id -u)" -ne 0 ] && SUDO="sudo"
  $SUDO apt-get update -qq
  DEBIAN_FRONTEND=noninteractive $SUDO apt-get install -y -qq --no-install-recommends "${need_apt[@]}"
fi

PY=python3
if ! $PY -c 'import sys; sys.exit(sys.version_info < (3, 11))'; then
  echo "setup: Python 3.11 or newer is required (found $($PY --version))" >&2
  exit 1
fi
[ -x .venv/bin/python ] || $PY -m venv .venv
.venv/bin/python -m pip install -q --disable-pip-version-check --upgrade pip
spec="."
[ -n "$extras" ] && spec=".[$extras]"
.venv/bin/python -m pip install -q --disable-pip-version-check --force-reinstall --no-deps "$spec"
.venv/bin/python -m pip install -q --disable-pip-version-check "$spec"
stamp >"$STAMP"
