"""Extreme cameras and scenes: no NaN, no GL error, and the core equalities still hold."""

from __future__ import annotations

import numpy as np
import pytest
import trimesh
from checks import check_frame

from rtta.bench.compare import near_edges
from rtta.renderer.placing import make_staging
from rtta.scene.camera import Camera
from rtta.scene.generators.generate import random_scene
from rtta.scene.model import from_meshes

PATHS = ("vs", "gs")


def _box(size, center):
    m = trimesh.creation.box(extents=np.full(3, size))
    return np.asarray(m.vertices) + center, np.asarray(m.faces)


def _look(eye, target, center, radius, fov=45.0) -> Camera:
    cam = Camera(eye=np.asarray(eye, float), target=np.asarray(target, float), up=np.array([0.0, 1, 0]), fov_y=fov)
    return cam.fit_depth(center, radius)


@pytest.mark.parametrize("path", PATHS)
def test_camera_inside_an_object(make_renderer, path):
    parts = [("room", *_box(20.0, np.zeros(3)), None)]
    rng = np.random.default_rng(1)
    for i in range(8):
        parts.append((f"crate{i}", *_box(rng.uniform(0.5, 2), rng.uniform(-6, 6, 3)), None))
    scene = from_meshes(parts)
    r = make_renderer(scene)
    target = (scene.aabb_min[1] + scene.aabb_max[1]) / 2  # look at a crate from inside the room
    cam = _look([0.3, 0.2, 0.1], target, scene.center, scene.radius)
    out = check_frame(r, cam, (200, 150), path)
    rec = r.parameterize(cam, (200, 150))
    assert rec.visible[0] and list(rec.viewport_rect[0]) == [0, 0, 200, 150]  # surrounds the camera
    assert out["visible"] >= 2


@pytest.mark.parametrize("path", PATHS)
def test_objects_crossing_the_near_plane(make_renderer, demo_scene, path):
    r = make_renderer(demo_scene)
    cam = Camera.orbit(demo_scene.center, demo_scene.radius, 30, 15, 1.2)
    cam.near = float(np.linalg.norm(cam.eye - demo_scene.center)) * 0.9  # cuts through the assembly
    rec = r.parameterize(cam, (240, 180))
    corners = demo_scene.box_corners()
    view = cam.view(demo_scene.origin)
    z = (np.concatenate([corners, np.ones((*corners.shape[:2], 1))], 2) @ view.T)[..., 2]
    crossing = (z.max(1) > -cam.near) & (z.min(1) < -cam.near)
    assert crossing.sum() >= 3, "the view must cut several objects"
    assert rec.visible[crossing].any()
    check_frame(r, cam, (240, 180), path)


@pytest.mark.parametrize("path", PATHS)
def test_objects_behind_the_camera(make_renderer, path):
    scene = random_scene(60, seed=4, spread=20.0)
    r = make_renderer(scene)
    cam = _look([0, 0, 0], [0, 0, -1], scene.center, scene.radius)
    rec = r.parameterize(cam, (200, 150))
    behind = scene.aabb_min[:, 2] > 0.5
    assert behind.sum() >= 10 and not rec.visible[behind].any()
    check_frame(r, cam, (200, 150), path)


def test_scene_far_from_the_origin(make_renderer):
    near_scene = random_scene(25, seed=9)
    far_scene = random_scene(25, seed=9, offset=(1e6, -1e6, 1e6))
    frames = []
    for scene in (near_scene, far_scene):
        r = make_renderer(scene)
        cam = Camera.orbit(scene.center, scene.radius, 30, 20, 1.8)
        check_frame(r, cam, (220, 160), "vs")
        frames.append(r.std(cam, (220, 160)).read((220, 160), 1))
    a, b = frames
    inner = ~near_edges(a["id"][0])
    assert (a["id"][0] != b["id"][0])[inner].mean() < 0.002
    same = inner & (a["id"][0] == b["id"][0]) & (a["id"][0] >= 0)
    assert np.abs(a["depth"][0] - b["depth"][0])[same].max() < 1e-5


@pytest.mark.parametrize("path", PATHS)
def test_tiny_and_huge_objects_in_one_scene(make_renderer, path):
    parts = [
        ("huge", *_box(1e4, np.zeros(3)), None),
        ("tiny", *_box(1e-4, np.array([6e3, 0, 0])), None),
        ("mid", *_box(1.0, np.array([6e3, 0, 2.0])), None),
    ]
    scene = from_meshes(parts)
    r = make_renderer(scene)
    check_frame(r, Camera.orbit(scene.center, scene.radius, 60, 10, 1.5), (200, 200), path)
    close = _look([6e3 + 3e-4, 1e-4, 2e-4], [6e3, 0, 0], np.array([6e3, 0, 0]), 1e-3)
    out = check_frame(r, close, (200, 200), path)
    assert out["visible"] >= 1


@pytest.mark.parametrize("path", PATHS)
@pytest.mark.parametrize("fov", [5.0, 150.0])
def test_extreme_fields_of_view(make_renderer, demo_scene, path, fov):
    r = make_renderer(demo_scene)
    cam = Camera.orbit(demo_scene.center, demo_scene.radius, 40, 20, 2.0 if fov > 90 else 12.0, fov_y=fov)
    out = check_frame(r, cam, (200, 150), path)
    assert out["visible"] >= 10


