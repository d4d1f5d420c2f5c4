"""Where a frame's GPU time goes: GL_TIMESTAMP queries before and after STD, the capture, each
compositing draw and (--stages) every compute dispatch by program, over FRAMES frames of MODE on
SCENE; GPU ms (between the two timestamps, so nested calls are counted in each) against the CPU's
wall ms for the same calls.
python scripts/gpu_timers.py [SCENE] [--mode ghosted] [--frames 10] [--size 1280x720] [--stages]"""

from __future__ import annotations

import argparse
import ctypes
import time

import moderngl
import numpy as np

from rtta.gl import glraw, glsl
from rtta.gl.context import shared_context
from rtta.passes import blend_tiles, capture, composite, post, sprites
from rtta.renderer.renderer import Renderer, Settings
from rtta.scene.camera import Camera
from rtta.scene.loader import load_scene_or_demo

GL_TIMESTAMP = 0x8E28
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
            q = (ctypes.c_uint * 2)()
            gl.glGenQueries(2, q)
            gl.glQueryCounter(q[0], GL_TIMESTAMP)
            t0 = time.perf_counter()
            try:
                return fn(*args, **kwargs)
            finally:
                wall = time.perf_counter() - t0
                gl.glQueryCounter(q[1], GL_TIMESTAMP)
                key = name(args, kwargs) if callable(name) else name
                self.pending.append((key, (q[0], q[1]), wall))

        return run

    def collect(self) -> None:
        gl = glraw._lib()
        for key, qs, wall in self.pending:
            ns = [ctypes.c_uint64(0), ctypes.c_uint64(0)]
            for q, t in zip(qs, ns, strict=True):
                gl.glGetQueryObjectui64v(q, GL_QUERY_RESULT, ctypes.byref(t))
            gl.glDeleteQueries(2, (ctypes.c_uint * 2)(*qs))
            self.gpu.setdefault(key, []).append((ns[1].value - ns[0].value) / 1e6)
            self.wall.setdefault(key, []).append(wall * 1e3)
        self.pending.clear()


def wrap_dispatches(timers: Timers) -> None:
    """Every compute dispatch timed under its program's file and defines."""
    names: dict[str, str] = {}
    load = glsl.load

    def named_load(name: str, **defines):
        source = load(name, **defines)
        shown = " ".join(f"{k}={v}" for k, v in defines.items() if k in ("STAGE", "OFFSETS"))
        names[source] = f"compute {name.split('.')[0]} {shown}".strip()
        return source

    glsl.load = named_load
    programs: dict[int, str] = {}
    make = moderngl.Context.compute_shader

    def compute_shader(self, source, *args, **kwargs):
        program = make(self, source, *args, **kwargs)
        programs[id(program)] = names.get(source, "compute ?")
        return program

    moderngl.Context.compute_shader = compute_shader
    name = lambda args, kw: programs.get(id(args[0]), "compute ?")  # noqa: E731
    moderngl.ComputeShader.run = timers.wrap(name, moderngl.ComputeShader.run)
    moderngl.ComputeShader.run_indirect = timers.wrap(name, moderngl.ComputeShader.run_indirect)


def main() -> None:
    p = argparse.ArgumentParser()
    p.add_argument("scene", nargs="?")
    p.add_argument("--mode", default="ghosted")
    p.add_argument("--frames", type=int, default=10)
    p.add_argument("--size", default="1280x720")
    p.add_argument("--sync", action="store_true", help="finish the GPU's queue before each timed call")
    p.add_argument("--no-hull", action="store_true", help="sprites over B_viewport's rectangle only")
    p.add_argument("--stages", action="store_true", help="also every compute dispatch, by program")
    p.add_argument("--parameterize", default="auto", choices=("auto", "cpu", "gpu"))
    p.add_argument("--fused-max", type=int, default=None, help="objects up to which Algorithm 1 runs in one work group")
    p.add_argument(
        "--blends", default="auto", help="comma-separated Settings.blend values, one table each; compute:N: SPAN N"
    )
    a = p.parse_args()
    ctx = shared_context()
    scene = load_scene_or_demo(a.scene)
    viewport = tuple(int(v) for v in a.size.split("x"))
    r = Renderer(ctx, scene, Settings(parameterize=a.parameterize))
    r.atlas_sizing = "ahead"  # as the viewer and the benches draw
    if a.fused_max is not None and r.on_gpu:
        r._gpu_atlas.fused_max = a.fused_max  # type: ignore[union-attr]  (on_gpu: a GpuParameterize)
    style = composite.Style(focus={0, scene.count // 2})
    timers = Timers(ctx.finish if a.sync else None)
    if a.no_hull:
        sprites.worth_outlines = lambda records, ids: False
    capture.CapturePass.render = timers.wrap("capture", capture.CapturePass.render)
    capture.StdPass.render = timers.wrap("std", capture.StdPass.render)
    kind = lambda args, kw: f"composite {args[2].kind.value}" + ("+upsample" if args[2].upsample else "")  # noqa: E731
    sprites.SpritePass._run = timers.wrap(kind, sprites.SpritePass._run)
    listed = lambda args, kw: f"composite listed {args[2].kind.value}"  # noqa: E731
    sprites.SpritePass.draw_listed = timers.wrap(listed, sprites.SpritePass.draw_listed)
    post.AtlasPostPass.render = timers.wrap("post (AO, edges)", post.AtlasPostPass.render)
    Renderer.parameterize = timers.wrap("parameterize", Renderer.parameterize)
    Renderer.composite = timers.wrap("composite (all)", Renderer.composite)
    blend_tiles.TileBlend.draw = timers.wrap("composite blend_tiles", blend_tiles.TileBlend.draw)
    if a.stages:
        wrap_dispatches(timers)
    for blend in a.blends.split(","):
        r.settings.blend, _, span = blend.partition(":")  # type: ignore[assignment]
        blend_tiles.SPAN = int(span or blend_tiles.SPAN)
        if r._composite is not None and r._composite._gpu is not None:
            r._composite._gpu._tiles = None  # made again with this SPAN
        frames(a, ctx, r, scene, style, timers, viewport, f"blend {blend}")
    r.release()


def frames(a, ctx, r, scene, style, timers: Timers, viewport, label: str) -> None:
    """Frames of the mode, then a table of GPU and wall ms per timed call."""
    timers.gpu.clear()
    timers.wall.clear()
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
        + f", {label}"
    )
    print(f"{'call':40s} {'GPU ms':>8s} {'wall ms':>8s} {'calls':>6s}")
    for key in sorted(timers.wall, key=lambda k: -np.sum(timers.wall[k])):
        g = timers.gpu.get(key)
        n = len(timers.wall[key]) / a.frames
        gpu = f"{np.median(g) * n:8.2f}" if g else f"{'':8s}"
        print(f"{key:40s} {gpu} {np.median(timers.wall[key]) * n:8.2f} {n:6.0f}")


if __name__ == "__main__":
    main()
