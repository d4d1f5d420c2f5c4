"""Native readers run in a child process: OpenCASCADE (cascadio), ifcopenshell and USD.

A damaged file can crash these libraries (cascadio dies of a segmentation fault on STEP
files with a few bytes changed) or send them into work that does not end (ifcopenshell
ran for over 5 minutes on a 69 KB IFC file with one span repeated). In the process that
asked, either would kill or hang the CLI or the viewer. The child reads the file with
the same reader and hands the Assembly back, pickled into a private temporary folder;
the parent waits at most `time_limit(path)` (RTTA_READER_TIMEOUT seconds, when set) and
turns a crash or a timeout into one RttaError. Cost: one Python start, about 0.4 s.
"""

from __future__ import annotations

import os
import pickle
import signal
import subprocess
import sys
import tempfile
from pathlib import Path

from ...errors import RttaError

BASE_S = 60.0  # seconds any file gets
PER_MB_S = 30.0  # and per megabyte (OpenCASCADE meshes a 20 MB assembly in about a minute)
ENV = "RTTA_READER_TIMEOUT"

_CHILD = r"""
import importlib, os, pickle, sys
from pathlib import Path
module, path, out = sys.argv[1:4]
from rtta.errors import RttaError
try:
    result = ("ok", importlib.import_module(module).read(Path(path)))
except RttaError as exc:
    result = ("error", exc.message)
except MemoryError:
    result = ("error", "out of memory while reading it")
except Exception as exc:
    from rtta.errors import reason
    result = ("failed", reason(exc))
with open(out + ".part", "wb") as f:
    pickle.dump(result, f, protocol=5)
os.replace(out + ".part", out)
"""


def time_limit(path: Path) -> float:
    """Seconds the reader of `path` may take: RTTA_READER_TIMEOUT, or 60 s + 30 s per MB."""
    text = os.environ.get(ENV, "").strip()
    if text:
        try:
            value = float(text)
        except ValueError:
            value = 0.0
        if value > 0:  # NaN is not
            return value
    try:
        size = path.stat().st_size
    except OSError:
        size = 0
    return BASE_S + PER_MB_S * size / 1e6


def read(module: str, path: Path, library: str):
    """What `module`.read(path) gives (module: a dotted name, e.g. rtta.scene.readers.step),
    read in a child process that gets this process's sys.path."""
    limit = time_limit(path)
    env = dict(os.environ, PYTHONPATH=os.pathsep.join(p for p in sys.path if p))
    with tempfile.TemporaryDirectory(prefix="rtta-reader-") as tmp:
        out = Path(tmp) / "assembly.pickle"
        with open(Path(tmp) / "stderr", "w+b") as err:
            proc = subprocess.Popen(
                [sys.executable, "-c", _CHILD, module, str(path), str(out)],
                stdin=subprocess.DEVNULL,
                stdout=subprocess.DEVNULL,
                stderr=err,
                env=env,
            )
            try:
                rc = proc.wait(timeout=limit)
            except subprocess.TimeoutExpired:
                raise RttaError(
                    f"the {library} reader did not finish within {limit:.0f} s (the file may be "
                    f"damaged; {ENV}=SECONDS allows longer)",
                    path,
                ) from None
            finally:
                if proc.poll() is None:
                    proc.kill()
                    proc.wait()
            err.seek(0)
            said = err.read()[-4096:].decode("utf-8", "replace").strip().splitlines()
        if rc < 0:
            raise RttaError(
                f"the {library} reader crashed on this file ({_signal_name(-rc)}); it is probably damaged", path
            )
        if not out.exists():
            last = said[-1][:160] if said else f"exit status {rc}"
            raise RttaError(f"the {library} reader failed ({last})", path)
        with open(out, "rb") as f:
            status, value = pickle.load(f)
    if status == "failed":  # an exception the reader did not expect
        raise RttaError(f"the {library} reader failed ({value})", path)
    if status != "ok":
        raise RttaError(value, path)
    return value


def _signal_name(number: int) -> str:
    try:
        return signal.Signals(number).name
    except ValueError:
        return f"signal {number}"
