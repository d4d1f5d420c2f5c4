"""Packing and parameterization properties (numpy only, hypothesis)."""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from rtta.atlas import scratch
from rtta.atlas.packing import overlaps, pack_shelves
from rtta.atlas.parameterize import parameterize
from rtta.scene.camera import Camera
from rtta.scene.generators.generate import random_scene

sizes = st.integers(1, 64)


@st.composite
def rect_sets(draw):
    W = draw(st.integers(1, 128))
    H = draw(st.integers(1, 128))
    n = draw(st.integers(0, 80))
    w = np.array(draw(st.lists(st.integers(1, W), min_size=n, max_size=n)), np.int64)
    h = np.array(draw(st.lists(st.integers(1, H), min_size=n, max_size=n)), np.int64)
    return w, h, W, H


@given(rect_sets())
@settings(max_examples=300, deadline=None)
def test_shelf_packing_is_valid(case):
    w, h, W, H = case
    p = pack_shelves(w, h, W, H)
    assert len(p.x) == len(w)
    if len(w) == 0:
        assert p.layers == 0
        return
    assert (p.x >= 0).all() and (p.y >= 0).all()
    assert (p.x + w <= p.width).all() and (p.y + h <= p.height).all()
    assert p.width <= W and p.height <= H
    assert set(np.unique(p.layer)) == set(range(p.layers))
    assert not overlaps(p, w, h)


def test_full_size_and_unit_rectangles():
    p = pack_shelves(np.array([100, 1, 1, 100]), np.array([50, 1, 1, 50]), 100, 50)
    assert p.layers == 3 and not overlaps(p, np.array([100, 1, 1, 100]), np.array([50, 1, 1, 50]))


def test_packing_rejects_oversized():
    with pytest.raises(ValueError):
        pack_shelves(np.array([11]), np.array([1]), 10, 10)


@given(
    st.integers(0, 300),
    st.integers(0, 3),
    st.sampled_from([(64, 64), (200, 120), (37, 300)]),
    st.integers(1, 4),
    st.floats(0, 359),
    st.floats(-89, 89),
    st.floats(0.3, 4.0),
)
@settings(max_examples=60, deadline=None)
def test_parameterization_regions(n, border, atlas_max, max_layers, az, el, dist):
    """No overlap, inside the atlas, every visible object present, layers <= cap (scaled if needed)."""
    scene = random_scene(max(n, 1), seed=n)
    vp = (160, 120)
    cam = Camera.orbit(scene.center, scene.radius, az, el, dist)
    vpm = cam.projection(vp[0] / vp[1]) @ cam.view(scene.origin)
    try:
        rec = parameterize(scene.box_corners(), vpm, vp, border=border, atlas_max=atlas_max, max_layers=max_layers)
    except ValueError as exc:  # only when even 1-pixel regions cannot fit
        assert "do not fit" in str(exc)
        assert rec_min_area(scene, vpm, vp, border) > atlas_max[0] * atlas_max[1] * max_layers * 0.5
        return
    for key in ("transform", "clip_ndc", "scale"):
        assert np.isfinite(getattr(rec, key)).all()
    vis = rec.visible
    tw, th, td = rec.atlas_size
    assert td <= max_layers and tw <= atlas_max[0] and th <= atlas_max[1]
    r = rec.atlas_rect[vis]
    assert (r[:, 2] >= 1 + 2 * border).all() and (r[:, 3] >= 1 + 2 * border).all()
    assert (r[:, 0] >= 0).all() and (r[:, 0] + r[:, 2] <= tw).all() and (r[:, 1] + r[:, 3] <= th).all()
    from rtta.atlas.packing import Packing

    p = Packing(r[:, 0], r[:, 1], rec.layer[vis], tw, th, td)
    assert not overlaps(p, r[:, 2], r[:, 3])
    assert ((rec.scale[vis] > 0) & (rec.scale[vis] <= 1)).all()


def rec_min_area(scene, vpm, vp, border):
    from rtta.atlas.parameterize import project_bounds

    vis, _, _ = project_bounds(scene.box_corners(), vpm)
    return vis.sum() * (1 + 2 * border) ** 2


