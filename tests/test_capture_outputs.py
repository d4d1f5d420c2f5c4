"""A capture for a mode that reads no normals leaves the normal image alone (a colour mask):
the same colour, depth and ids, the same images in those modes; a mode that reads normals
afterwards (ghosted-ao, the projector) captures again instead of shading with stale ones.
A capture without the id image gives the same images and the same picks (picking reads
depths alone)."""

from __future__ import annotations

import numpy as np
import pytest

from rtta.passes.composite import Style
from rtta.passes.picking import objects_at
from rtta.renderer.snapshot import render_modes
from rtta.scene.camera import DEFAULT_ORBIT, Camera

VP = (240, 180)
FOCUS = {1, 5}


def _cams(scene):
    return (
        Camera.orbit(scene.center, scene.radius, *DEFAULT_ORBIT),
        Camera.orbit(scene.center, scene.radius, 140.0, -25.0, 1.8),
    )


def _atlas(r, normals: bool):
    tw, th, td = r.last[0].atlas_size
    return r.atlas.read((tw, th), td, parts=("color", "id", "depth", "normal") if normals else None)


def test_capture_without_normals_gives_the_same_images(make_renderer, demo_scene):
    r = make_renderer(demo_scene)
    _, cam = _cams(demo_scene)
    r.capture(cam, VP, focus=FOCUS)
    full = _atlas(r, True)
    images = {m: r.composite(m, Style(focus=FOCUS)).read()[0].copy() for m in ("sprites", "transparent", "ghosted")}
    r.capture(cam, VP, focus=FOCUS, normals=False)
    assert not r.captured_normals and not r.needs_normals("ghosted")
    lean = _atlas(r, False)
    assert set(lean) == {"color", "id", "depth"}
    for key in lean:
        assert np.array_equal(lean[key], full[key]), key
    with pytest.raises(ValueError, match="no normal image"):
        r.atlas.read(parts=("normal",))
    frames = r.capture_pass().frames
    for mode, want in images.items():
        assert np.array_equal(r.composite(mode, Style(focus=FOCUS)).read()[0], want), mode
    assert r.capture_pass().frames == frames  # none of them captured again


def test_a_mode_that_reads_normals_captures_them(make_renderer, demo_scene):
    """The first camera's normals stay in the image under a capture without normals from the
    second camera, so shading them would be wrong: ghosted-ao captures again and equals a
    renderer that captured with normals from the start."""
    r, fresh = make_renderer(demo_scene), make_renderer(demo_scene)
    first, second = _cams(demo_scene)
    r.capture(first, VP, focus=FOCUS)
    r.capture(second, VP, focus=FOCUS, normals=False)
    fresh.capture(second, VP, focus=FOCUS)
    tw, th, td = r.last[0].atlas_size
    assert td >= 1
    stale = r.atlas.normal.read()  # what the guard in read() keeps callers from
    frames = r.capture_pass().frames
    got = r.composite("ghosted-ao", Style(focus=FOCUS)).read()[0]
    want = fresh.composite("ghosted-ao", Style(focus=FOCUS)).read()[0]
    assert r.capture_pass().frames == frames + 1 and r.captured_normals
    assert np.array_equal(got, want)
    assert np.array_equal(_atlas(r, True)["normal"], _atlas(fresh, True)["normal"])
    assert r.atlas.normal.read() != stale, "the second camera's normals equal the first's: the test proves nothing"


def test_snapshots_write_normals_only_for_the_modes_that_read_them(make_renderer, demo_scene):
    r = make_renderer(demo_scene)
    cam, _ = _cams(demo_scene)
    style = Style(focus=FOCUS)
    render_modes(r, cam, VP, ("std", "ghosted", "transparent"), style)
    assert not r.captured_normals
    render_modes(r, cam, VP, ("ghosted", "ghosted-ao"), style)
    assert r.captured_normals


def test_capture_without_ids_gives_the_same_images_and_picks(make_renderer, demo_scene):
    """Hits by the id image (the object's own id at its mapped texel) from a full capture
    equal the depth-only hits of a capture that wrote no ids, on 400 pixels, occluded
    objects included; the composites are equal; reading ids from it raises."""
    r = make_renderer(demo_scene)
    cam, _ = _cams(demo_scene)
    rec = r.capture(cam, VP, focus=FOCUS)
    full = _atlas(r, True)
    images = {m: r.composite(m, Style(focus=FOCUS)).read()[0].copy() for m in ("sprites", "ghosted", "ghosted-ao")}
    rng = np.random.default_rng(11)
    pixels = list(zip(rng.integers(0, VP[0], 400).tolist(), rng.integers(0, VP[1], 400).tolist(), strict=True))
    by_id = []
    for x, y in pixels:
        hits = []
        for oid, depth in objects_at(full, rec, x, y):
            t = r.atlas.texels(np.array([[*_texel(rec, oid, x, y)]]))
            assert t["id"][0] == oid  # the depth rule agrees with the id image
            hits.append((oid, depth))
        by_id.append(hits)
    r.capture(cam, VP, focus=FOCUS, ids=False)
    assert set(_atlas(r, False)) == {"color", "normal", "depth"}
    for key in ("color", "normal", "depth"):
        assert np.array_equal(_atlas(r, False)[key], full[key]), key
    with pytest.raises(ValueError, match="no id image"):
        r.atlas.read(parts=("id",))
    with pytest.raises(ValueError, match="no id image"):
        r.atlas.texels(np.zeros((1, 3), np.int64))
    assert [objects_at(r.atlas, rec, x, y) for x, y in pixels] == by_id
    assert sum(len(h) > 1 for h in by_id) > 20 and sum(len(h) == 0 for h in by_id) > 20
    for mode, want in images.items():
        assert np.array_equal(r.composite(mode, Style(focus=FOCUS)).read()[0], want), mode


def _texel(rec, oid, x, y):
    from rtta.gl.readback import to_atlas

    return (*(int(v) for v in to_atlas(rec, oid, x, y)), int(rec.layer[oid]))
