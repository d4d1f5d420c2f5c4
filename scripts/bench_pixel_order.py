"""Where the `transparent` composite's time goes, pass by pass (each timed with a finish),
in per-pixel order and in object order, on one capture.
python scripts/bench_pixel_order.py [SCENE] [--frames 7] [--size 1024x1024]"""

from __future__ import annotations

import argparse
import time

import numpy as np

from rtta.gl.context import shared_context
from rtta.passes import composite, oit
from rtta.renderer.renderer import Renderer
from rtta.scene.camera import Camera
from rtta.scene.loader import load_scene_or_demo


def timed(ctx, times: dict, name: str, fn):
    def run(*args, **kwargs):
        ctx.finish()
        t0 = time.perf_counter()
        out = fn(*args, **kwargs)
        ctx.finish()
        times.setdefault(name(args, kwargs) if callable(name) else name, []).append(time.perf_counter() - t0)
        return out
    return run


def main() -> None:
    p = argparse.ArgumentParser()
    p.add_argument("scene", nargs="?")
    p.add_argument("--frames", type=int, default=7)
    p.add_argument("--size", default="1024x1024")
    a = p.parse_args()
    ctx = shared_context()
    scene = load_scene_or_demo(a.scene)
    focus = {0, scene.count // 2}
    r = Renderer(ctx, scene)
    r.capture(Camera.orbit(scene.center, scene.radius, 30.0, 20.0, 2.2),
              tuple(int(v) for v in a.size.split("x")), focus=focus, ids=False)
    times: dict[str, list[float]] = {}
    draw_name = lambda args, kw: "+".join(k for k, v in kw.items() if v is True) or "draw"   # noqa: E731
    composite.CompositePass._draw_run = timed(ctx, times, draw_name, composite.CompositePass._draw_run)
    oit.PixelOrderPass.resolve = timed(ctx, times, "resolve", oit.PixelOrderPass.resolve)
    for order in ("pixel", "object"):
        for _ in range(a.frames):
            t0 = time.perf_counter()
            r.composite("transparent", composite.Style(focus=focus, order=order))
            ctx.finish()
            times.setdefault("composite", []).append(time.perf_counter() - t0)
        print(f"{order:6s} " + ", ".join(f"{k} {1e3 * np.median(v):.2f}" for k, v in times.items()) + " ms")
        times.clear()


if __name__ == "__main__":
    main()
