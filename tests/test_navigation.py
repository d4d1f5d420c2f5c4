"""Fast navigation (rtta.renderer.navigation): which parts a frame drawn while moving leaves
out, and the budget that sets how many; the viewer's side is in test_viewer.py (20,000 parts)."""

from __future__ import annotations

from types import SimpleNamespace

import numpy as np
import pytest

from rtta.renderer.navigation import MIN_OBJECTS, FrameBudget, left_out


def _records(n: int, seed: int = 0):
    rng = np.random.default_rng(seed)
    lo = rng.integers(0, 500, (n, 2))
    size = rng.integers(1, 60, (n, 2))
    visible = rng.random(n) > 0.1
    return SimpleNamespace(visible=visible, viewport_rect=np.hstack([lo, lo + size]).astype(np.int32))


def _area(rec) -> np.ndarray:
    r = rec.viewport_rect
    return ((r[:, 2] - r[:, 0]) * (r[:, 3] - r[:, 1])).astype(float)


@pytest.mark.parametrize("keep", [0.9, 0.5, 0.2])
def test_the_smallest_parts_are_left_out_down_to_the_share(keep):
    rec = _records(2000)
    tri = np.random.default_rng(1).integers(12, 400, 2000)
    out = left_out(rec, tri, keep)
    kept = rec.visible & ~out
    assert not (out & ~rec.visible).any()                 # culled or hidden: never "left out"
    assert _area(rec)[out].max() <= _area(rec)[kept].min()     # the smallest go first
    total = tri[rec.visible].sum()
    assert tri[kept].sum() >= keep * total                # no more left out than the share allows
    smallest_kept = np.flatnonzero(kept)[np.argmin(_area(rec)[kept])]
    assert tri[kept].sum() - tri[smallest_kept] <= keep * total    # and no fewer


def test_the_focus_is_never_left_out():
    rec = _records(1000, seed=2)
    tri = np.full(1000, 50)
    focus = np.zeros(1000, bool)
    smallest = np.argsort(np.where(rec.visible, _area(rec), np.inf))[:20]
    focus[smallest] = True
    out = left_out(rec, tri, 0.1, protect=focus)
    assert out is not None and out.sum() > 500
    assert not (out & focus).any()


def test_nothing_is_left_out_at_full_share_or_in_small_scenes():
    rec = _records(2000)
    tri = np.full(2000, 52)
    assert left_out(rec, tri, 1.0) is None and left_out(rec, tri, 0.99) is None
    small = _records(MIN_OBJECTS - 1)
    assert left_out(small, np.full(MIN_OBJECTS - 1, 52), 0.1) is None


def test_the_budget_follows_the_frame_time():
    b = FrameBudget(target_ms=100.0)
    b.update(400.0)
    assert b.keep == pytest.approx(0.6)                   # one slow frame: at most 0.6x
    for _ in range(20):
        b.update(1000.0)
    assert b.keep == b.min_keep
    for bad in (float("nan"), float("inf"), 0.0, -5.0):
        b.update(bad)
        assert b.keep == b.min_keep
    for _ in range(20):
        b.update(20.0)                                    # fast frames: back to every part
    assert b.keep == 1.0
    b.keep = 0.5
    b.update(100.0)
    assert b.keep == pytest.approx(0.5)                   # on target: unchanged
