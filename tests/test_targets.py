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
