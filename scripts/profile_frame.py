"""Where a frame's wall time goes on the CPU side: FRAMES frames of MODE on SCENE (the demo
by default), each capture + composite + finish, under cProfile; prints ms per frame with and
without the profiler and the functions with the most cumulative time.
python scripts/profile_frame.py [SCENE] [--mode ghosted-ao] [--frames 200] [--size 1024x1024] [--sizing ahead]"""

from __future__ import annotations

import argparse
import cProfile
import pstats
import time

from rtta.gl.context import shared_context
from rtta.passes.composite import Style
from rtta.renderer.renderer import Renderer
from rtta.scene.camera import Camera
from rtta.scene.loader import load_scene_or_demo


def main() -> None:
    p = argparse.ArgumentParser()
    p.add_argument("scene", nargs="?")
    p.add_argument("--mode", default="ghosted-ao")
    p.add_argument("--frames", type=int, default=200)
    p.add_argument("--size", default="1024x1024")
    p.add_argument("--top", type=int, default=30)
    p.add_argument("--sizing", default="ahead", choices=("ahead", "exact"), help="the atlas's (ahead: as the viewer)")
    a = p.parse_args()
    ctx = shared_context()
    scene = load_scene_or_demo(a.scene)
    viewport = tuple(int(v) for v in a.size.split("x"))
    r = Renderer(ctx, scene)
    r.atlas_sizing = a.sizing
    style = Style(focus={0, scene.count // 2})

    def frames(n: int) -> float:
        t0 = time.perf_counter()
        for i in range(n):
            cam = Camera.orbit(scene.center, scene.radius, 30.0 + i * 0.5, 20.0, 2.2)
            r.capture(cam, viewport)
            r.composite(a.mode, style)
            ctx.finish()
        return (time.perf_counter() - t0) / n * 1e3

    frames(10)
    print(f"{ctx.info['GL_RENDERER']}: {a.mode}, {scene.count} objects, {a.size}: {frames(a.frames):.3f} ms a frame")
    prof = cProfile.Profile()
    prof.enable()
    ms = frames(a.frames)
    prof.disable()
    print(f"under cProfile: {ms:.3f} ms a frame")
    pstats.Stats(prof).sort_stats("cumulative").print_stats(a.top)
    pstats.Stats(prof).sort_stats("tottime").print_stats(a.top)
    r.release()


if __name__ == "__main__":
    main()
