"""The part tree: the panel's model (rows, open groups, filter, counts), hiding (hidden
objects get no atlas region and are not drawn), framing at any aspect, and the up axis."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from rtta.scene.camera import Camera
from rtta.scene.model import from_meshes
from viewer.orbit import Orbit
from viewer.parts import PartTree
from viewer.state import ViewerState

SHARED = Path(__file__).resolve().parents[2] / "shared" / "data"
PATHS = [("E",), ("E", "crank"), ("E", "head"), ("E", "head"), ()]
NAMES = ["block", "shaft", "valve", "valve_2", "loose"]


def _box(lo, hi):
    lo, hi = np.asarray(lo, float), np.asarray(hi, float)
    corners = np.array([[(hi if (i >> k) & 1 else lo)[k] for k in range(3)] for i in range(8)])
    faces = np.array(
        [
            [0, 2, 1],
            [1, 2, 3],
            [4, 5, 6],
            [5, 7, 6],
            [0, 1, 4],
            [1, 5, 4],
            [2, 6, 3],
            [3, 6, 7],
            [0, 4, 2],
            [2, 4, 6],
            [1, 3, 5],
            [3, 7, 5],
        ]
    )
    return corners, faces


def _scene(paths=True):
    boxes = [
        ((0, 0, 0), (4, 1, 1)),
        ((0, 2, 0), (1, 3, 1)),
        ((2, 2, 0), (3, 3, 1)),
        ((3.5, 2, 0), (4, 3, 1)),
        ((1.5, -2, 0), (2.5, -1, 1)),
    ]
    parts = [(n, *_box(lo, hi), None) for n, (lo, hi) in zip(NAMES, boxes, strict=True)]
    s = from_meshes(parts)
    if paths:
        s.paths = PATHS
    return s


def test_rows_open_close_filter_and_counts():
    t = PartTree(NAMES, PATHS)
    labels = [t.labels[n] for n in t.rows()]
    assert labels == ["loose", "E", "block", "crank", "shaft", "head", "valve", "valve_2"]
    head = t.labels.index("head")
    assert list(t.members(head)) == [2, 3] and list(t.members(t.labels.index("E"))) == [0, 1, 2, 3]
    t.open.discard(head)
    assert [t.labels[n] for n in t.rows()] == ["loose", "E", "block", "crank", "shaft", "head"]
    assert [t.labels[n] for n in t.rows("valve_")] == ["E", "head", "valve_2"]  # opened for the match
    counts = t.counts({2})
    assert counts[head] == 1 and counts[t.labels.index("E")] == 1 and counts[t.labels.index("crank")] == 0
    t.open.clear()
    node = t.reveal(3)
    assert t.labels[node] == "valve_2" and node in t.rows()


def test_state_group_toggle_hide_isolate():
    s = ViewerState(NAMES, paths=PATHS)
    head = s.tree.labels.index("head")
    s.toggle(2)
    s.toggle_group(s.tree.members(head))  # mixed -> all
    assert s.highlighted == {2, 3}
    s.toggle_group(s.tree.members(head))  # all -> none
    assert s.highlighted == set()
    rev = s.capture_key()
    s.hide([1])
    assert s.hidden == {1} and s.capture_key() != rev
    s.isolate(s.tree.members(head))
    assert s.hidden == {0, 1, 4}
    s.show_all()
    assert s.hidden == set()


def test_hidden_objects_have_no_region_and_are_not_drawn(make_renderer):
    scene = _scene()
    r = make_renderer(scene)
    cam = Camera.orbit(scene.center, scene.radius, 0, 10, 2.5)
    vp = (160, 120)
    full = r.std(cam, vp).read(vp, 1)["id"][0].copy()
    assert 1 in full
    r.hidden = {1, 4}
    rec = r.capture(cam, vp)
    assert not rec.visible[[1, 4]].any() and rec.visible[[0, 2, 3]].all()
    assert (rec.atlas_rect[[1, 4]] == 0).all()
    ids = r.std(cam, vp).read(vp, 1)["id"][0]
    assert not np.isin(ids, [1, 4]).any()
    keep = ~np.isin(full, [1, 4])  # elsewhere the picture is what it was
    assert (ids[keep] == full[keep]).all()
    atlas_ids = r.atlas.read(rec.atlas_size[:2], rec.atlas_size[2], parts=("id",))["id"]
    assert not np.isin(atlas_ids, [1, 4]).any()


def _margins(mask: np.ndarray) -> tuple[float, float, float, float]:
    """Free fraction of the width/height on the left, right, bottom and top of a mask."""
    h, w = mask.shape
    ys, xs = np.nonzero(mask)
    return xs.min() / w, (w - 1 - xs.max()) / w, ys.min() / h, (h - 1 - ys.max()) / h


def _framed(make_renderer, scene, hidden=()):
    r = make_renderer(scene)
    r.hidden = set(hidden)
    shown = [i for i in range(scene.count) if i not in r.hidden]
    out = {}
    for aspect in (0.5, 1.0, 2.0):
        vp = (int(200 * aspect), 200)
        o = Orbit.default(scene.center, scene.radius, up_axis=scene.up_axis)
        o.frame(corners=scene.box_corners("aabb")[shown].reshape(-1, 3) + scene.origin, aspect=aspect)
        ids = r.std(o.camera(), vp).read(vp, 1)["id"][0]
        out[aspect] = _margins(ids >= 0)
    return out


def test_framing_leaves_a_margin_at_every_aspect(make_renderer):
    scene = _scene()
    for hidden in ((), (4,)):
        for aspect, m in _framed(make_renderer, scene, hidden).items():
            assert min(m) >= 0.02, (hidden, aspect, m)  # no object pixel within 2% of an edge
            assert min(m[0] + m[1], m[2] + m[3]) < 0.5, (hidden, aspect, m)  # and it fills the view


@pytest.mark.skipif(not (SHARED / "engine_2cyl.glb").exists(), reason="../shared/data/engine_2cyl.glb not present")
def test_framing_the_engine(make_renderer):
    from rtta.scene.loader import load_scene

    for aspect, m in _framed(make_renderer, load_scene(SHARED / "engine_2cyl.glb")).items():
        assert min(m) >= 0.02 and min(m[0] + m[1], m[2] + m[3]) < 0.5, (aspect, m)


def test_z_up_orbit_stands_upright():
    cam = Camera.orbit(np.zeros(3), 1.0, 0.0, 30.0, 2.0, up_axis="z")
    assert cam.eye[2] > 0 and cam.eye[1] < 0 and abs(cam.eye[0]) < 1e-9  # above, from the front (-Y)
    assert cam.up[2] > 0.8
    o = Orbit.default(np.zeros(3), 1.0, up_axis="z")
    o.rotate(0, 100)  # elevation 25 -> 55 degrees, about +Z
    assert o.camera().eye[2] == pytest.approx(2.2 * np.sin(np.radians(55))) and o.camera().eye[1] < 0
    eye = o.camera().eye.copy()
    o.orbit_around([0.3, 0.1, 0.2])
    assert np.allclose(o.camera().eye, eye)
