"""Arrays reused from one parameterization to the next, for Algorithm 1's temporaries.

At 10^5 objects every [n] array of Algorithm 1 is 0.8 MB. Allocated afresh each frame, each
is a new mapping of the process (the CLI fixes glibc's mmap threshold at 256 KB,
tools.memory): measured in a long viewer-like process, 12,300 page faults and half of a
40 ms call. Temporaries taken from here are touched once and then stay (27 MB in all at
10^5 objects); what a call returns (the records) is always allocated afresh, since callers
keep it.
"""

from __future__ import annotations

import threading

import numpy as np

_LOCAL = threading.local()      # one pool per thread: a call never shares its temporaries


def scratch(name: str, shape: tuple[int, ...] | int, dtype=np.float64) -> np.ndarray:
    """An uninitialised array of `shape` that is this thread's `name` until the next request
    for `name` (its contents are overwritten then: never return one from a public call).
    The pool keeps the largest size asked for per name."""
    pool: dict[str, np.ndarray] | None = getattr(_LOCAL, "pool", None)
    if pool is None:
        pool = _LOCAL.pool = {}
    dtype = np.dtype(dtype)
    count = int(np.prod(shape, dtype=np.int64))
    nbytes = count * dtype.itemsize
    buf = pool.get(name)
    if buf is None or buf.nbytes < nbytes:
        buf = pool[name] = np.empty(max(nbytes, 1), np.uint8)
    return buf[:nbytes].view(dtype).reshape(shape)


def release() -> None:
    """Drop this thread's pool (e.g. after a very large scene is closed)."""
    _LOCAL.pool = {}
