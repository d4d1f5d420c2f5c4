"""Run the viewer monkey (tests/viewer_monkey.py) for a long while: a seeded random stream of
user actions on the real window, under the X display given or a fresh Xvfb.

    python scripts/monkey.py --seconds 3600 --seed 7 --scene large

Prints the monkey's summary line and its findings; exit status 1 when there are findings.
The run's files (result.json, the monkey's folder of good and bad files, saved views,
screenshots) go to --out (default: a new temporary folder, kept).
"""

from __future__ import annotations

import argparse
import os
import shutil
import subprocess
import sys
import tempfile
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
DRIVER = ROOT / "tests" / "viewer_monkey.py"


def xvfb() -> tuple[subprocess.Popen, str]:
    """A fresh Xvfb and its display name."""
    exe = shutil.which("Xvfb")
    if exe is None:
        sys.exit("monkey: error: Xvfb is missing and DISPLAY is not set (scripts/setup.sh installs xvfb)")
    r, w = os.pipe()
    proc = subprocess.Popen(
        [exe, "-displayfd", str(w), "-screen", "0", "1920x1080x24", "-nolisten", "tcp"],
        pass_fds=(w,),
        stderr=subprocess.DEVNULL,
    )
    os.close(w)
    with os.fdopen(r) as f:
        number = f.readline().strip()
    if not number:
        sys.exit("monkey: error: Xvfb did not start")
    return proc, f":{number}"


def main() -> int:
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    p.add_argument("--seconds", type=float, default=600.0, help="how long to act (default 600)")
    p.add_argument("--seed", type=int, default=0)
    p.add_argument("--scene", default="demo", help="demo, engine, large (20,000 parts), or a scene file")
    p.add_argument("--parts", type=int, default=20_000, help="parts of the large scene")
    p.add_argument("--warmup", type=float, default=0.2, help="part of the run before the growth baseline")
    p.add_argument("--settles", type=int, default=8, help="settled samples of GL objects and RSS (>= 2)")
    p.add_argument("--out", type=Path, default=None, help="the run's folder (default: a new temporary one)")
    a = p.parse_args()
    out = a.out or Path(tempfile.mkdtemp(prefix="rtta-monkey-"))
    out.mkdir(parents=True, exist_ok=True)
    server, display = (None, os.environ["DISPLAY"]) if os.environ.get("DISPLAY") else xvfb()
    env = {**os.environ, "DISPLAY": display, "RTTA_CACHE_DIR": str(out / "cache")}
    args = ["--scene", a.scene, "--seed", str(a.seed), "--seconds", str(a.seconds)]
    args += ["--parts", str(a.parts), "--warmup", str(a.warmup), "--settles", str(a.settles)]
    try:
        proc = subprocess.run([sys.executable, str(DRIVER), str(out / "run"), *args], env=env, cwd=out)
    finally:
        if server is not None:
            server.terminate()
            server.wait(10)
    print(f"monkey: the run's files are in {out}")
    return proc.returncode


if __name__ == "__main__":
    sys.exit(main())
