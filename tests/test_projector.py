"""Projective texturing checked in numpy: image pixels land where bias · P · V predicts,
nothing lands behind the projector or in its shadow, and the composited modes (painting
at the world position reconstructed from the atlas depth) agree with STD."""

from __future__ import annotations

import numpy as np
import pytest
import trimesh

from rtta.bench.compare import near_edges
from rtta.errors import RttaError
from rtta.passes.projector import Projector, default_image, load_image
from rtta.renderer.snapshot import over_background
from rtta.scene.camera import Camera
from rtta.scene.model import from_meshes

VP = (200, 150)


def _plane(size=8.0):
    v = np.array([[-1, -1, 0], [1, -1, 0], [1, 1, 0], [-1, 1, 0]], float) * size / 2
    return ("plane", v, np.array([[0, 1, 2], [0, 2, 3]]), None)


def _blocks(cells=8, texels=8, seed=0) -> np.ndarray:
    """An image of cells x cells uniformly coloured blocks (RGBA, top row first)."""
    rng = np.random.default_rng(seed)
    colors = rng.integers(0, 256, (cells, cells, 3), dtype=np.uint8)
    img = np.repeat(np.repeat(colors, texels, 0), texels, 1)
    return np.concatenate([img, np.full((*img.shape[:2], 1), 255, np.uint8)], -1)


def _render(r, cam, projector):
    r.projector = projector
    return r.std(cam, VP).read(VP, 1)["color"][0][..., :3].astype(int)


def _world_on_plane(r, cam) -> np.ndarray:
    """World point (relative to the scene origin) on z = 0 seen through each pixel centre."""
    view, proj = r.matrices(cam, VP)
    inv = np.linalg.inv(proj @ view)
    x, y = np.meshgrid((np.arange(VP[0]) + 0.5) / VP[0] * 2 - 1, (np.arange(VP[1]) + 0.5) / VP[1] * 2 - 1)
    pts = []
    for z in (-1.0, 1.0):
        h = np.stack([x, y, np.full_like(x, z), np.ones_like(x)], -1) @ inv.T
        pts.append(h[..., :3] / h[..., 3:])
    a, b = pts
    origin_z = -r.scene.origin[2]
    k = (origin_z - a[..., 2]) / (b[..., 2] - a[..., 2])
    return a + k[..., None] * (b - a)


def _predicted_texel(projector, origin, world) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """(ix, iy_top, inside) of the image texel each world point gets (iy counted from the top)."""
    m = projector.matrix(origin)
    h = np.concatenate([world, np.ones((*world.shape[:2], 1))], -1) @ m.T
    q = h[..., 3]
    s, t = h[..., 0] / q, h[..., 1] / q
    H, W = projector.image.shape[:2]
    inside = (q > 0) & (s >= 0) & (s <= 1) & (t >= 0) & (t <= 1)
    ix = np.clip(np.floor(s * W), 0, W - 1).astype(int)
    iy = np.clip(np.floor(t * H), 0, H - 1).astype(int)
    return ix, H - 1 - iy, inside


def _same_in_3x3(a: np.ndarray) -> np.ndarray:
    """Pixels whose 8 neighbours hold the same value (not within a pixel of a change)."""
    return ~near_edges(a)


