"""The core equalities on llvmpipe: atlas regions mapped back through T^-1 equal RTT;
STD equals the front-most mapped-back atlas. Both capture paths, demo and generated scenes."""

from __future__ import annotations

import numpy as np
import pytest
from checks import assert_depth_close, check_frame

from rtta.bench.compare import near_edges, near_silhouettes
from rtta.scene.camera import DEFAULT_ORBIT, Camera
from rtta.scene.generators.generate import random_scene

PATHS = ("vs", "gs")


PROJECTIONS = ("perspective", "ortho")


@pytest.mark.parametrize("projection", PROJECTIONS)
@pytest.mark.parametrize("path", PATHS)
def test_demo_default_view(make_renderer, demo_scene, path, projection):
    r = make_renderer(demo_scene)
    cam = Camera.orbit(demo_scene.center, demo_scene.radius, *DEFAULT_ORBIT, projection=projection)
    out = check_frame(r, cam, (320, 240), path)
    assert out["visible"] == demo_scene.count


@pytest.mark.parametrize("projection", PROJECTIONS)
@pytest.mark.parametrize("path", PATHS)
@pytest.mark.parametrize("orbit", [(0, 0, 2.0), (120, -40, 1.6), (250, 80, 3.0), (300, 10, 0.9)])
def test_demo_orbits(make_renderer, demo_scene, path, orbit, projection):
    r = make_renderer(demo_scene)
    cam = Camera.orbit(demo_scene.center, demo_scene.radius, *orbit, projection=projection)
    check_frame(r, cam, (256, 200), path)


@pytest.mark.parametrize("projection", PROJECTIONS)
@pytest.mark.parametrize("n", [1, 7, 60])
@pytest.mark.parametrize("path", PATHS)
def test_generated_scenes(make_renderer, n, path, projection):
    scene = random_scene(n, seed=n)
    r = make_renderer(scene)
    cam = Camera.orbit(scene.center, scene.radius, 40, 25, 1.8, projection=projection)
    out = check_frame(r, cam, (240, 180), path)
    assert out["visible"] >= 1


def test_two_thousand_objects(make_renderer):
    scene = random_scene(2000, seed=5, spread=30.0, size_range=(0.2, 0.9))
    r = make_renderer(scene)
    cam = Camera.orbit(scene.center, scene.radius, 20, 30, 1.5)
    out = check_frame(r, cam, (256, 192), "vs")
    assert out["visible"] > 500


def test_paths_produce_identical_atlases(make_renderer, demo_scene):
    r = make_renderer(demo_scene)
    cam = Camera.orbit(demo_scene.center, demo_scene.radius, *DEFAULT_ORBIT)
    images = []
    for path in PATHS:
        rec = r.capture(cam, (300, 200), path=path)
        images.append(r.atlas.read(rec.atlas_size[:2], rec.atlas_size[2]))
    a, b = images
    for layer in range(a["id"].shape[0]):
        inner = ~near_edges(a["id"][layer])
        assert np.array_equal(a["id"][layer][inner], b["id"][layer][inner])
        assert_depth_close(
            a["depth"][layer], b["depth"][layer], inner & (a["id"][layer] >= 0), a["id"][layer], f"layer {layer}"
        )
        smooth = inner & ~near_silhouettes(a["id"][layer], a["depth"][layer], b["depth"][layer])
        assert np.abs(a["color"][layer].astype(int) - b["color"][layer].astype(int))[smooth].max() <= 3


def test_culled_objects_are_not_packed(make_renderer):
    scene = random_scene(40, seed=2, spread=20.0)
    r = make_renderer(scene)
    cam = Camera.orbit(scene.center, scene.radius, 0, 0, 0.05)  # in the middle of the scene
    rec = r.capture(cam, (200, 150), path="vs")
    assert 0 < rec.visible.sum() < scene.count
    assert (rec.atlas_rect[~rec.visible] == 0).all()
    atlas = r.atlas.read(rec.atlas_size[:2], rec.atlas_size[2])
    present = set(np.unique(atlas["id"])) - {-1}
    assert present <= set(np.flatnonzero(rec.visible))


def test_twenty_thousand_part_assembly(make_renderer, tmp_path):
    """The batched loader's output at 20,000 parts (a generated GLB): STD against the
    front-most atlas everywhere, and id/depth against RTT for a sample of objects."""
    from rtta.scene.generators.assembly import write_assembly
    from rtta.scene.loader import load_scene

    scene = load_scene(write_assembly(tmp_path / "assembly.glb", 20_000, seed=2))
    assert scene.count == 20_000
    r = make_renderer(scene)
    cam = Camera.orbit(scene.center, scene.radius, 30, 20, 2.0)  # all in view: few culled to check
    sample = np.random.default_rng(0).choice(scene.count, 40, replace=False)
    out = check_frame(r, cam, (400, 300), "vs", rtt_objects=sample)
    assert out["visible"] > 15_000


@pytest.mark.parametrize("path", PATHS)
def test_culled_and_hidden_objects_are_not_drawn(make_renderer, gl, path):
    """The capture's one draw covers only the objects with a region: the GPU generates
    exactly their triangles (culled and hidden ones are never fetched), and the atlas still
    equals RTT per object."""
    scene = random_scene(60, seed=4, spread=20.0)
    r = make_renderer(scene)
    cam = Camera.orbit(scene.center, scene.radius, 0, 0, 0.05)  # inside the scene: many culled
    r.hidden = {3, 17, 18, 19, 40}
    query = gl.query(primitives=True)
    with query:
        rec = r.capture(cam, (200, 150), path=path)
    runs = np.r_[False, rec.visible, False].astype(int)
    assert 1 < np.count_nonzero(np.diff(runs) == 1) and not rec.visible[[3, 17, 18, 19, 40]].any()
    triangles = scene.index_ranges[rec.visible, 1].sum() // 3  # (gs: counted after the geometry shader)
    assert query.primitives == triangles, (query.primitives, triangles, scene.indices.size // 3)
    check_frame(r, cam, (200, 150), path)