def test_more_objects_than_fit_are_scaled_not_dropped():
    scene = random_scene(200, seed=3, spread=6.0)
    vp = (400, 300)
    cam = Camera.orbit(scene.center, scene.radius, 30, 20, 1.5)
    vpm = cam.projection(vp[0] / vp[1]) @ cam.view(scene.origin)
    free = parameterize(scene.box_corners(), vpm, vp, border=1)
    capped = parameterize(scene.box_corners(), vpm, vp, border=1, atlas_max=(256, 256), max_layers=1)
    assert free.atlas_size[2] > 1 or free.atlas_size[0] > 256
    assert capped.atlas_size[2] == 1
    assert np.array_equal(capped.visible, free.visible)
    assert (capped.scale[capped.visible] < 1).all()


def test_transform_maps_viewport_rect_onto_atlas_rect():
    scene = random_scene(30, seed=1)
    vp = (300, 200)
    cam = Camera.orbit(scene.center, scene.radius, 10, 10, 2.0)
    vpm = cam.projection(1.5) @ cam.view(scene.origin)
    for cap in (None, (128, 128)):
        rec = parameterize(scene.box_corners(), vpm, vp, border=2, atlas_max=cap, max_layers=4)
        tw, th, _ = rec.atlas_size
        for i in np.flatnonzero(rec.visible):
            x0, y0, x1, y1 = rec.viewport_rect[i]
            sx, sy, tx, ty = rec.transform[i]
            ndc = np.array([x0, y0]) / vp * 2 - 1
            atlas_px = ((np.array([sx, sy]) * ndc + [tx, ty]) + 1) / 2 * [tw, th]
            np.testing.assert_allclose(atlas_px, rec.atlas_rect[i, :2] + 2, atol=1e-6)


@given(st.integers(1, 200), st.floats(0, 359), st.floats(-89, 89), st.floats(0.05, 3.0))
@settings(max_examples=60, deadline=None)
def test_viewport_rects_hold_each_objects_projection(n, az, el, dist):
    """Every visible box's B_viewport, from the whole-array projection, holds that box's own
    projected corners (computed one object at a time) and is at most a pixel larger on each
    side; boxes wholly behind the camera or outside the view are culled. The same records
    come from corners stored planar (as Scene keeps them) or object by object."""
    scene = random_scene(n, seed=n)
    vp = (160, 120)
    cam = Camera.orbit(scene.center, scene.radius, az, el, dist)
    vpm = cam.projection(vp[0] / vp[1]) @ cam.view(scene.origin)
    corners = scene.box_corners()
    rec = parameterize(corners, vpm, vp)
    size = np.array(vp, np.float64)
    for i in range(n):
        clip = np.c_[corners[i], np.ones(8)] @ vpm.T
        front = clip[:, 2] + clip[:, 3] >= 0
        if not front.any():
            assert not rec.visible[i]
            continue
        if not front.all():
            continue  # near-plane clipping: test_bounds
        ndc = clip[:, :3] / clip[:, 3:]
        lo, hi = ndc.min(axis=0), ndc.max(axis=0)
        outside = (lo[:2] > 1).any() or (hi[:2] < -1).any() or lo[2] > 1
        if outside:
            assert not rec.visible[i]
            continue
        px_lo = (np.clip(lo[:2], -1, 1) + 1) / 2 * size
        px_hi = (np.clip(hi[:2], -1, 1) + 1) / 2 * size
        if not rec.visible[i]:  # only a zero-area sliver on the border may drop
            assert (np.minimum(px_hi, size) - np.maximum(px_lo, 0) <= 1e-3).any()
            continue
        x0, y0, x1, y1 = rec.viewport_rect[i]
        assert x0 <= px_lo[0] + 1e-6 and y0 <= px_lo[1] + 1e-6, i
        assert x1 >= px_hi[0] - 1e-6 and y1 >= px_hi[1] - 1e-6, i
        assert x0 >= px_lo[0] - 1.01 and y0 >= px_lo[1] - 1.01 and x1 <= max(px_hi[0] + 1.01, x0 + 1), i
        assert y1 <= max(px_hi[1] + 1.01, y0 + 1), i
    objectwise = parameterize(np.ascontiguousarray(corners), vpm, vp)
    for key in ("visible", "viewport_rect", "atlas_rect", "layer", "scale", "transform", "clip_ndc"):
        assert np.array_equal(getattr(rec, key), getattr(objectwise, key)), key