def test_image_pixels_land_where_the_projection_predicts(make_renderer):
    scene = from_meshes([_plane()], colors=[[1.0, 1.0, 1.0, 1.0]])
    r = make_renderer(scene)
    cam = Camera(eye=np.array([1.5, -1.0, 6.0]), target=np.zeros(3), up=np.array([0.0, 1, 0]))
    cam.fit_depth(scene.center, scene.radius)
    image = _blocks()
    projector = Projector(
        eye=np.array([0.4, -0.3, 5.0]), target=np.array([0.2, 0.1, 0.0]), fov_y=40.0, image=image, shadows=False
    ).fit_depth(scene.center, scene.radius)
    plain = _render(r, cam, None)
    painted = _render(r, cam, projector)
    ix, iy, inside = _predicted_texel(projector, scene.origin, _world_on_plane(r, cam))
    block = (iy // 8) * 8 + ix // 8
    check = inside & _same_in_3x3(np.where(inside, block, -1))  # 1 pixel away from any block edge
    assert check.sum() > 5000
    light = plain / 255.0
    expected = image[iy, ix, :3] * light
    err = np.abs(painted - expected)[check].max(-1)
    assert (err <= 3).mean() >= 0.999 and err.max() <= 6, (err.max(), (err > 3).sum())
    outside = ~inside & _same_in_3x3(inside.astype(int))
    assert outside.sum() > 1000 and np.abs(painted - plain)[outside].max() == 0


def test_nothing_lands_behind_the_projector(make_renderer):
    scene = from_meshes([_plane()], colors=[[1.0, 1.0, 1.0, 1.0]])
    r = make_renderer(scene)
    cam = Camera(eye=np.array([0.5, 0.5, 6.0]), target=np.zeros(3), up=np.array([0.0, 1, 0]))
    cam.fit_depth(scene.center, scene.radius)
    away = Projector(
        eye=np.array([0.0, 0.0, 2.0]), target=np.array([0.0, 0.0, 6.0]), fov_y=120.0, image=_blocks(), shadows=False
    ).fit_depth(scene.center, scene.radius)
    world = _world_on_plane(r, cam)
    m = away.matrix(scene.origin)
    h = np.concatenate([world, np.ones((*world.shape[:2], 1))], -1) @ m.T
    s, t = h[..., 0] / h[..., 3], h[..., 1] / h[..., 3]
    mirrored = (h[..., 3] < 0) & (s >= 0) & (s <= 1) & (t >= 0) & (t <= 1)
    assert mirrored.mean() > 0.3  # without the q <= 0 test these pixels would be painted
    assert np.array_equal(_render(r, cam, away), _render(r, cam, None))


def test_shadowed_surface_receives_nothing(make_renderer):
    box = trimesh.creation.box(extents=(1.0, 1.0, 0.5))
    blocker = ("blocker", np.asarray(box.vertices) + [0.0, 0.0, 2.5], np.asarray(box.faces), None)
    scene = from_meshes([_plane(), blocker], colors=[[1.0, 1.0, 1.0, 1.0], [0.3, 0.3, 0.3, 1.0]])
    r = make_renderer(scene)
    cam = Camera(eye=np.array([3.0, 2.0, 7.0]), target=np.zeros(3), up=np.array([0.0, 1, 0]))
    cam.fit_depth(scene.center, scene.radius)
    eye = np.array([0.0, 0.0, 6.0])
    lit = Projector(eye=eye, target=np.zeros(3), fov_y=60.0, image=_blocks(), shadows=True)
    lit.fit_depth(scene.center, scene.radius)
    plain = _render(r, cam, None)
    shadowed = _render(r, cam, lit)
    lit.shadows = False
    unshadowed = _render(r, cam, lit)
    ids = r.std(cam, VP).read(VP, 1)["id"][0]
    world = _world_on_plane(r, cam) + scene.origin
    # the segment from the projector to the plane point crosses the blocker's box (numpy)
    lo, hi = scene.aabb_min[1], scene.aabb_max[1]
    d = world - eye
    with np.errstate(divide="ignore", invalid="ignore"):
        t0, t1 = (lo - eye) / d, (hi - eye) / d
    enter = np.minimum(t0, t1).max(-1)
    leave = np.maximum(t0, t1).min(-1)
    in_shadow = (enter <= leave) & (leave > 0) & (enter < 1)
    plane = (ids == 0) & _same_in_3x3(ids)
    umbra = plane & _same_in_3x3(in_shadow.astype(int)) & in_shadow
    sunlit = plane & _same_in_3x3(in_shadow.astype(int)) & ~in_shadow
    assert umbra.sum() > 300 and sunlit.sum() > 1000
    assert np.abs(shadowed - plain)[umbra].max() <= 1  # nothing in the shadow
    assert (np.abs(unshadowed - plain)[umbra].max(-1) > 3).mean() > 0.5  # painted without shadows
    assert np.array_equal(shadowed[sunlit], unshadowed[sunlit])


@pytest.mark.parametrize("mode", ["sprites", "ghosted"])
def test_composited_modes_paint_like_std(make_renderer, demo_scene, mode):
    r = make_renderer(demo_scene)
    cam = Camera.orbit(demo_scene.center, demo_scene.radius, 35, 25, 2.2)
    r.projector = Projector.orbit(demo_scene.center, demo_scene.radius, 60, 35, 2.5, fov_y=35.0)
    std = over_background(r.std(cam, (240, 180)).read((240, 180), 1)["color"][0])[..., :3].astype(int)
    r.capture(cam, (240, 180))
    rgba, _ = r.composite("sprites").read()
    close = np.abs(rgba[..., :3].astype(int) - std).max(-1) <= 3
    assert close.mean() >= 0.99
    r.projector = None
    plain, _ = r.composite("sprites").read()
    assert (np.abs(plain[..., :3].astype(int) - std).max(-1) > 3).mean() > 0.05  # the projection shows
    if mode == "ghosted":
        r.projector = Projector.orbit(demo_scene.center, demo_scene.radius, 60, 35, 2.5, fov_y=35.0)
        painted, _ = r.composite("ghosted").read()
        r.projector = None
        unpainted, _ = r.composite("ghosted").read()
        assert (np.abs(painted.astype(int) - unpainted.astype(int)).max(-1) > 3).mean() > 0.05


def test_default_image_is_the_shipped_asset_and_bad_images_fail_cleanly(tmp_path):
    from importlib import resources

    shipped = load_image(resources.files("rtta.assets").joinpath("projector_grid.png"))
    assert np.array_equal(shipped, default_image())
    bad = tmp_path / "bad.png"
    bad.write_bytes(b"not an image")
    with pytest.raises(RttaError, match="bad.png"):
        load_image(bad)
    with pytest.raises(RttaError, match="no such image"):
        load_image(tmp_path / "missing.png")
