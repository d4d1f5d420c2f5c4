"""Fast navigation (rtta.renderer.navigation): which parts a frame drawn while moving leaves
out, and the budget that sets how many; the viewer's side is in test_viewer.py (20,000 parts)."""

from __future__ import annotations

from types import SimpleNamespace

import numpy as np
import pytest

from rtta.renderer.navigation import AIM, MIN_OBJECTS, FrameBudget, left_out


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
    out = left_out(rec.visible, rec.viewport_rect, tri, keep)
    kept = rec.visible & ~out
    assert not (out & ~rec.visible).any()  # culled or hidden: never "left out"
    assert _area(rec)[out].max() <= _area(rec)[kept].min()  # the smallest go first
    total = tri[rec.visible].sum()
    assert tri[kept].sum() >= keep * total  # no more left out than the share allows
    smallest_kept = np.flatnonzero(kept)[np.argmin(_area(rec)[kept])]
    assert tri[kept].sum() - tri[smallest_kept] <= keep * total  # and no fewer


def test_the_focus_is_never_left_out():
    rec = _records(1000, seed=2)
    tri = np.full(1000, 50)
    focus = np.zeros(1000, bool)
    smallest = np.argsort(np.where(rec.visible, _area(rec), np.inf))[:20]
    focus[smallest] = True
    out = left_out(rec.visible, rec.viewport_rect, tri, 0.1, protect=focus)
    assert out is not None and out.sum() > 500
    assert not (out & focus).any()


def test_nothing_is_left_out_at_full_share_or_in_small_scenes():
    rec = _records(2000)
    tri = np.full(2000, 52)
    assert left_out(rec.visible, rec.viewport_rect, tri, 1.0) is None
    assert left_out(rec.visible, rec.viewport_rect, tri, 0.99) is None
    small = _records(MIN_OBJECTS - 1)
    assert left_out(small.visible, small.viewport_rect, np.full(MIN_OBJECTS - 1, 52), 0.1) is None


def test_the_budget_follows_the_frame_time():
    b = FrameBudget(target_ms=100.0)
    b.update(400.0)
    assert b.keep == pytest.approx(0.6)  # one slow frame: at most 0.6x
    for _ in range(20):
        b.update(1000.0)
    assert b.keep == b.min_keep
    for bad in (float("nan"), float("inf"), 0.0, -5.0):
        b.update(bad)
        assert b.keep == b.min_keep
    for _ in range(20):
        b.update(20.0)  # fast frames: back to every part
    assert b.keep == 1.0
    b.keep = 0.5
    b.update(AIM * 100.0)
    assert b.keep == pytest.approx(0.5)  # on its aim: unchanged
    b.update(100.0)
    assert 0.45 < b.keep < 0.5  # at the target: a little under it, for the scatter


def _boxes(n: int, seed: int = 3) -> np.ndarray:
    """B_world corners [n, 8, 3] of n boxes of mixed sizes scattered in a unit cube."""
    rng = np.random.default_rng(seed)
    lo = rng.random((n, 3)) * 2 - 1
    hi = lo + rng.random((n, 3)) ** 3 * 0.2 + 1e-3
    bits = np.array([[(k >> a) & 1 for a in range(3)] for k in range(8)], bool)
    return np.where(bits[None], hi[:, None], lo[:, None])


def test_frames_in_motion_leave_out_the_share_asked_and_the_same_parts():
    """Ranked on each frame's own projection (parameterize's `thin`), consecutive frames of a
    slowly moving camera draw `keep` of the triangles and leave out the same smallest parts.
    Ranked on the last frame's records, as before, the parts left out had no B_viewport there
    and came back every other frame: 50%, then 75%, 62%, 69% of the triangles drawn."""
    from rtta.atlas.parameterize import parameterize
    from rtta.scene.camera import Camera

    n, keep, vp = 3000, 0.5, (640, 480)
    corners = _boxes(n)
    tri = np.random.default_rng(4).integers(12, 100, n)
    shares, sets = [], []
    for i in range(4):
        cam = Camera.orbit(np.zeros(3), 1.8, 30.0 + 0.2 * i, 20.0, 2.2)
        vpm = cam.projection(vp[0] / vp[1]) @ cam.view(np.zeros(3))
        seen = {}

        def thin(visible, rect, seen=seen):
            seen["visible"] = visible.copy()
            return left_out(visible, rect, tri, keep)

        rec = parameterize(corners, vpm, vp, thin=thin)
        out = seen["visible"] & ~rec.visible
        assert not rec.viewport_rect[out].any() and not rec.transform[out].any()  # culled: no region
        shares.append(tri[rec.visible].sum() / tri[seen["visible"]].sum())
        sets.append(out)
    assert all(keep <= s <= keep + 0.01 for s in shares), shares
    for a, b in zip(sets[:-1], sets[1:], strict=True):
        assert (a & b).sum() >= 0.95 * max(a.sum(), b.sum())  # the same parts, not alternate ones
