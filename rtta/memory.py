"""Process memory: RSS, and a steadier heap for long sessions.

Atlas and composite textures are freed and reallocated at changing sizes as views and
windows change. With glibc's default *dynamic* mmap threshold, freeing one large block
raises the threshold, so the next blocks of that size come from the heap, which then
fragments and grows for hours (measured: +40% RSS over 20,000 soak frames). A fixed
threshold keeps large blocks in mmap, returned to the system when freed; capping the number
of arenas keeps the driver's worker threads from each holding freed memory of their own.
"""

from __future__ import annotations

import ctypes
import ctypes.util
import os
from functools import cache

M_MMAP_THRESHOLD = -3
M_ARENA_MAX = -8
MMAP_THRESHOLD_BYTES = 256 * 1024
ARENAS = 2  # the driver's worker threads would each grow an arena of their own


@cache
def _libc() -> ctypes.CDLL | None:
    try:
        return ctypes.CDLL(ctypes.util.find_library("c") or "libc.so.6")
    except OSError:
        return None


def steady_heap() -> bool:
    """Fix glibc's mmap threshold (process-wide; the CLI and viewer call it at start).
    Returns False where the C library is not glibc (nothing is changed there)."""
    mallopt = getattr(_libc(), "mallopt", None)
    return bool(mallopt and mallopt(M_MMAP_THRESHOLD, MMAP_THRESHOLD_BYTES) and mallopt(M_ARENA_MAX, ARENAS))


def rss_bytes() -> int:
    """Resident set size of this process (Linux /proc)."""
    with open("/proc/self/statm") as f:
        pages = int(f.read().split()[1])
    return pages * os.sysconf("SC_PAGE_SIZE")


class _MallInfo2(ctypes.Structure):
    _fields_ = [
        (name, ctypes.c_size_t)
        for name in (
            "arena",
            "ordblks",
            "smblks",
            "hblks",
            "hblkhd",
            "usmblks",
            "fsmblks",
            "uordblks",
            "fordblks",
            "keepcost",
        )
    ]


def mapped_block_bytes() -> int | None:
    """Bytes in live blocks that glibc's malloc gave their own mmap (at least
    MMAP_THRESHOLD_BYTES once steady_heap() ran): on llvmpipe, texture storage. None where
    the C library is not glibc >= 2.33."""
    fn = getattr(_libc(), "mallinfo2", None)
    if fn is None:
        return None
    fn.restype = _MallInfo2
    return int(fn().hblkhd)
