"""Atlas textures are reused across frames, grow at once, shrink lazily, and are released."""

import numpy as np

from rtta.camera import Camera
from rtta.generate import random_scene
from rtta.targets import SHRINK_AFTER_FRAMES, LayeredTarget


def test_hysteresis(gl):
    t = LayeredTarget(gl, (64, 64), 1)
    try:
        assert not t.ensure((60, 60), 1)
        assert t.ensure((300, 100), 3) and t.size[0] >= 300 and t.layers == 3
        allocations = t.allocations
        for _ in range(SHRINK_AFTER_FRAMES - 1):
            assert not t.ensure((40, 40), 1)          # small need: kept for a while
        assert t.allocations == allocations
        assert t.ensure((40, 40), 1) and t.layers == 1  # then shrunk once
        assert not t.ensure((300, 100), 1) or t.size[0] >= 300
    finally:
        t.release()


def test_capture_reuses_textures_across_frames(make_renderer, gl):
    scene = random_scene(50, seed=2)
    r = make_renderer(scene)
    rng = np.random.default_rng(0)
    r.capture(Camera.orbit(scene.center, scene.radius, 0, 0, 2.0), (200, 150))
    first = r.atlas.allocations
    for _ in range(40):
        cam = Camera.orbit(scene.center, scene.radius, rng.uniform(0, 360), rng.uniform(-60, 60), 2.0)
        r.capture(cam, (200, 150))
    assert r.atlas.allocations - first <= 3


def test_clear_values(gl):
    t = LayeredTarget(gl, (16, 8), 2)
    try:
        t.clear()
        d = t.read()
        assert (d["id"] == -1).all() and (d["depth"] == 1.0).all() and (d["color"] == 0).all()
        assert d["id"].shape == (2, 8, 16)
    finally:
        t.release()


def test_trim_shrinks_to_the_last_capture_at_once(make_renderer, demo_scene, gl):
    """After a large view, trim() gives the memory back now (not after SHRINK_AFTER_FRAMES),
    and the next capture and composite work in the trimmed targets and equal an untrimmed run."""
    from rtta.snapshot import over_background

    r = make_renderer(demo_scene)
    cam = Camera.orbit(demo_scene.center, demo_scene.radius, 30, 20, 2.2)
    r.capture(cam, (900, 700))
    r.composite("sprites")
    big = r.target_bytes
    r.capture(cam, (120, 90))
    before = over_background(r.composite("sprites").read()[0])
    assert r.target_bytes == big                     # lazily kept
    r.trim()
    assert r.target_bytes < big / 10 and r.atlas.size[0] <= 192 and r.target.size == (128, 128)
    r.capture(cam, (120, 90))
    after = over_background(r.composite("sprites").read()[0])
    assert np.abs(after.astype(int) - before.astype(int)).max() <= 1
