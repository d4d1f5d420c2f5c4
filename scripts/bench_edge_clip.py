"""Captures that clip only the regions on the viewport's edge (the default) and captures that
clip every region, in turns over one orbit, in one process.

    python scripts/bench_edge_clip.py [SCENE [WxH [ROUNDS]]]     (default: demo 1024x1024 20)

Prints the medians of both, their ratio to STD (drawn in the same round) and to each other.
docs/performance/capture.md, "Only regions on the viewport's edge are clipped".
"""

from __future__ import annotations

import importlib
import sys
import time

import numpy as np

from rtta.gl.context import create_headless_context
from rtta.renderer.renderer import Renderer
from rtta.scene.camera import Camera
from rtta.scene.loader import load_scene_or_demo

Records = importlib.import_module("rtta.atlas.parameterize").Records
EDGE = Records.meets_edge
EVERY = property(lambda self: np.ones(len(self.visible), bool))  # every region clipped, as before


def main() -> None:
    args = sys.argv[1:] + [None] * 3
    ctx = create_headless_context()
    scene = load_scene_or_demo(None if args[0] in (None, "demo") else args[0])
    viewport = tuple(int(v) for v in (args[1] or "1024x1024").split("x"))
    rounds = int(args[2] or 20)
    cameras = [Camera.orbit(scene.center, scene.radius, 30 + 36 * i, 20, 2.2) for i in range(10)]
    r = Renderer(ctx, scene)
    times: dict[str, list[float]] = {"std": [], "every region clipped": [], "edge regions clipped": []}
    edges = []
    for i in range(rounds):
        cam = cameras[i % len(cameras)]
        for kind in times:
            Records.meets_edge = EVERY if kind == "every region clipped" else EDGE
            ctx.finish()
            start = time.perf_counter()
            if kind == "std":
                r.std(cam, viewport)
            else:
                records = r.capture(cam, viewport, normals=False, ids=False)
            ctx.finish()
            times[kind].append(time.perf_counter() - start)
        edges.append(int((records.visible & records.meets_edge).sum()))
    Records.meets_edge = EDGE
    std, every = np.array(times["std"]), np.array(times["every region clipped"])
    print(
        f"{ctx.info['GL_RENDERER']}; {scene.count} objects; {viewport[0]}x{viewport[1]}; regions on the edge "
        f"per camera: {edges[: len(cameras)]}; ms, medians of {rounds}"
    )
    for kind, t in times.items():
        t = np.array(t)
        print(
            f"{kind:22s} {np.median(t) * 1e3:7.1f}  x STD {np.median(t / std):.2f}  "
            f"x every-clipped {np.median(t / every):.3f}"
        )
    r.release()


if __name__ == "__main__":
    main()
