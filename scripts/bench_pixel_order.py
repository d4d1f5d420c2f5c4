"""Where the `transparent` composite's time goes, pass by pass (each timed with a finish): per-
pixel order with the first surfaces fetched (where the driver can), with every surface a list
node, and object order, in turns on one capture.
python scripts/bench_pixel_order.py [SCENE] [--frames 7] [--size 1024x1024]"""

from __future__ import annotations

import argparse
import time

import numpy as np

from rtta.gl.context import shared_context
from rtta.passes import composite, oit, sprites
from rtta.renderer.renderer import Renderer
from rtta.scene.camera import Camera
from rtta.scene.loader import load_scene_or_demo


def timed(ctx, times: dict, way: list, name, fn):
    def run(*args, **kwargs):
        ctx.finish()
        t0 = time.perf_counter()
        out = fn(*args, **kwargs)
        ctx.finish()
        key = name(args, kwargs) if callable(name) else name
        times.setdefault((way[0], key), []).append(time.perf_counter() - t0)
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
    r.capture(
        Camera.orbit(scene.center, scene.radius, 30.0, 20.0, 2.2),
        tuple(int(v) for v in a.size.split("x")),
        focus=focus,
        ids=False,
    )
    r.composite("transparent", composite.Style(focus=focus))
    ways = {"lists": oit.PixelOrderPass(ctx, fetch=False)}
    if oit.first_fetched(ctx):
        ways = {"fetched": oit.PixelOrderPass(ctx, fetch=True), **ways}
    times: dict[tuple[str, str], list[float]] = {}
    way = [""]
    draw_name = lambda args, kw: args[2].kind.value  # noqa: E731  (the SpriteDraw of SpritePass._run)
    sprites.SpritePass._run = timed(ctx, times, way, draw_name, sprites.SpritePass._run)
    for method in ("begin", "collect_into", "resolve"):
        setattr(oit.PixelOrderPass, method, timed(ctx, times, way, method, getattr(oit.PixelOrderPass, method)))
    for _ in range(a.frames):
        for name, order in [*((w, "pixel") for w in ways), ("object", "object")]:
            way[0] = name
            if order == "pixel":
                r._composite._pixel_order = ways[name]
            t0 = time.perf_counter()
            r.composite("transparent", composite.Style(focus=focus, order=order))
            ctx.finish()
            times.setdefault((name, "composite"), []).append(time.perf_counter() - t0)
    for name in [*ways, "object"]:
        print(
            f"{name:8s} "
            + ", ".join(f"{k} {1e3 * np.median(v):.2f}" for (w, k), v in times.items() if w == name)
            + " ms"
        )
    for p_ in ways.values():
        p_.release()


if __name__ == "__main__":
    main()