@pytest.mark.parametrize("path", PATHS)
@pytest.mark.parametrize("viewport", [(1, 512), (4096, 16)])
def test_extreme_viewports(make_renderer, demo_scene, path, viewport):
    r = make_renderer(demo_scene)
    cam = Camera.orbit(demo_scene.center, demo_scene.radius, 40, 20, 2.2)
    out = check_frame(r, cam, viewport, path)
    assert out["visible"] >= 1


@pytest.mark.parametrize("projection", ["perspective", "ortho"])
def test_view_and_outline_eye_match_numpy(projection):
    """The view matrix's lengths (without np.linalg.norm) and the outline eye from its rigid
    inverse (without np.linalg.inv) against numpy's own, over orbits near and far, at a far origin."""
    from rtta.scene.camera import near_distance, outline_eye, view_depth

    rng = np.random.default_rng(5)
    for _ in range(50):
        center, radius = rng.normal(size=3) * 10.0 ** rng.uniform(-3, 6), 10.0 ** rng.uniform(-4, 5)
        cam = Camera.orbit(center, radius, rng.uniform(0, 360), rng.uniform(-89, 89), rng.uniform(0.1, 10))
        cam.kind = projection
        origin = center + rng.normal(size=3) * radius
        view, proj = cam.view(origin), cam.projection(1.5)
        assert near_distance(proj) == pytest.approx(float(view_depth(0.0, proj)), rel=1e-12)
        f = (cam.target - cam.eye) / np.linalg.norm(cam.target - cam.eye)
        np.testing.assert_allclose(view[2, :3], -f, atol=1e-12)
        np.testing.assert_allclose(view[:3, :3] @ view[:3, :3].T, np.eye(3), atol=1e-12)
        inv = np.linalg.inv(view)
        far = 1e4 * radius if projection == "ortho" else 0.0
        want = inv[:3, 3] + inv[:3, 2] * far
        np.testing.assert_allclose(
            outline_eye(view, proj, radius), want, rtol=1e-9, atol=1e-9 * (1 + np.abs(want).max())
        )
        np.testing.assert_allclose(
            outline_eye(view, proj, radius)[:3] - far * inv[:3, 2],
            cam.eye - origin,
            atol=1e-6 * (1 + np.abs(cam.eye - origin).max()),
        )


@pytest.mark.parametrize("up_axis", ["y", "z"])
def test_orbit_matches_the_spherical_formula(up_axis):
    """Camera.orbit (scalar math) against numpy's spherical coordinates over wide angles; a
    non-finite angle is refused with RttaError rather than making a NaN camera."""
    from rtta.errors import RttaError
    from rtta.scene.camera import up_basis

    rng = np.random.default_rng(11)
    basis = up_basis(up_axis)
    for _ in range(200):
        az, el, dist = rng.uniform(-1e6, 1e6), rng.uniform(-90, 90), rng.uniform(0.1, 10)
        a, e = np.radians(az), np.radians(el)
        cam = Camera.orbit([1.0, -2.0, 3.0], 2.5, az, el, dist, up_axis=up_axis)
        eye = np.array([1.0, -2.0, 3.0]) + basis @ [np.sin(a) * np.cos(e), np.sin(e), np.cos(a) * np.cos(e)] * (
            dist * 2.5
        )
        np.testing.assert_allclose(cam.eye, eye, atol=1e-9)
        np.testing.assert_allclose(
            cam.up, basis @ [-np.sin(a) * np.sin(e), np.cos(e), -np.cos(a) * np.sin(e)], atol=1e-12
        )
    for bad in (np.nan, np.inf, -np.inf):
        with pytest.raises(RttaError, match="finite"):
            Camera.orbit([0.0, 0, 0], 1.0, bad, 0.0, 2.0)
        with pytest.raises(RttaError, match="finite"):
            Camera.orbit([0.0, 0, 0], 1.0, 0.0, bad, 2.0)


@pytest.mark.parametrize("path", PATHS)
@pytest.mark.parametrize("height", [1e-5, 1e-6])
@pytest.mark.parametrize("section", [None, "z=0.599995"])
def test_ortho_zoomed_past_float32_clipping(make_renderer, path, height, section):
    """An orthographic view `height` scene radii high on a corner where two boxes meet (cut
    and capped just below it): the parts' triangles reach clip coordinates of ~1e6, beyond
    what float32 clips to the region planes within a pixel; the guard (rtta.passes.guard)
    keeps every region whole. Failed without it: STD and the atlas differed at ~160 px; and
    with the guard's atlas size taken from the textures, larger than the part drawn (the sweep)."""
    scene = from_meshes([("a", *_box(2.0, np.zeros(3)), None), ("b", *_box(1.0, np.array([1.5, 0.2, 0.1])), None)])
    corner = np.array([1.0, 0.7, 0.6])  # b's corner on a's face
    eye = corner + np.array([0.4, 0.5, 1.0])
    cam = Camera(eye=eye, target=corner, up=np.array([0.0, 1, 0]), kind="ortho", height=height * scene.radius)
    r = make_renderer(scene)
    if section is not None:
        r.staging = make_staging([section], "solid")
    r.capture(Camera.orbit(scene.center, scene.radius, 30, 20, 2.0), (900, 700), path=path)  # atlas textures grow
    out = check_frame(r, cam.fit_depth(scene.center, scene.radius), (320, 240), path)
    assert out["visible"] == 2 and r.capture_pass(path).guard > 0
