"""Back faces culled only where they can never be seen (rtta.scene.closure): which objects
are closed surfaces facing outward, which lie wholly beyond the near plane, and STD and the
atlas drawn so against the same scene drawn double-sided."""

from __future__ import annotations

import numpy as np
import pytest
import trimesh

from rtta.scene.camera import Camera
from rtta.scene.closure import beyond_near, closed_objects
from rtta.scene.model import Scene, from_meshes


def _box(offset=(0.0, 0.0, 0.0)) -> tuple[np.ndarray, np.ndarray]:
    b = trimesh.creation.box()
    return b.vertices + offset, b.faces.copy()


def _split(v, f):
    """Every triangle with vertices of its own (as a file with flat normals has them)."""
    return v[f].reshape(-1, 3), np.arange(3 * len(f)).reshape(-1, 3)


def _flipped_first(v, f):
    f = f.copy()
    f[0] = f[0][::-1]
    return v, f


CASES = {
    "box": (_box(), True),
    "box, split vertices": (_split(*_box()), True),
    "icosphere": ((trimesh.creation.icosphere(2).vertices, trimesh.creation.icosphere(2).faces), True),
    "cylinder": (
        (trimesh.creation.cylinder(0.5, 2, sections=12).vertices, trimesh.creation.cylinder(0.5, 2, sections=12).faces),
        True,
    ),
    "two boxes in one object": ((np.r_[_box()[0], _box((3, 0, 0))[0]], np.r_[_box()[1], _box()[1] + 8]), True),
    "box and a degenerate triangle": ((_box()[0], np.r_[_box()[1], [[0, 0, 1]]]), True),
    "inside-out box": ((_box()[0], _box()[1][:, ::-1]), False),
    "box without a face": ((_box()[0], _box()[1][:-2]), False),
    "box with one face turned": (_flipped_first(*_box()), False),
    "box and a loose triangle": (
        (np.r_[_box()[0], [[5, 0, 0], [6, 0, 0], [5, 1, 0]]], np.r_[_box()[1], [[8, 9, 10]]]),
        False,
    ),
    "square sheet": (
        (np.array([[0, 0, 0], [1, 0, 0], [1, 1, 0], [0, 1, 0]], float), np.array([[0, 1, 2], [0, 2, 3]])),
        False,
    ),
}


@pytest.mark.parametrize("name", list(CASES))
def test_closed_surfaces_are_told_from_open_ones(name):
    (v, f), closed = CASES[name]
    scene = from_meshes([("a", v, f, None), ("reference box", *_box((9, 0, 0)), None)])
    assert scene.closed.tolist() == [closed, True]


def test_objects_out_of_order_in_the_index_buffer():
    """index_ranges need not follow object order: each object is judged on its own triangles."""
    box_v, box_f = _box()
    sheet_v = np.array([[0, 0, 5], [1, 0, 5], [0, 1, 5]], np.float32)
    positions = np.r_[box_v, sheet_v].astype(np.float32)
    indices = np.r_[[8, 9, 10], box_f.reshape(-1)].astype(np.uint32)  # the sheet's triangle first
    ranges = np.array([[3, 36], [0, 3]])  # object 0: the box, 1: the sheet
    centers = np.array([[0, 0, 0], [0.3, 0.3, 5]], float)
    assert closed_objects(positions, indices, ranges, centers).tolist() == [True, False]


def test_beyond_near():
    cam = Camera.orbit(np.zeros(3), 1.0, 0.0, 0.0, 10.0)  # on +z, looking at the origin
    view, proj = cam.view(np.zeros(3)), cam.projection(1.0)
    near = proj[2, 3] / (proj[2, 2] - 1.0)
    eye = np.linalg.inv(view)[:3, 3]
    lo = np.array([[-1, -1, -1], eye - 0.1, eye - [1, 1, near + 0.5], eye - [1, 1, near / 2]], float)
    hi = np.array([[1, 1, 1], eye + 0.1, eye + [1, 1, -near - 0.1], eye + [1, 1, -near / 4]], float)
    assert beyond_near(lo, hi, view, proj).tolist() == [True, False, True, False]


def _double_sided(monkeypatch):
    monkeypatch.setattr(Scene, "closed", property(lambda self: np.zeros(self.count, bool)))


def _pictures(make_renderer, scene, cam, size, monkeypatch, culled: bool):
    with monkeypatch.context() as m:
        if not culled:
            _double_sided(m)
        r = make_renderer(scene)
        std = r.std(cam, size).read(size, 1)["color"][0].astype(int)
        records = r.capture(cam, size)
        tw, th, td = records.atlas_size
        atlas = r.atlas.read((tw, th), td)
        return std, atlas["color"].astype(int), atlas["depth"]


