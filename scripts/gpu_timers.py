"""Where a frame's GPU time goes: GL_TIME_ELAPSED queries around STD, the capture and each
compositing draw (queries of one kind cannot nest, so the stages are timed one by one), over
FRAMES frames of MODE on SCENE; GPU ms against the CPU's wall ms for the same calls.
python scripts/gpu_timers.py [SCENE] [--mode ghosted] [--frames 10] [--size 1280x720]"""

from __future__ import annotations

import argparse
import ctypes
import time

import numpy as np

from rtta.gl import glraw
from rtta.gl.context import shared_context
from rtta.passes import capture, composite, sprites
from rtta.renderer.renderer import Renderer
from rtta.scene.camera import Camera
from rtta.scene.loader import load_scene_or_demo

GL_TIME_ELAPSED = 0x88BF
GL_QUERY_RESULT = 0x8866


class Timers:
    """GPU and wall time per named call, the GPU's read back at the end (no stall per call)."""

    def __init__(self, sync=None) -> None:
        self.sync = sync  # called before each timed call (ctx.finish: nothing queued overlaps it)
        self.pending: list[tuple[str, int, float]] = []
        self.gpu: dict[str, list[float]] = {}
        self.wall: dict[str, list[float]] = {}

    def wrap(self, name, fn):
        def run(*args, **kwargs):
            if self.sync is not None:
                self.sync()
            gl = glraw._lib()
            q = ctypes.c_uint(0)
            gl.glGenQueries(1, ctypes.byref(q))
            gl.glBeginQuery(GL_TIME_ELAPSED, q)
            t0 = time.perf_counter()
            try:
                return fn(*args, **kwargs)
            finally:
                wall = time.perf_counter() - t0
                gl.glEndQuery(GL_TIME_ELAPSED)
                key = name(args, kwargs) if callable(name) else name
                self.pending.append((key, q.value, wall))

        return run

    def collect(self) -> None:
        gl = glraw._lib()
        for key, q, wall in self.pending:
            ns = ctypes.c_uint64(0)
            gl.glGetQueryObjectui64v(q, GL_QUERY_RESULT, ctypes.byref(ns))
            gl.glDeleteQueries(1, ctypes.byref(ctypes.c_uint(q)))
            self.gpu.setdefault(key, []).append(ns.value / 1e6)
            self.wall.setdefault(key, []).append(wall * 1e3)
        self.pending.clear()


def main() -> None:
    p = argparse.ArgumentParser()
    p.add_argument("scene", nargs="?")
    p.add_argument("--mode", default="ghosted")
    p.add_argument("--frames", type=int, default=10)
    p.add_argument("--size", default="1280x720")
    p.add_argument("--sync", action="store_true", help="finish the GPU's queue before each timed call")
    p.add_argument("--no-hull", action="store_true", help="sprites over B_viewport's rectangle only")
    a = p.parse_args()
    ctx = shared_context()
    scene = load_scene_or_demo(a.scene)
    viewport = tuple(int(v) for v in a.size.split("x"))
    r = Renderer(ctx, scene)
    style = composite.Style(focus={0, scene.count // 2})
    timers = Timers(ctx.finish if a.sync else None)
    if a.no_hull:
        sprites.worth_outlines = lambda records, ids: False
    capture.CapturePass.render = timers.wrap("capture", capture.CapturePass.render)
    capture.StdPass.render = timers.wrap("std", capture.StdPass.render)
    kind = lambda args, kw: f"composite {args[2].kind.value}" + ("+upsample" if args[2].upsample else "")  # noqa: E731
    sprites.SpritePass._run = timers.wrap(kind, sprites.SpritePass._run)
    for i in range(a.frames + 2):
        cam = Camera.orbit(scene.center, scene.radius, 30.0 + i * 0.5, 20.0, 2.2)
        t0 = time.perf_counter()
        r.capture(cam, viewport, normals=r.needs_normals(a.mode), ids=False)
        r.composite(a.mode, style)
        ctx.finish()
        frame = (time.perf_counter() - t0) * 1e3
        r.std(cam, viewport)
        ctx.finish()
        timers.collect()
        if i < 2:  # warm-up: programs made, buffers grown
            timers.gpu.clear()
            timers.wall.clear()
        else:
            timers.wall.setdefault("frame (capture + composite)", []).append(frame)
    print(
        f"{ctx.info['GL_RENDERER']}: {a.mode}, {scene.count} objects, {a.size}, medians of {a.frames} frames"
        + (", synced" if a.sync else "")
        + (", no outline sprites" if a.no_hull else "")
    )
    print(f"{'call':40s} {'GPU ms':>8s} {'wall ms':>8s} {'calls':>6s}")
    for key in sorted(timers.wall, key=lambda k: -np.sum(timers.wall[k])):
        g = timers.gpu.get(key)
        n = len(timers.wall[key]) / a.frames
        gpu = f"{np.median(g) * n:8.2f}" if g else f"{'':8s}"
        print(f"{key:40s} {gpu} {np.median(timers.wall[key]) * n:8.2f} {n:6.0f}")
    r.release()


if __name__ == "__main__":
    main()
