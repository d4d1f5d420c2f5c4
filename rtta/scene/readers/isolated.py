"""Native readers run in a child process: OpenCASCADE (cascadio), ifcopenshell and USD.

A damaged file can crash these libraries (cascadio dies of a segmentation fault on STEP
files with a few bytes changed), send them into work that does not end (ifcopenshell
ran for over 5 minutes on a 69 KB IFC file with one span repeated) or make them take all of
the machine's memory (a 157 KB USD file holds 60 million face indices, 240 MB unpacked, and
the format allows billions). In the
process that asked, any of these would kill or hang the CLI or the viewer, or have the
system's out-of-memory killer pick a process. The child reads the file with the same reader
and hands the Assembly back, pickled into a private temporary folder. It may allocate at
most `memory_cap()` bytes of data (RLIMIT_DATA: RTTA_READER_MEMORY_MB MiB, when set, else
half of the machine's memory); the parent waits at most `time_limit(path)`
(RTTA_READER_TIMEOUT seconds, when set) and turns a crash, a timeout or the child running
out of memory into one RttaError. Cost: one Python start, about 0.4 s.

RLIMIT_DATA, not RLIMIT_AS: it counts the memory a process writes to (heap, anonymous
mappings) but not the address space libraries reserve without using (glibc's per-thread
malloc arenas, mapped files): on 2 cores the USD reader reserves 1.3 GB of address space and
uses 214 MB of data. Where the libraries report a failed allocation (MemoryError,
std::bad_alloc, OpenBLAS's message) the error says memory; USD's binary reader hides one
behind 'Corrupt asset', and a library that does not check may crash. A cap below what the
libraries need to start (about 300 MB on 2 cores, more with more cores: OpenBLAS keeps
buffers per core) fails every file, some only at the timeout (OpenBLAS retries without end).
"""

from __future__ import annotations

import os
import pickle
import re
import signal
import subprocess
import sys
import tempfile
from pathlib import Path

from ...errors import RttaError

BASE_S = 60.0  # seconds any file gets
PER_MB_S = 30.0  # and per megabyte (OpenCASCADE meshes a 20 MB assembly in about a minute)
ENV = "RTTA_READER_TIMEOUT"
MEMORY_ENV = "RTTA_READER_MEMORY_MB"
MEMORY_SHARE = 0.5  # of the machine's memory (or its cgroup's limit): the rest stays for the process that asked
CGROUP_MAX = Path("/sys/fs/cgroup/memory.max")
# what a failed allocation leaves in a library's error or on the child's stderr
_OUT_OF_MEMORY = re.compile(
    r"MemoryError|bad_alloc|OutOfMemory|out of memory|cannot allocate memory|memory allocation", re.I
)

_CHILD = r"""
import importlib, os, pickle, sys
from pathlib import Path
module, path, out, cap = sys.argv[1:5]
try:  # before the readers' libraries load: what they allocate counts
    import resource
    cap, hard = int(cap), resource.getrlimit(resource.RLIMIT_DATA)[1]
    if cap > 0:
        resource.setrlimit(resource.RLIMIT_DATA, (cap if hard == resource.RLIM_INFINITY else min(cap, hard), hard))
except (ImportError, ValueError, OSError):  # no resource module (Windows), or the limit refused
    pass
from rtta.errors import RttaError
try:
    result = ("ok", importlib.import_module(module).read(Path(path)))
except RttaError as exc:
    result = ("error", exc.message)
except MemoryError:
    result = ("memory", "")
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


def memory_cap() -> int:
    """Bytes of data the reader child may allocate: RTTA_READER_MEMORY_MB MiB (a positive number;
    anything else is ignored), or half of the machine's memory, or of its cgroup's limit when
    that is lower; 0 (no cap) where neither is known."""
    text = os.environ.get(MEMORY_ENV, "").strip()
    try:
        mib = float(text) if text else 0.0
    except ValueError:
        mib = 0.0
    if 0 < mib < 2**40:  # NaN and infinity are not
        return max(int(mib * 2**20), 1)
    return int(MEMORY_SHARE * _machine_memory())


def _machine_memory() -> int:
    """Bytes of physical memory, or the cgroup's (v2) limit where lower; 0 where unknown."""
    try:
        sizes = [os.sysconf("SC_PAGE_SIZE") * os.sysconf("SC_PHYS_PAGES")]
    except (AttributeError, ValueError, OSError):  # no sysconf, or not these names
        sizes = []
    try:
        sizes.append(int(CGROUP_MAX.read_text()))  # 'max' where there is no limit
    except (OSError, ValueError):
        pass
    return min((size for size in sizes if size > 0), default=0)


def read(module: str, path: Path, library: str):
    """What `module`.read(path) gives (module: a dotted name, e.g. rtta.scene.readers.step),
    read in a child process that gets this process's sys.path."""
    limit, cap = time_limit(path), memory_cap()
    env = dict(os.environ, PYTHONPATH=os.pathsep.join(p for p in sys.path if p))
    with tempfile.TemporaryDirectory(prefix="rtta-reader-") as tmp:
        out = Path(tmp) / "assembly.pickle"
        with open(Path(tmp) / "stderr", "w+b") as err:
            proc = subprocess.Popen(
                [sys.executable, "-c", _CHILD, module, str(path), str(out), str(cap)],
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
        if (rc < 0 or not out.exists()) and _OUT_OF_MEMORY.search("\n".join(said)):
            raise _memory_error(library, cap, path)
        if rc < 0:
            raise RttaError(
                f"the {library} reader crashed on this file ({_signal_name(-rc)}); it is probably damaged", path
            )
        if not out.exists():
            last = said[-1][:160] if said else f"exit status {rc}"
            raise RttaError(f"the {library} reader failed ({last})", path)
        with open(out, "rb") as f:
            status, value = pickle.load(f)
    if status == "memory" or (status == "failed" and _OUT_OF_MEMORY.search(value)):
        raise _memory_error(library, cap, path)
    if status == "failed":  # an exception the reader did not expect
        raise RttaError(f"the {library} reader failed ({value})", path)
    if status != "ok":
        raise RttaError(value, path)
    return value


def _memory_error(library: str, cap: int, path: Path) -> RttaError:
    limit = f"its limit of {cap / 2**20:,.0f} MiB" if cap else "the machine's memory"
    return RttaError(
        f"the {library} reader ran out of memory at {limit} (the file may be damaged; {MEMORY_ENV}=MIB allows more)",
        path,
    )


def _signal_name(number: int) -> str:
    try:
        return signal.Signals(number).name
    except ValueError:
        return f"signal {number}"