@pytest.mark.parametrize("orbit", [(30, 20, 2.2), (200, -30, 1.4), (30, 20, 0.25), (90, 5, 0.1)])
def test_culling_leaves_std_and_the_atlas_as_double_sided(make_renderer, demo_scene, monkeypatch, orbit):
    """At 0.25 and 0.1 radii the near plane cuts parts of the demo: those stay double-sided,
    so their insides show through the cut as before."""
    cam = Camera.orbit(demo_scene.center, demo_scene.radius, *orbit)
    size = (200, 150)
    culled = _pictures(make_renderer, demo_scene, cam, size, monkeypatch, True)
    both = _pictures(make_renderer, demo_scene, cam, size, monkeypatch, False)
    for got, want, tolerance in zip(culled, both, (3, 3, 1e-6), strict=True):  # std, atlas colour, depth
        assert got.shape == want.shape
        assert (np.abs(got - want) > tolerance).mean() < 1e-4


def test_near_cut_objects_show_their_insides(make_renderer, monkeypatch):
    """With the camera inside a closed box (the room), the box is cut by the near plane and
    drawn double-sided: its inside walls fill the view as without culling. Culling every
    closed object regardless of the near plane would take the room out of the picture."""
    room = trimesh.creation.box(extents=(10, 10, 10))
    scene = from_meshes([("room", room.vertices, room.faces, None), ("cube", *_box((0, 0, -3)), None)])
    assert scene.closed.all()
    cam = Camera(eye=np.array([0.0, 0.0, 2.0]), target=np.zeros(3), up=np.array([0.0, 1.0, 0.0]))
    size = (160, 120)
    with monkeypatch.context() as m:
        m.setattr("rtta.passes.capture.beyond_near", lambda lo, *a: np.ones(len(lo), bool))
        culled = make_renderer(scene).std(cam, size).read(size, 1)["id"][0]
    std = make_renderer(scene).std(cam, size).read(size, 1)
    both = _pictures(make_renderer, scene, cam, size, monkeypatch, False)[0]
    assert (std["id"][0] == 0).mean() > 0.5 and (culled == 0).mean() == 0
    assert (np.abs(std["color"][0].astype(int) - both).max(-1) > 3).mean() < 1e-4


def test_open_and_inside_out_objects_are_seen_from_behind(make_renderer):
    sheet = (np.array([[0, 0, 0], [1, 0, 0], [1, 1, 0], [0, 1, 0]], float), np.array([[0, 1, 2], [0, 2, 3]]))
    inside_out = (_box((3, 0.5, 0))[0], _box()[1][:, ::-1])
    scene = from_meshes([("sheet", *sheet, None), ("inside out", *inside_out, None)])
    assert scene.closed.tolist() == [False, False]
    r = make_renderer(scene)
    cam = Camera.orbit(scene.center, scene.radius, 180, 0, 2.5)  # from -z: the sheet's back
    records = r.capture(cam, (160, 120))
    assert records.visible.all()
    depth = r.std(cam, (160, 120)).read((160, 120), 1)["depth"][0]
    ids = r.std(cam, (160, 120)).read((160, 120), 1)["id"][0]
    for oid in (0, 1):
        assert ((ids == oid) & (depth < 1)).sum() > 50, oid


def test_objects_taken_for_closed_lose_their_back_faces(make_renderer, monkeypatch):
    """The mechanism itself: a sheet marked closed is culled from behind, in STD and in the
    atlas (its region stays empty), and drawn from the front."""
    sheet = (np.array([[0, 0, 0], [1, 0, 0], [1, 1, 0], [0, 1, 0]], float), np.array([[0, 1, 2], [0, 2, 3]]))
    scene = from_meshes([("sheet", *sheet, None)])
    monkeypatch.setattr(Scene, "closed", property(lambda self: np.ones(self.count, bool)))
    r = make_renderer(scene)
    for az, seen in ((0, True), (180, False)):
        cam = Camera.orbit(scene.center, scene.radius, az, 0, 2.5)
        covered = (r.std(cam, (96, 72)).read((96, 72), 1)["depth"][0] < 1).mean()
        records = r.capture(cam, (96, 72))
        tw, th, td = records.atlas_size
        captured = (r.atlas.read((tw, th), td)["depth"] < 1).mean()
        assert (covered > 0.05 and captured > 0.05) if seen else (covered == 0 and captured == 0), (az, covered)
