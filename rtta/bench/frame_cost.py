"""What a frame costs the CPU and the GPU, per path of Algorithm 1 (issue 43's measure).

"Python" is the time a frame spends in Python and numpy outside calls into moderngl and
raw GL (cProfile's own time of every function but those), as the issue measures it; on a
machine of two cores a moment the driver's threads take the CPU from Python counts as
Python's. "GL calls" is the time inside those calls (llvmpipe does vertex work there); "wall"
is the frame with the GPU finished; the GPU's time per stage comes from GL_TIME_ELAPSED
queries around the parameterize + capture calls and the composite call (queries of one kind
cannot nest, so the stages are timed one after the other, in frames of their own). The CPU
and GPU paths take turns within each round, so a slow phase of a shared machine hits both.
"""

from __future__ import annotations

import cProfile
import pstats
import time

import numpy as np

from ..outputs import write_text
from ..passes.style import ModeName, Style
from ..renderer.renderer import Renderer
from ..renderer.settings import Settings
from ..scene.camera import Camera

PATHS = ("cpu", "gpu")
RAW_GL = ("glraw.py", "indirect.py")  # rtta.gl's ctypes calls (cProfile counts a ctypes call as its caller's time)


def is_gl(file: str, name: str) -> bool:
    """Whether a profiled function is a call into GL (moderngl's C methods, rtta.gl's ctypes wrappers)."""
    return "mgl." in name or "moderngl" in file or file.endswith(RAW_GL) or "CFuncPtr" in name


def _python_ms(stats: pstats.Stats, frames: int) -> tuple[float, float]:
    """(outside GL, in GL) ms per frame from a profile of `frames` frames."""
    inside = outside = 0.0
    for (file, _, name), row in stats.stats.items():  # type: ignore[attr-defined]
        own = row[2]
        if is_gl(file, name):
            inside += own
        else:
            outside += own
    return outside / frames * 1e3, inside / frames * 1e3