def test_alignment_is_remembered_only_for_read_only_corners():
    """Scene's corners are read-only, so their axis alignment is checked once; a writable
    array is checked on every call, so changing it in place (boxes no longer axis-aligned)
    gives the records of a fresh copy, never those of the remembered answer."""
    scene = random_scene(40, seed=2)
    cam = Camera.orbit(scene.center, scene.radius, 30.0, 20.0, 2.5)
    vpm = cam.projection(4 / 3) @ cam.view(scene.origin)
    corners = scene.box_corners()
    assert not corners.flags.writeable
    with pytest.raises(ValueError):
        corners[0, 0, 0] = 1.0
    writable = np.array(corners)
    first = parameterize(writable, vpm, (320, 240))
    again = parameterize(corners, vpm, (320, 240))
    assert np.array_equal(first.viewport_rect, again.viewport_rect)
    rot = np.array([[0.8, -0.6, 0.0], [0.6, 0.8, 0.0], [0.0, 0.0, 1.0]])
    centre = writable.mean(axis=1, keepdims=True)
    writable[:] = (writable - centre) @ rot.T + centre  # turned boxes: not axis-aligned
    turned = parameterize(writable, vpm, (320, 240))
    fresh = parameterize(np.array(writable), vpm, (320, 240))
    assert np.array_equal(turned.viewport_rect, fresh.viewport_rect)
    assert not np.array_equal(turned.viewport_rect, first.viewport_rect)


@pytest.mark.parametrize("turned", [False, True])
def test_projection_in_chunks_equals_one_pass(monkeypatch, turned):
    """project_bounds works through the boxes CHUNK at a time, reusing its buffers: the bounds
    are the same, bit for bit, as one pass over all boxes, across chunk boundaries and for a
    last short chunk, with boxes behind the camera and crossing the near plane among them."""
    import importlib

    param = importlib.import_module("rtta.atlas.parameterize")  # the module, not the function

    scene = random_scene(700, seed=5)
    cam = Camera.orbit(scene.center, scene.radius, 40.0, 15.0, 0.3)  # inside: crossings
    vpm = cam.projection(4 / 3) @ cam.view(scene.origin)
    corners = np.array(scene.box_corners())
    if turned:
        rot = np.array([[0.8, -0.6, 0.0], [0.6, 0.8, 0.0], [0.0, 0.0, 1.0]])
        centre = corners.mean(axis=1, keepdims=True)
        corners = (corners - centre) @ rot.T + centre
    planar = np.ascontiguousarray(corners.transpose(2, 1, 0)).transpose(2, 1, 0)
    whole = param.project_bounds(planar, vpm)
    front = [((np.c_[c, np.ones(8)] @ vpm.T)[:, 2:].sum(axis=1) >= 0).sum() for c in corners]
    crossing = np.isin(front, range(1, 8))
    assert crossing.any() and whole[0].any() and not whole[0].all()
    monkeypatch.setattr(param, "CHUNK", 64)  # 11 chunks, the last of 60 boxes
    chunked = param.project_bounds(planar, vpm)
    for a, b in zip(whole, chunked, strict=True):
        assert np.array_equal(a, b)


def test_records_are_not_reused_by_the_next_call():
    """Algorithm 1's temporaries are reused from call to call (atlas/scratch.py), its records
    never: those of one frame stay as they were when the next frames are parameterized, with
    the same objects from another camera and viewport, and with other objects."""
    scene, other = random_scene(300, seed=5), random_scene(500, seed=6)
    cam = Camera.orbit(scene.center, scene.radius, 30.0, 20.0, 2.5)
    vpm = cam.projection(4 / 3) @ cam.view(scene.origin)
    keys = ("visible", "viewport_rect", "atlas_rect", "layer", "scale", "transform", "clip_ndc")
    rec = parameterize(scene.box_corners(), vpm, (320, 240))
    kept = {k: np.array(getattr(rec, k)) for k in keys}
    cam2 = Camera.orbit(scene.center, scene.radius, 120.0, -10.0, 1.5)
    again = parameterize(scene.box_corners(), cam2.projection(1.0) @ cam2.view(scene.origin), (200, 200), border=2)
    assert not np.array_equal(again.viewport_rect, kept["viewport_rect"])
    parameterize(scene.box_corners(), vpm, (640, 480))  # all visible: packed in place
    parameterize(other.box_corners(), vpm, (320, 240), hidden=np.arange(500) % 3 == 0)
    for k in keys:
        assert np.array_equal(getattr(rec, k), kept[k]), k


