"""Back faces of closed parts culled (the default) against every object drawn double-sided
(Settings(cull_closed=False)): STD, the capture and whole `ghosted` and `ghosted-ao` frames,
the two renderers in turns within each round, one process.

    python scripts/bench_culling.py [SCENE [WxH [ROUNDS]]]     (default: demo 1024x1024 9)

Prints the medians, culled over double-sided (paired per round), and each kind's frames as
multiples of its own STD. docs/performance/capture.md, "Back faces of closed parts culled".
"""

from __future__ import annotations

import sys
import time

import numpy as np

from rtta.gl.context import create_headless_context
from rtta.passes.composite import Style
from rtta.renderer.renderer import Renderer, Settings
from rtta.scene.camera import Camera
from rtta.scene.loader import load_scene_or_demo


def main() -> None:
    args = sys.argv[1:] + [None] * 3
    ctx = create_headless_context()
    scene = load_scene_or_demo(None if args[0] in (None, "demo") else args[0])
    viewport = tuple(int(v) for v in (args[1] or "1024x1024").split("x"))
    rounds = int(args[2] or 9)
    start = time.perf_counter()
    closed = int(scene.closed.sum())
    print(
        f"renderer: {ctx.info['GL_RENDERER']}; {scene.count:,} objects, {len(scene.indices) // 3:,} triangles, "
        f"{closed:,} closed (found in {(time.perf_counter() - start) * 1e3:.0f} ms); viewport "
        f"{viewport[0]}x{viewport[1]}, camera 30,20,2.2, focus objects 0 and n/2, {rounds} rounds"
    )
    cam = Camera.orbit(scene.center, scene.radius, 30, 20, 2.2)
    focus = {0, scene.count // 2}
    kinds = {"double-sided": Renderer(ctx, scene, Settings(cull_closed=False)), "culled": Renderer(ctx, scene)}

    def frame(r: Renderer, mode: str) -> None:
        r.capture(cam, viewport, focus=focus, normals=r.needs_normals(mode), ids=False)
        r.composite(mode, Style(focus=focus))

    stages = {
        "std": lambda r: r.std(cam, viewport),
        "capture": lambda r: r.capture(cam, viewport, normals=False, ids=False),
        "ghosted": lambda r: frame(r, "ghosted"),
        "ghosted-ao": lambda r: frame(r, "ghosted-ao"),
    }
    times = {(k, s): [] for k in kinds for s in stages}
    for _ in range(rounds):
        for kind, r in kinds.items():
            for stage, fn in stages.items():
                fn(r)
                ctx.finish()
                t0 = time.perf_counter()
                fn(r)
                ctx.finish()
                times[(kind, stage)].append((time.perf_counter() - t0) * 1e3)
    print(f"{'':12s} {'double-sided ms':>16s} {'culled ms':>10s} {'culled / double-sided':>22s}")
    for stage in stages:
        a, b = (np.array(times[(k, stage)]) for k in kinds)
        print(f"{stage:12s} {np.median(a):16.1f} {np.median(b):10.1f} {np.median(b / a):22.3f}")
    for kind in kinds:
        std = np.array(times[(kind, "std")])
        print(
            f"{kind}, x its STD: "
            + ", ".join(f"{s} {np.median(np.array(times[(kind, s)]) / std):.2f}" for s in stages if s != "std")
        )
    for r in kinds.values():
        r.release()


if __name__ == "__main__":
    main()
