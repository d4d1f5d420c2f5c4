"""Process memory: RSS, and a steadier heap for long sessions.

Atlas and composite textures are freed and reallocated at changing sizes as views and
windows change. With glibc's default *dynamic* mmap threshold, freeing one large block
raises the threshold, so the next blocks of that size come from the heap, which then
fragments and grows for hours (measured: +40% RSS over 20,000 soak frames). A fixed
threshold keeps large blocks in mmap, returned to the system when freed; capping the number
of arenas keeps the driver's worker threads from each holding freed memory of their own.

Two settings, by phase. While a scene loads (`loading_heap`), blocks of 256 KB and more are
mappings of their own, returned when freed: the load's many large temporaries never pile up
in the heap, so its peak RSS stays near its live data (1.20x trimesh.load's at 10k parts,
against 1.35x with 4 MB). Between loads, while frames are drawn, the threshold is 4 MB and
the heap keeps up to 64 MB free at its top: the per-frame arrays of Algorithm 1 at 10^5
objects (0.8-3.2 MB each) are then reused heap instead of fresh mappings, which cost 12,500
page faults and about 30 ms per frame there (rtta bench scale: param+pack 57 -> 25 ms).
Textures (4 MB and more at any size worth the name) stay mappings.
"""

from __future__ import annotations

import ctypes
import ctypes.util
import os
import threading
from collections.abc import Iterator
from contextlib import contextmanager
from functools import cache

M_TRIM_THRESHOLD = -1
M_MMAP_THRESHOLD = -3
M_ARENA_MAX = -8
MMAP_THRESHOLD_BYTES = 256 * 1024       # while loading
TRIM_THRESHOLD_BYTES = 128 * 1024       # glibc's default
FRAME_MMAP_THRESHOLD_BYTES = 4 << 20    # between loads
FRAME_TRIM_THRESHOLD_BYTES = 64 << 20
ARENAS = 2              # the driver's worker threads would each grow an arena of their own

_phase = {"steady": False, "loads": 0}
_phase_lock = threading.Lock()


@cache
def _libc() -> ctypes.CDLL | None:
    try:
        return ctypes.CDLL(ctypes.util.find_library("c") or "libc.so.6")
    except OSError:
        return None


def steady_heap() -> bool:
    """Fix glibc's mmap threshold, at the frame setting (process-wide; the CLI and viewer call
    it at start, and load scenes inside `loading_heap`). Returns False where the C library is
    not glibc (nothing is changed there)."""
    mallopt = getattr(_libc(), "mallopt", None)
    if not (mallopt and mallopt(M_ARENA_MAX, ARENAS) and _set(FRAME_MMAP_THRESHOLD_BYTES, FRAME_TRIM_THRESHOLD_BYTES)):
        return False
    _phase["steady"] = True
    return True


@contextmanager
def loading_heap() -> Iterator[None]:
    """The load setting for the block (a scene being read), the frame setting after the last
    of concurrent loads ends (the viewer loads in a thread while it draws). Nothing changes
    unless steady_heap() ran: a library user's process keeps its own allocator settings."""
    with _phase_lock:
        steady = _phase["steady"]
        if steady:
            _phase["loads"] += 1
            if _phase["loads"] == 1:
                _set(MMAP_THRESHOLD_BYTES, TRIM_THRESHOLD_BYTES)
                trim = getattr(_libc(), "malloc_trim", None)
                if trim:
                    trim(0)               # the frames' free heap goes back: the load starts lean
    try:
        yield
    finally:
        if steady:
            with _phase_lock:
                _phase["loads"] -= 1
                if _phase["loads"] == 0:
                    _set(FRAME_MMAP_THRESHOLD_BYTES, FRAME_TRIM_THRESHOLD_BYTES)


def _set(mmap_threshold: int, trim_threshold: int) -> bool:
    mallopt = getattr(_libc(), "mallopt", None)
    return bool(mallopt and mallopt(M_MMAP_THRESHOLD, mmap_threshold) and mallopt(M_TRIM_THRESHOLD, trim_threshold))


def rss_bytes() -> int:
    """Resident set size of this process (Linux /proc)."""
    with open("/proc/self/statm") as f:
        pages = int(f.read().split()[1])
    return pages * os.sysconf("SC_PAGE_SIZE")


class _MallInfo2(ctypes.Structure):
    _fields_ = [(name, ctypes.c_size_t) for name in
                ("arena", "ordblks", "smblks", "hblks", "hblkhd", "usmblks", "fsmblks", "uordblks",
                 "fordblks", "keepcost")]


def mapped_block_bytes() -> int | None:
    """Bytes in live blocks that glibc's malloc gave their own mmap (at least
    the mmap threshold in force once steady_heap() ran): on llvmpipe, texture storage. None where
    the C library is not glibc >= 2.33."""
    fn = getattr(_libc(), "mallinfo2", None)
    if fn is None:
        return None
    fn.restype = _MallInfo2
    return int(fn().hblkhd)
