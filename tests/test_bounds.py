"""Tighter object bounds (oriented boxes), the atlas region scale, and the degradations the
stability report relies on: depth range limit and collapsed-object warning."""

from __future__ import annotations

import warnings

import numpy as np
import pytest
import trimesh
from checks import assert_depth_close, check_frame

from rtta.bench.report_runs import _two_spheres, sprites_error
from rtta.cli.main import main
from rtta.renderer.renderer import Settings
from rtta.scene.camera import MAX_FAR_NEAR, Camera
from rtta.scene.generators.generate import random_scene
from rtta.scene.model import from_meshes


def _rotated_box(extents, angle, axis, shift=(0.0, 0.0, 0.0)):
    m = trimesh.creation.box(extents)
    m.apply_transform(trimesh.transformations.rotation_matrix(angle, axis))
    return np.asarray(m.vertices) + shift, np.asarray(m.faces)


def test_obb_contains_every_vertex():
    scene = random_scene(40, seed=4, size_range=(0.1, 2.0))
    both = scene.box_corners("obb")
    assert np.array_equal(both[0], scene.box_corners("aabb"))
    obb = both[1]
    for i in range(scene.count):
        c = obb[i]
        axes = np.stack([c[1 << k] - c[0] for k in range(3)])  # box edges from corner 0
        local = (scene.positions[scene.object_ids == i] - c[0]) @ axes.T / np.maximum((axes**2).sum(1), 1e-30)
        assert (local >= -1e-6).all() and (local <= 1 + 1e-6).all(), i


def _area(corners):
    e = [np.linalg.norm(corners[:, 1 << k] - corners[:, 0], axis=1) for k in range(3)]
    return e[0] * e[1] + e[1] * e[2] + e[0] * e[2]


def test_obb_of_a_rotated_box_is_the_box():
    v, f = _rotated_box([4.0, 1.0, 0.5], 0.6, [1, 1, 0])
    scene = from_meshes([("bar", v, f, None)])
    c = scene.box_corners("obb")[1, 0]
    edges = sorted(np.linalg.norm(c[1 << k] - c[0]) for k in range(3))
    assert np.allclose(edges, [0.5, 1.0, 4.0], atol=1e-5)
    assert _area(scene.box_corners("aabb"))[0] > 1.5 * _area(scene.box_corners("obb")[1])[0]


def test_unknown_bounds_is_rejected(demo_scene):
    with pytest.raises(ValueError, match="unknown bounds"):
        demo_scene.box_corners("sphere")


@pytest.mark.parametrize("scene_name", ["demo", "random"])
def test_obb_capture_equals_rtt_and_std(make_renderer, demo_scene, scene_name):
    """With oriented bounds every object still lands whole in its region (RTT equality) and
    STD is the front-most atlas: the tighter bounds clip nothing."""
    scene = demo_scene if scene_name == "demo" else random_scene(60, seed=9, size_range=(0.2, 2.5))
    r = make_renderer(scene, Settings(bounds="obb"))
    cam = Camera.orbit(scene.center, scene.radius, 40, 25, 1.8)
    check_frame(r, cam, (240, 180), "vs")


def test_obb_regions_are_smaller(make_renderer):
    parts = [
        (f"bar{i}", *_rotated_box([3.0, 0.3, 0.3], 0.3 + 0.4 * i, [0, 0.5, 1], (i * 2.0, 0, 0)), None) for i in range(6)
    ]
    scene = from_meshes(parts)
    cam = Camera.orbit(scene.center, scene.radius, 20, 30, 2.0)
    area = {}
    for bounds in ("aabb", "obb"):
        rec = make_renderer(scene, Settings(bounds=bounds)).parameterize(cam, (320, 240))
        inner = rec.viewport_rect[:, 2:] - rec.viewport_rect[:, :2]
        area[bounds] = (inner[:, 0] * inner[:, 1]).sum()
    assert area["obb"] < 0.8 * area["aabb"]


