"""Window creation and the main loop; `--bench` orbits through every mode and prints a table."""

from __future__ import annotations

import time
from pathlib import Path

import numpy as np

from rtta.errors import RttaError
from rtta.scene.camera import DEFAULT_ORBIT
from rtta.scene.loader import load_scene_or_demo

from .orbit import DEGREES_PER_PIXEL
from .state import VIEW_MODES

STAGE_COLUMNS = ("parameterize", "capture", "post", "composite", "std", "ui")


def create_window(size: tuple[int, int], visible: bool = True):
    """A pyglet window with an OpenGL 4.3 core context, made current for moderngl. Made with
    signals held (rtta.outputs): a Ctrl-C inside the native context creation was turned into
    'cannot open a window' by pyglet, or crashed the process (SIGSEGV), about 1 in 40 runs
    interrupted at 0.8 to 1.6 s under load; it is raised once the window is made."""
    import moderngl_window as mglw
    from moderngl_window.context.pyglet.window import Window

    from rtta import outputs

    with outputs.signals_held():
        try:
            wnd = Window(title="rtta", gl_version=(4, 3), size=size, vsync=False, resizable=True, visible=visible)
        except Exception as exc:
            raise RttaError(f"cannot open a window with OpenGL 4.3 ({type(exc).__name__}: {exc})") from None
        mglw.activate_context(window=wnd)
    return wnd


def run(
    scene_path: str | None,
    *,
    size: tuple[int, int],
    mode: str,
    screenshot_dir: Path | None = None,
    bench: int = 0,
    load: dict | None = None,
    bench_modes: tuple[str, ...] | None = None,
    navigation_fps: float | None = None,
    start=None,
) -> int:
    """`load`: the loader's options (smoothing), for this scene and those opened later;
    `navigation_fps`: the frame rate fast navigation keeps while the camera moves (0: off;
    None: the viewer's default); `start`: the first view asked on the command line (start.Start)."""
    from .app import Viewer

    scene = load_scene_or_demo(scene_path, **(load or {}))  # a bad file on the command line: one line, exit 2
    wnd = create_window(size)
    app = Viewer(wnd, scene, screenshot_dir=screenshot_dir, mode=mode, load=load)
    if navigation_fps is not None:
        app.state.navigation_fps = navigation_fps
    try:
        if start is not None:
            from .start import apply_start

            apply_start(app, start)
        if bench:
            print_bench(app, bench, bench_modes)
            return 0
        while not wnd.is_closing:
            app.frame()
            wnd.swap_buffers()
    finally:
        app.release()
        wnd.destroy()
    return 0


def _orbit_frames(app, frames: int, turn: float = 360.0, left: list | None = None) -> list[float]:
    """Seconds per frame (swap included) while the camera orbits by `turn` degrees in all,
    so every frame re-captures; `left` gets the parts fast navigation left out of each."""
    times = []
    for _ in range(frames):
        app.orbit.rotate(turn / frames / DEGREES_PER_PIXEL, 0.0)
        t0 = time.perf_counter()
        app.frame()
        app.wnd.swap_buffers()
        times.append(time.perf_counter() - t0)
        if left is not None:
            left.append(app.left_out)
    return times


def bench_mode(app, mode: str, frames: int, warmup: int = 5) -> dict:
    """Frames per second as a user gets them (stage timing off), then the split of a frame
    into stages from a second run with stage timing on (which waits for the GPU per stage)."""
    app.state.choose_mode(mode)  # as chosen: a ghosted mode is timed as itself, never the first-view solid
    app.state.measure = False
    _orbit_frames(app, warmup)
    app.orbit.az = DEFAULT_ORBIT[0]  # every mode sees the same views: one full turn
    left: list[int] = []
    ms = 1e3 * float(np.mean(_orbit_frames(app, frames, left=left)))
    app.state.measure = True
    _orbit_frames(app, 2)
    app.orbit.az = DEFAULT_ORBIT[0]
    stages = {k: [] for k in STAGE_COLUMNS}
    for _ in range(frames):
        _orbit_frames(app, 1, 360.0 / frames)
        for k in STAGE_COLUMNS:
            stages[k].append(app.stats.stage_ms.get(k, 0.0))
    share = float(np.mean(left)) / max(1, app.renderer.scene.count)
    return {
        "mode": mode,
        "ms": ms,
        "fps": 1e3 / ms,
        "left_out": share,
        **{k: float(np.mean(v)) for k, v in stages.items()},
    }


def print_bench(app, frames: int, modes: tuple[str, ...] | None = None) -> list[dict]:
    import pyglet

    w, h = app.wnd.buffer_size
    vp = app.viewport
    print(f"renderer: {app.ctx.info['GL_RENDERER']}")
    kind = "headless window (EGL)" if pyglet.options["headless"] else "window"
    print(
        f"scene: {app.scene_label} ({app.renderer.scene.count} objects, {app.renderer.scene.vertex_count} "
        f"vertices); {kind} {w}x{h}, composite {vp[0]}x{vp[1]}, atlas view shown; {frames} frames per mode, "
        "one full orbit"
    )
    fps = app.state.navigation_fps
    print(
        "stage columns: ms per stage from a second run that waits for the GPU after each stage; left out: parts "
        "fast navigation left out while orbiting (share of all, mean over the fps run; "
        + (f"--navigation-fps {fps:g})" if fps > 0 else "off: --navigation-fps 0)")
    )
    print("| mode | fps | frame ms | left out | " + " | ".join(STAGE_COLUMNS) + " |")
    print("|---" * (4 + len(STAGE_COLUMNS)) + "|")
    rows = []
    for mode in modes or VIEW_MODES:
        r = bench_mode(app, mode, frames)
        rows.append(r)
        print(
            f"| {mode} | {r['fps']:.1f} | {r['ms']:.1f} | {100 * r['left_out']:.0f}% | "
            + " | ".join(f"{r[k]:.1f}" for k in STAGE_COLUMNS)
            + " |"
        )
    return rows
