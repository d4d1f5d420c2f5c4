"""How many covered pixels does back-to-front object order get wrong? From one capture, in
numpy: per pixel, the covering objects' atlas depths in draw order; a pixel is out of order
where a surface lies behind (or at the depth of) one drawn before it. For the sort keys the
composite could use: the view depth of the bounds' centre (shipped), nearest, farthest corner.
python scripts/probe_object_order.py [SCENE] [--size 1024x1024]"""

from __future__ import annotations

import argparse

import numpy as np

from rtta.gl.context import shared_context
from rtta.gl.readback import map_back
from rtta.passes.composite import back_to_front
from rtta.renderer.renderer import Renderer
from rtta.scene.camera import Camera
from rtta.scene.loader import load_scene_or_demo

ORBITS = ((30, 20, 2.2), (-60, 40, 1.2), (150, -30, 0.9))


def out_of_order(depths: dict[int, np.ndarray], order: np.ndarray) -> tuple[int, int]:
    """(covered pixels, pixels with a surface at or behind the nearest drawn before it)."""
    nearest = inverted = None
    for o in order:
        d = depths[int(o)]
        covered = d < 1.0
        if nearest is None:
            nearest, inverted = np.ones_like(d), np.zeros(d.shape, bool)
        inverted |= covered & (d >= nearest)
        np.minimum(nearest, np.where(covered, d, 1.0), out=nearest)
    return int((nearest < 1.0).sum()), int(inverted.sum())


def main() -> None:
    p = argparse.ArgumentParser()
    p.add_argument("scene", nargs="?")
    p.add_argument("--size", default="1024x1024")
    a = p.parse_args()
    ctx = shared_context()
    scene = load_scene_or_demo(a.scene)
    viewport = tuple(int(v) for v in a.size.split("x"))
    r = Renderer(ctx, scene)
    print(f"{ctx.info['GL_RENDERER']}: {scene.count} objects, {a.size}; share of covered pixels out of order")
    for orbit in ORBITS:
        cam = Camera.orbit(scene.center, scene.radius, *orbit)
        records = r.capture(cam, viewport, ids=False)
        tw, th, td = records.atlas_size
        atlas = {"depth": r.atlas.read((tw, th), td, ("depth",))["depth"]}
        visible = np.flatnonzero(records.visible)
        depths = {int(o): map_back(atlas, records, o)["depth"] for o in visible}
        view = cam.view(scene.origin)
        z = -(scene.box_corners() @ view[2, :3] + view[2, 3])  # view depth of every corner [n, 8]
        keys = {"centre": z.mean(1), "nearest corner": z.min(1), "farthest corner": z.max(1)}
        shares = []
        for name, key in keys.items():
            covered, wrong = out_of_order(depths, back_to_front(records, key, visible))
            shares.append(f"{name} {wrong / max(covered, 1):.3f}")
        print(f"camera {orbit}: covered {covered}, " + ", ".join(shares))
    r.release()


if __name__ == "__main__":
    main()