class FrameLoop:
    """A renderer drawing `mode` frames of an orbit, as the viewer does (sizing "ahead")."""

    def __init__(self, ctx, scene, viewport: tuple[int, int], path: str, mode: ModeName = "ghosted") -> None:
        self.ctx, self.scene, self.viewport = ctx, scene, viewport
        self.mode: ModeName = mode
        self.renderer = Renderer(ctx, scene, Settings(parameterize=path))  # type: ignore[arg-type]
        self.renderer.atlas_sizing = "ahead"
        self.style = Style(focus={0, scene.count // 2})
        self.turn = 0
        self.query = None

    def frame(self) -> None:
        r, scene = self.renderer, self.scene
        cam = Camera.orbit(scene.center, scene.radius, 30.0 + 0.25 * self.turn, 20.0, 2.2)
        self.turn += 1
        r.capture(cam, self.viewport, normals=r.needs_normals(self.mode), ids=False)
        r.composite(self.mode, self.style)

    def profiled(self, frames: int) -> dict:
        """Python and GL ms of each frame under cProfile (their medians: a frame in which the
        driver's threads took the CPU from Python is an outlier), and the wall ms without it."""
        self.ctx.finish()
        t0 = time.perf_counter()
        for _ in range(frames):
            self.frame()
        self.ctx.finish()
        wall = (time.perf_counter() - t0) / frames * 1e3
        each = []
        for _ in range(frames):
            prof = cProfile.Profile()
            prof.enable()
            self.frame()
            prof.disable()
            each.append(_python_ms(pstats.Stats(prof), 1))
        self.ctx.finish()
        python, gl = np.median(np.array(each), axis=0)
        return {"python_ms": float(python), "gl_call_ms": float(gl), "wall_ms": wall}

    def gpu_ms(self, frames: int) -> dict:
        """GPU ms per frame of parameterize + capture, and of compositing (timer queries)."""
        r, out = self.renderer, {"capture": [], "composite": []}
        q = self.query = self.query or self.ctx.query(time=True)  # one per loop (moderngl cannot free one)
        for _ in range(frames):
            cam = Camera.orbit(self.scene.center, self.scene.radius, 30.0 + 0.25 * self.turn, 20.0, 2.2)
            self.turn += 1
            with q:
                r.capture(cam, self.viewport, normals=r.needs_normals(self.mode), ids=False)
            out["capture"].append(q.elapsed / 1e6)
            with q:
                r.composite(self.mode, self.style)
            out["composite"].append(q.elapsed / 1e6)
        return {f"gpu_{k}_ms": float(np.median(v)) for k, v in out.items()}

    def release(self) -> None:
        self.renderer.release()


def frame_costs(
    ctx, scene, viewport: tuple[int, int], mode: ModeName = "ghosted", frames: int = 5, rounds: int = 2
) -> dict:
    """Per path: Python (outside GL), GL-call and wall ms per frame, medians over `rounds`
    rounds in which the paths take turns (and the GPU path's wall over the CPU path's, paired
    within a round), and the GPU ms per stage."""
    loops = {path: FrameLoop(ctx, scene, viewport, path, mode) for path in PATHS}
    try:
        for loop in loops.values():  # warm up: programs built, buffers and the atlas grown
            for _ in range(3):
                loop.frame()
        runs: dict[str, list[dict]] = {path: [] for path in PATHS}
        for _ in range(rounds):
            for path, loop in loops.items():
                runs[path].append(loop.profiled(frames))
        row: dict = {"objects": scene.count, "mode": mode}
        paired = [g["wall_ms"] / c["wall_ms"] for g, c in zip(runs["gpu"], runs["cpu"], strict=True)]
        row["gpu_over_cpu"] = float(np.median(paired))  # wall, paired within each round
        for path, loop in loops.items():
            for key in ("python_ms", "gl_call_ms", "wall_ms"):
                row[f"{path}_{key}"] = float(np.median([run[key] for run in runs[path]]))
            row.update({f"{path}_{k}": v for k, v in loop.gpu_ms(frames).items()})
        return row
    finally:
        for loop in loops.values():
            loop.release()


def print_costs(rows: list[dict], renderer: str, viewport: tuple[int, int], header: bool = True) -> None:
    """The table: per scene and path, Python / GL calls / wall / GPU capture / GPU composite ms."""
    if header:
        print(f"\nFrame cost per path ({renderer}, {viewport[0]}x{viewport[1]}, medians; Python = outside GL calls)")
        heads = (("objects", 8), ("mode", 10), ("path", 4), ("Python", 8), ("GL calls", 9), ("wall", 8))
        print(" ".join(f"{name:>{w}}" for name, w in heads) + f" {'GPU cap':>8} {'GPU comp':>9} {'gpu/cpu':>8}")
    for r in rows:
        for path in PATHS:
            print(
                f"{r['objects']:>8} {r['mode']:>10} {path:>4} {r[f'{path}_python_ms']:>8.2f} "
                f"{r[f'{path}_gl_call_ms']:>9.2f} {r[f'{path}_wall_ms']:>8.2f} "
                f"{r[f'{path}_gpu_capture_ms']:>8.2f} {r[f'{path}_gpu_composite_ms']:>9.2f}"
                + (f" {r['gpu_over_cpu']:>7.2f}x" if path == "gpu" else "")
            )


def run_frame(
    viewport: tuple[int, int], parts: list[int], files, modes: list[ModeName], frames: int, json_path: str | None
) -> int:
    """`rtta bench frame`: the cost table for generated assemblies of `parts` and `files`."""
    import json
    import tempfile
    from pathlib import Path

    from ..gl.context import shared_context
    from ..scene.generators.assembly import write_assembly
    from ..scene.loader import load_scene

    ctx = shared_context()
    renderer = str(ctx.info["GL_RENDERER"])
    rows = []
    with tempfile.TemporaryDirectory(prefix="rtta-frame-") as tmp:
        paths = [write_assembly(Path(tmp) / f"assembly_{n}.glb", n) for n in parts] + [Path(f) for f in files]
        for path in paths:
            scene = load_scene(path, cache=False)
            for mode in modes:
                rows.append({"scene": path.name, **frame_costs(ctx, scene, viewport, mode, frames, rounds=3)})
                print_costs(rows[-1:], renderer, viewport, header=len(rows) == 1)
    if json_path:
        write_text(json_path, json.dumps({"renderer": renderer, "viewport": list(viewport), "rows": rows}, indent=1))
    return 0