@pytest.mark.parametrize("scale", [0.5, 2.0])
def test_region_scale_sizes_regions(make_renderer, demo_scene, scale):
    cam = Camera.orbit(demo_scene.center, demo_scene.radius, 30, 20, 2.2)
    r = make_renderer(demo_scene, Settings(region_scale=scale, border=1))
    rec = r.capture(cam, (256, 192))
    vis = rec.visible
    inner = (rec.viewport_rect[vis, 2:] - rec.viewport_rect[vis, :2]).astype(float)
    assert np.array_equal(rec.atlas_rect[vis, 2:] - 2, np.maximum(np.ceil(inner * scale - 1e-9), 1))
    assert np.allclose(rec.scale[vis], scale)
    assert rec.atlas_size[0] <= int(np.ceil(256 * scale)) + 2


def test_supersampled_regions_are_the_double_resolution_capture(make_renderer, demo_scene):
    """At region scale 2 an object's region holds what a scale-1 capture of a viewport twice
    as large holds: texel a + (p - 2 x0) for pixel p of the large viewport, id for id."""
    cam = Camera.orbit(demo_scene.center, demo_scene.radius, 30, 20, 2.2)
    small, large = (160, 120), (320, 240)
    r2 = make_renderer(demo_scene, Settings(region_scale=2.0))
    r1 = make_renderer(demo_scene)
    rec2, rec1 = r2.capture(cam, small), r1.capture(cam, large)
    at2 = r2.atlas.read(rec2.atlas_size[:2], rec2.atlas_size[2], parts=("id", "depth"))
    at1 = r1.atlas.read(rec1.atlas_size[:2], rec1.atlas_size[2], parts=("id", "depth"))
    compared = 0
    for oid in np.flatnonzero(rec1.visible & rec2.visible):
        lx0, ly0, lx1, ly1 = rec1.viewport_rect[oid]
        sx0, sy0 = rec2.viewport_rect[oid, :2]
        px, py = np.meshgrid(np.arange(lx0, lx1), np.arange(ly0, ly1))
        t2x = rec2.atlas_rect[oid, 0] + 1 + px - 2 * sx0
        t2y = rec2.atlas_rect[oid, 1] + 1 + py - 2 * sy0
        t1x, t1y = rec1.atlas_rect[oid, 0] + 1 + px - lx0, rec1.atlas_rect[oid, 1] + 1 + py - ly0
        ids2 = at2["id"][rec2.layer[oid]][t2y, t2x]
        ids1 = at1["id"][rec1.layer[oid]][t1y, t1x]
        assert np.array_equal(ids2, ids1), oid
        on = ids1 == oid
        d2 = at2["depth"][rec2.layer[oid]][t2y, t2x]
        d1 = at1["depth"][rec1.layer[oid]][t1y, t1x]
        assert_depth_close(d2, d1, on, ids1, f"object {oid}")
        compared += int(on.sum())
    assert compared > 10000


def test_region_scale_is_checked():
    from rtta.atlas.parameterize import parameterize

    with pytest.raises(ValueError, match="region scale"):
        parameterize(np.zeros((1, 8, 3)), np.identity(4), (8, 8), region_scale=0.0)


def test_extreme_depth_range_degrades_with_a_message(make_renderer, demo_scene):
    cam = Camera.orbit(demo_scene.center, demo_scene.radius, 30, 20, 2.2)
    cam.near = cam.far / 1e7
    limited, msg = cam.depth_limited()
    assert limited.far / limited.near == pytest.approx(MAX_FAR_NEAR) and "near plane raised" in msg
    r = make_renderer(demo_scene)
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        err = sprites_error(r, cam, (256, 192))
        sprites_error(r, cam, (256, 192))
    assert len([w for w in caught if "near plane raised" in str(w.message)]) == 1  # said once
    assert r.warnings == [msg]
    assert err["finite"] and err["holes"] == 0 and err["color_off"] < 0.005


def test_collapsed_objects_are_named():
    assert _two_spheres(1e2).warnings == []
    (note,) = _two_spheres(1e8).warnings
    assert "small" in note and "collapsed" in note


def test_cli_region_scale_and_bounds(tmp_path, capsys):
    out = tmp_path / "s.png"
    assert (
        main(
            [
                "snapshot",
                "--mode",
                "sprites",
                "--size",
                "160x120",
                "--bounds",
                "obb",
                "--region-scale",
                "0.5",
                "--out",
                str(out),
            ]
        )
        == 0
    )
    assert out.stat().st_size > 1000
    assert main(["snapshot", "--region-scale", "9", "--out", str(tmp_path / "t.png")]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "--region-scale" in err[0]
    assert not (tmp_path / "t.png").exists()
