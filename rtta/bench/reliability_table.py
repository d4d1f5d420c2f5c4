"""`rtta bench reliability`: the extreme-camera sweep and the soak, as tables.

Figures come from the run; docs/reliability.md records them with the command and renderer.
"""

from __future__ import annotations

import json
import platform
import sys
import time

from ..errors import RttaError
from ..gl.context import shared_context
from ..outputs import write_text
from ..renderer.renderer import Renderer
from ..scene.generators.generate import random_scene
from .reliability import drift, soak, sweep


def _progress(label: str, total: int):
    """A one-line progress bar on stderr (only when it is a terminal)."""
    if not sys.stderr.isatty():
        return None
    step = max(1, total // 100)

    def show(done: int) -> None:
        if done % step == 0 or done == total:
            filled = int(30 * done / total)
            print(
                f"\r{label:>12} [{'#' * filled}{'.' * (30 - filled)}] {done}/{total}",
                end="",
                file=sys.stderr,
                flush=True,
            )
            if done == total:
                print(file=sys.stderr)

    return show


def _scenes(quick: bool) -> dict:
    """Name -> a function making the scene: the demo, a large generated scene, and a
    textured one (material atlas, REPEAT emulation and mip levels under the same extreme
    cameras). Only the scenes asked for are made."""
    from ..scene.generators.textured import textured_scene
    from ..scene.loader import load_scene_or_demo

    return {
        "demo": lambda: load_scene_or_demo(None),
        "random-2000": lambda: random_scene(200 if quick else 2000, seed=3, spread=40.0),
        "textured-64": lambda: textured_scene(64, seed=4),
    }


def run_reliability(
    sweep_frames: int,
    soak_frames: int,
    quick: bool = False,
    json_path: str | None = None,
    ctx=None,
    only: list[str] | None = None,
) -> int:
    """Sweep and soak on the demo, a generated 2,000-object scene and a textured scene (or
    the `only` ones); exit 1 on any failure."""
    makers = _scenes(quick)
    unknown = sorted(set(only or []) - set(makers))
    if unknown:
        raise RttaError(f"--scenes: unknown {', '.join(unknown)}; choose from {', '.join(makers)}")
    names = [name for name in makers if only is None or name in only]
    ctx = ctx or shared_context()
    renderer_name = str(ctx.info["GL_RENDERER"])
    print(
        f"renderer: {renderer_name}; cpu: {platform.processor() or platform.machine()}; "
        f"date: {time.strftime('%Y-%m-%d')}"
    )
    flags = " --quick" if quick else f" --sweep {sweep_frames} --soak {soak_frames}"
    flags += f" --scenes {','.join(only)}" if only else ""
    print(f"command: rtta bench reliability{flags}")
    report, failed = {"renderer": renderer_name, "scenes": []}, False
    print(
        f"{'scene':>12} {'objects':>7} {'sweep frames':>12} {'failed':>6} {'worst colour':>12} "
        f"{'worst depth':>11} {'s':>7} | {'soak frames':>11} {'RSS MiB':>15} {'drift':>7} "
        f"{'GL objects':>10} {'GL errors':>9} {'s':>7}"
    )
    for name in names:
        scene = makers[name]()
        r = Renderer(ctx, scene)
        t0 = time.perf_counter()
        sw = sweep(r, sweep_frames, seed=1, progress=_progress(f"{name} sweep", sweep_frames))
        t1 = time.perf_counter()
        samples, errors = soak(r, soak_frames, samples=20, seed=2, progress=_progress(f"{name} soak", soak_frames))
        t2 = time.perf_counter()
        rss_drift, objects_drift = drift(samples)
        r.release()
        start, end = samples[min(len(samples) - 1, len(samples) // 5)], samples[-1]
        objs = f"{sum(start.objects.values())}->{sum(end.objects.values())}"
        rss = f"{start.rss / 2**20:.0f}->{end.rss / 2**20:.0f}"
        print(
            f"{name:>12} {scene.count:>7} {sw.frames:>12} {len(sw.failures):>6} {sw.worst_color:>12.4f} "
            f"{sw.worst_depth:>11.2e} {t1 - t0:>7.1f} | {soak_frames:>11} {rss:>15} {rss_drift:>+7.1%} "
            f"{objs:>10} {len(errors):>9} {t2 - t1:>7.1f}"
        )
        for frame, kind, check in sw.failures[:5]:
            print(f"   failed sweep frame {frame} ({kind}): {check}")
        failed |= bool(sw.failures or errors) or abs(rss_drift) > 0.05 or any(objects_drift.values())
        report["scenes"].append(
            {
                "name": name,
                "objects": scene.count,
                "sweep_frames": sw.frames,
                "sweep_failures": len(sw.failures),
                "kinds": sw.kinds,
                "worst_color": sw.worst_color,
                "worst_depth": sw.worst_depth,
                "soak_frames": soak_frames,
                "rss_drift": rss_drift,
                "gl_objects_drift": objects_drift,
                "gl_errors": len(errors),
                "samples": [(s.frame, s.rss, s.targets, s.objects) for s in samples],
            }
        )
    print(
        "worst colour: smallest fraction of pixels within 3/255 of STD in any frame (ties between coincident "
        "surfaces of two objects count as equal); worst depth: largest |sprites - STD| window depth off "
        "silhouettes"
    )
    print(
        "RSS: first sample after warm-up (20% of the soak) -> last; drift: change of RSS without the render "
        "targets after warm-up (least-squares line through the samples, relative to their mean); GL objects "
        "counted with glIs* over every name handed out"
    )
    if json_path:
        write_text(json_path, json.dumps(report, indent=1))
    return 1 if failed else 0
