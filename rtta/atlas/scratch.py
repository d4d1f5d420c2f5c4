"""Arrays reused from one parameterization to the next, for Algorithm 1's temporaries.

At 10^5 objects every [n] array of Algorithm 1 is 0.8 MB. Allocated afresh each frame, each
is a new mapping of the process (the CLI fixes glibc's mmap threshold at 256 KB,
rtta.memory): measured in a long viewer-like process, 12,300 page faults and half of a
40 ms call. Temporaries taken from here are touched once and then stay (27 MB in all at
10^5 objects). What a call returns (the records) callers keep: `result_block` hands out a
block of memory again only once no array of an earlier result refers to it.
"""

from __future__ import annotations

import math
import sys
import threading

import numpy as np
import numpy.typing as npt

_LOCAL = threading.local()  # one pool per thread: a call never shares its temporaries
RESULT_BLOCKS = 3  # result blocks kept per name: a caller's last result, the new one, a spare


def _pool() -> dict:
    pool = getattr(_LOCAL, "pool", None)
    if pool is None:
        pool = _LOCAL.pool = {}
    return pool


def scratch(name: str, shape: tuple[int, ...] | int, dtype: npt.DTypeLike = np.float64) -> np.ndarray:
    """An uninitialised array of `shape` that is this thread's `name` until the next request
    for `name` (its contents are overwritten then: never return one from a public call).
    The pool keeps the largest size asked for per name."""
    pool = _pool()
    dtype = np.dtype(dtype)
    count = int(math.prod(shape)) if isinstance(shape, tuple) else int(shape)  # (np.prod: 5 µs a call)
    nbytes = count * dtype.itemsize
    buf = pool.get(name)
    if buf is None or buf.nbytes < nbytes:
        buf = pool[name] = np.empty(max(nbytes, 1), np.uint8)
    return buf[:nbytes].view(dtype).reshape(shape)


def result_block(name: str, nbytes: int) -> np.ndarray:
    """uint8 [nbytes] for arrays that a call returns (views of it: numpy keeps the block as
    their base). A block of this thread's that no view refers to any more, so its pages are
    mapped already (at 10^5 objects the records are 14 MB: 3,500 page faults a frame when
    fresh), else a new one, kept for later calls while fewer than RESULT_BLOCKS are."""
    blocks: list[np.ndarray] = _pool().setdefault("result:" + name, [])
    # a free block has two references, the list's and getrefcount's argument (no loop names)
    free = [i for i in range(len(blocks)) if sys.getrefcount(blocks[i]) <= 2]
    for i in free:
        if blocks[i].nbytes >= nbytes:
            return blocks[i][:nbytes]
    block = np.empty(max(nbytes, 1), np.uint8)
    if len(blocks) < RESULT_BLOCKS:
        blocks.append(block)
    elif free:  # in place of one no result uses (from a scene of another size)
        blocks[free[0]] = block
    return block[:nbytes]


def release() -> None:
    """Drop this thread's pool (e.g. after a very large scene is closed)."""
    _LOCAL.pool = {}
