"""Sprites over the projected outline of B_world (composite.geom's HULL) instead of the whole
B_viewport: they must shade exactly the pixels the rectangles do, in every mode."""

from __future__ import annotations

import numpy as np
import pytest
import trimesh

from rtta.passes.composite import CompositePass, Style
from rtta.renderer.renderer import Settings
from rtta.scene.camera import Camera
from rtta.scene.model import from_meshes

VP = (240, 180)
CAMERAS = [(30, 20, 2.2), (75, 40, 0.7), (160, -30, 0.3), (250, 80, 1.2), (300, -85, 0.05), (0, 0, 1.0)]
MODES = [
    ("sprites", {}),
    ("ghosted", {"halo": 2}),
    ("ghosted-ao", {}),
    ("transparent", {}),
    ("ghosted", {"order": "pixel", "outline_width": 3}),
]


def _boxes() -> object:
    """Axis-aligned boxes (their outline is their own silhouette: no slack for the outline's
    margin to hide in; vertices along their edges round off the line), some thin, and a few
    turned ones, on a grid."""
    rng = np.random.default_rng(3)
    parts = []
    for i in range(18):
        size = rng.uniform(0.2, 1.0, 3)
        if i % 5 == 0:
            size[i % 3] = 0.02
        box = trimesh.creation.box(extents=size).subdivide().subdivide()  # vertices along the edges
        if i % 4 == 3:
            box.apply_transform(trimesh.transformations.random_rotation_matrix(rng.random(3)))
        center = np.array([i % 3, (i // 3) % 3, i // 9], float) * 1.4
        parts.append((f"b{i}", np.asarray(box.vertices) + center, np.asarray(box.faces), None))
    return from_meshes(parts)


def _rectangles(render):
    def render_without_outlines(self, **kw):
        return render(self, **{**kw, "eye": None})

    return render_without_outlines


@pytest.mark.parametrize("which,scale", [("demo", 1.0), ("boxes", 1.0), ("boxes", 2.0), ("demo", 1.37)])
def test_outline_sprites_shade_what_rectangles_shade(make_renderer, demo_scene, which, scale, monkeypatch):
    """Also supersampled (region scale above 1): a pixel then takes the texel its centre falls
    in, which the capture covered if the texel's own centre was inside the object."""
    scene = demo_scene if which == "demo" else _boxes()
    r = make_renderer(scene, Settings(region_scale=scale))
    focus = {0, scene.count // 2}
    render = CompositePass.render
    cases = used = 0
    for orbit in CAMERAS:
        r.capture(Camera.orbit(scene.center, scene.radius, *orbit), VP, focus=focus)
        for mode, style in MODES:
            s = Style(focus=focus, **style)
            outlines = r.composite(mode, s).read()
            used += r._composite.hull_draws > 0
            monkeypatch.setattr(CompositePass, "render", _rectangles(render))
            rectangles = r.composite(mode, s).read()
            monkeypatch.setattr(CompositePass, "render", render)
            assert r._composite.hull_draws == 0
            for got, want in zip(outlines, rectangles, strict=True):  # colour, depth
                diff = np.argwhere(np.any(np.atleast_3d(got != want), axis=-1))
                assert not len(diff), f"{mode} {style} {orbit}: {len(diff)} pixels differ, first {diff[:3].tolist()}"
            cases += 1
    assert used >= cases // 2, f"outline sprites drawn in {used} of {cases} composites"