def test_records_memory_is_reused_once_released():
    """The records' arrays come from blocks handed out again once no array of an earlier
    result refers to them (no fresh pages per frame); results that are kept, more of them
    than the pool holds, never share memory."""
    scene = random_scene(300, seed=5)
    cams = [Camera.orbit(scene.center, scene.radius, 30.0 + 20 * i, 20.0, 2.5) for i in range(6)]
    vpms = [c.projection(4 / 3) @ c.view(scene.origin) for c in cams]
    rec = parameterize(scene.box_corners(), vpms[0], (320, 240))
    where = rec.transform.__array_interface__["data"][0]
    del rec
    again = parameterize(scene.box_corners(), vpms[1], (320, 240))
    assert again.transform.__array_interface__["data"][0] == where
    assert any(np.shares_memory(again.transform, block) for block in scratch._pool()["result:records"])
    del again
    kept = [parameterize(scene.box_corners(), m, (320, 240)) for m in vpms]
    for i, a in enumerate(kept):
        fresh = parameterize(scene.box_corners(), vpms[i], (320, 240))
        assert np.array_equal(a.transform, fresh.transform) and np.array_equal(a.atlas_rect, fresh.atlas_rect)
        for b in kept[i + 1 :]:
            assert not np.shares_memory(a.transform, b.transform)


def test_scratch_is_reused_until_released(gl):
    """A scratch array is the same memory from call to call (no fresh mapping per frame)
    until released, as a renderer does when it is released (a scene closed)."""
    from rtta.renderer.renderer import Renderer

    a = scratch.scratch("test.a", (4, 1000))
    assert np.shares_memory(a, scratch.scratch("test.a", (2, 500), np.int64))
    scratch.release()
    assert not np.shares_memory(a, scratch.scratch("test.a", (4, 1000)))
    scene = random_scene(50, seed=3)
    r = Renderer(gl, scene)
    r.parameterize(Camera.orbit(scene.center, scene.radius, 30.0, 20.0, 2.5), (320, 240))
    kept = scratch.scratch("bounds.lo", (3, 50))
    r.release()
    assert not np.shares_memory(kept, scratch.scratch("bounds.lo", (3, 50)))


def test_packed_records_match_the_std430_layout_field_by_field():
    """Records.packed (planar rows, one transposing copy; into scratch with reuse) holds every
    field where shaders/records.glsl reads it, culled objects and per-object scales included."""
    from rtta.atlas.records import RECORD_DTYPE

    scene = random_scene(400, seed=9)
    cam = Camera.orbit(scene.center, scene.radius, 30.0, 20.0, 1.2)
    rec = parameterize(
        scene.box_corners(),
        cam.projection(4 / 3) @ cam.view(scene.origin),
        (320, 240),
        region_scale=np.linspace(0.3, 1.0, 400),
    )
    assert not rec.visible.all()
    ref = np.zeros(400, RECORD_DTYPE)
    ref["transform"], ref["clip"], ref["atlas"], ref["viewport"] = (
        rec.transform,
        rec.clip_ndc,
        rec.atlas_rect,
        rec.viewport_rect,
    )
    ref["info"][:, 0], ref["info"][:, 1], ref["info"][:, 2] = rec.layer, rec.visible, rec.border
    ref["info"][:, 3] = rec.scale.astype(np.float32).view(np.int32)
    for reuse in (False, True):
        packed = rec.packed(reuse)
        assert packed.dtype == RECORD_DTYPE and packed.shape == (400,)
        assert packed.tobytes() == ref.tobytes()
