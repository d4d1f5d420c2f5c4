"""The heap's two settings (rtta.tools.memory): while a scene loads, blocks of 256 KB and
more are mappings of their own; between loads (frames) blocks under 4 MB come from the heap,
so per-frame arrays do not fault in fresh pages every frame."""

from __future__ import annotations

import numpy as np

from rtta.tools.memory import loading_heap, mapped_block_bytes, steady_heap

MB = 1 << 20


def _mapped_growth(nbytes: int) -> int:
    """How much glibc's mapped blocks grow while an array of `nbytes` is alive."""
    before = mapped_block_bytes()
    block = np.ones(nbytes, np.uint8)
    grown = mapped_block_bytes() - before
    del block
    return grown


def test_frames_take_blocks_under_4_mb_from_the_heap():
    assert steady_heap(), "glibc expected on the test machines"
    _mapped_growth(2 * MB)                             # warm: the heap has room for it
    assert _mapped_growth(2 * MB) < MB
    assert _mapped_growth(8 * MB) >= 8 * MB            # textures and the like stay mappings


def _faults() -> int:
    """Minor page faults of 20 rounds of the same 3 MB temporary."""
    import resource

    t0 = resource.getrusage(resource.RUSAGE_SELF).ru_minflt
    for _ in range(20):
        a = np.ones(3 * MB, np.uint8)
        a += 1
        del a
    return resource.getrusage(resource.RUSAGE_SELF).ru_minflt - t0


def test_page_faults_of_repeated_arrays_vanish_between_loads():
    """What the frame setting is for: the same 3 MB temporaries, allocated again and again,
    are not fresh pages each time (at 10^5 objects Algorithm 1 makes dozens per frame); while
    loading they are (each returned when freed, so a load's peak is its live data)."""
    steady_heap()
    every_page = 20 * (3 * MB // 4096)
    _faults()                                          # warm
    with loading_heap():
        loading = _faults()
        with loading_heap():                           # a second load at the same time (viewer thread)
            pass
        still = _faults()                              # the first load has not ended
    framing = _faults()
    assert loading >= 0.9 * every_page and still >= 0.9 * every_page, (loading, still)
    assert framing < loading / 10, (framing, loading)
