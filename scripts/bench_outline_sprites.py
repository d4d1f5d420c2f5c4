"""Composites with sprites over the projected outlines of B_world (the default) and over the
whole B_viewport rectangles, in turns on one capture, in one process.

    python scripts/bench_outline_sprites.py [SCENE [WxH [ROUNDS [MODES]]]]   (default: demo 1024x1024 11)

Prints per mode the medians of both, the median of their ratios, and how many pixels of the
two images differ (none should). docs/performance/modes.md, "Sprites over the projected outline of B_world".
"""

from __future__ import annotations

import sys
import time

import numpy as np

from rtta.gl.context import create_headless_context
from rtta.passes.composite import CompositePass, Style
from rtta.renderer.renderer import Renderer
from rtta.scene.camera import Camera
from rtta.scene.loader import load_scene_or_demo

RENDER = CompositePass.render


def _rectangles(self, **kw):
    return RENDER(self, **{**kw, "eye": None})  # no eye: B_viewport rectangles


def main() -> None:
    args = sys.argv[1:] + [None] * 4
    ctx = create_headless_context()
    scene = load_scene_or_demo(None if args[0] in (None, "demo") else args[0])
    viewport = tuple(int(v) for v in (args[1] or "1024x1024").split("x"))
    rounds = int(args[2] or 11)
    modes = (args[3] or "sprites,ghosted,ghosted-ao,transparent").split(",")
    r = Renderer(ctx, scene)
    focus = {0, scene.count // 2}
    r.capture(Camera.orbit(scene.center, scene.radius, 30, 20, 2.2), viewport, focus=focus)
    print(
        f"{ctx.info['GL_RENDERER']}; {scene.count} objects; {viewport[0]}x{viewport[1]}; "
        f"composite ms, medians of {rounds}"
    )
    for mode in modes:
        times: dict[str, list[float]] = {"rectangles": [], "outlines": []}
        images = {}
        for _ in range(rounds):
            for kind in times:
                CompositePass.render = _rectangles if kind == "rectangles" else RENDER
                r.composite(mode, Style(focus=focus))  # untimed: the same state for both
                ctx.finish()
                start = time.perf_counter()
                images[kind] = r.composite(mode, Style(focus=focus)).read()[0]
                ctx.finish()
                times[kind].append(time.perf_counter() - start)
        CompositePass.render = RENDER
        a, b = np.array(times["rectangles"]), np.array(times["outlines"])
        differ = int(np.any(images["rectangles"] != images["outlines"], axis=-1).sum())
        print(
            f"{mode:12s} rectangles {np.median(a) * 1e3:6.1f}  outlines {np.median(b) * 1e3:6.1f}  "
            f"ratio {np.median(b / a):.3f}  pixels that differ {differ}"
        )
    r.release()


if __name__ == "__main__":
    main()
