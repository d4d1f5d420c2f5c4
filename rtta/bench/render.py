"""`rtta bench capture|packing`: measured tables (median of frames, wall clock after glFinish).

Only figures from the run are printed; docs/performance/ records them with the command.
"""

from __future__ import annotations

import json
import os
import platform
import time
from collections.abc import Callable, Mapping
from pathlib import Path
from typing import Any, TypeVar

import numpy as np

from ..atlas.packing import pack_shelves
from ..atlas.parameterize import parameterize
from ..gl.context import shared_context
from ..outputs import write_text
from ..renderer.renderer import Renderer
from ..scene.camera import Camera, Projection
from ..scene.generators.generate import TABLE1, random_scene, table1_scene
from . import param_gpu


def shared_data() -> Path:
    """../shared/data beside the project (third-party scenes; RTTA_SHARED_DATA overrides)."""
    return Path(os.environ.get("RTTA_SHARED_DATA", Path.cwd().parent / "shared" / "data"))


def _median_ms(fn, frames: int, warmup: int = 2) -> float:
    for _ in range(warmup):
        fn()
    times = []
    for _ in range(frames):
        t0 = time.perf_counter()
        fn()
        times.append((time.perf_counter() - t0) * 1e3)
    return float(np.median(times))


K = TypeVar("K")


def _interleaved_ms(fns: Mapping[K, Callable[[], object]], rounds: int) -> dict[K, list[float]]:
    """ms of each function per round, the functions taking turns within a round: a slow
    phase of a shared machine (this VM swings by ±30% for seconds at a time) then hits every
    function of that round alike, and ratios taken within a round cancel it. Each turn is
    one untimed call, then one timed call, so that a function never pays for the caches
    the previous one left (steady frames of one mode, as in the viewer)."""
    times: dict[K, list[float]] = {name: [] for name in fns}
    for _ in range(rounds):
        for name, fn in fns.items():
            fn()
            t0 = time.perf_counter()
            fn()
            times[name].append((time.perf_counter() - t0) * 1e3)
    return times


def _gl_timed(ctx, fn):
    def run():
        fn()
        ctx.finish()

    return run


def capture_row(ctx, scene, viewport, frames: int, rtt: bool = True, projection: Projection = "perspective") -> dict:
    r = Renderer(ctx, scene)
    cam = Camera.orbit(scene.center, scene.radius, 30.0, 20.0, 2.2, projection=projection)
    view, proj = r.matrices(cam, viewport)
    corners, vpm = scene.box_corners(), proj @ view
    row = {"objects": scene.count, "vertices": scene.vertex_count}
    row["std_ms"] = _median_ms(_gl_timed(ctx, lambda: r.std(cam, viewport)), frames)
    visible = np.flatnonzero(r.parameterize(cam, viewport).visible)
    row["rtt_ms"] = (
        _median_ms(_gl_timed(ctx, lambda: r.rtt(cam, viewport, visible)), max(1, frames // 3), 1)
        if rtt
        else float("nan")
    )
    row["rtta_gs_ms"] = _median_ms(_gl_timed(ctx, lambda: r.capture(cam, viewport, "gs")), frames)
    row["rtta_vs_ms"] = (
        _median_ms(_gl_timed(ctx, lambda: r.capture(cam, viewport, "vs")), frames)
        if r.caps.vertex_layer
        else float("nan")
    )
    row["param_ms"] = _median_ms(lambda: parameterize(corners, vpm, viewport, border=1), frames * 5)
    row["atlas"] = list(r.parameterize(cam, viewport).atlas_size)
    r.release()
    return row


def param_scaling(counts, viewport, frames: int, projection: Projection = "perspective") -> list[dict]:
    out = []
    for n in counts:
        scene = random_scene(n, seed=7, spread=4.0 * np.cbrt(n))
        cam = Camera.orbit(scene.center, scene.radius, 30.0, 20.0, 2.2, projection=projection)
        vpm = cam.projection(viewport[0] / viewport[1]) @ cam.view(scene.origin)
        corners = scene.box_corners()
        out.append({"objects": n, "ms": _median_ms(lambda c=corners, m=vpm: parameterize(c, m, viewport), frames)})
    return out


def run_capture(
    viewport: tuple[int, int],
    quick: bool = False,
    json_path: str | None = None,
    ctx=None,
    projection: Projection = "perspective",
    full: bool = False,
) -> int:
    """Table 1's frame times (STD, RTT, RTTA both paths) and Algorithm 1's scaling, with a
    perspective (the paper's) or orthographic camera; Algorithm 1 on the CPU against the GPU
    path at 1k and 10k parts (--quick: 1k; full: and 100k)."""
    ctx = ctx or shared_context()
    renderer = str(ctx.info["GL_RENDERER"])
    frames = 3 if quick else 15
    rows = []
    for objects, vertices in TABLE1:
        if quick:
            vertices = min(vertices, 60000)
        rows.append(capture_row(ctx, table1_scene(objects, vertices), viewport, frames, projection=projection))
    counts = [100, 1000] if quick else [100, 300, 1000, 3000, 10000]
    scaling = param_scaling(counts, viewport, 5 if quick else 21, projection)
    _print_capture(rows, scaling, f"{renderer}; {projection}", viewport)
    paths = param_gpu.param_paths(ctx, param_gpu.counts_for(quick, full), viewport, frames)
    param_gpu.print_paths(paths)
    if json_path:
        write_text(
            json_path,
            json.dumps(
                {
                    "renderer": renderer,
                    "viewport": list(viewport),
                    "scenes": rows,
                    "param_scaling": scaling,
                    "paths": paths,
                },
                indent=1,
            ),
        )
    return 0


def _print_capture(rows, scaling, renderer, viewport) -> None:
    print(
        f"renderer: {renderer}; cpu: {platform.processor() or platform.machine()}; "
        f"viewport {viewport[0]}x{viewport[1]}; median ms per frame"
    )
    print(
        f"{'objects':>8} {'vertices':>9} {'STD':>8} {'RTT':>9} {'RTTA-GS':>8} {'RTTA-VS':>8} "
        f"{'param':>7} {'GS/STD':>7} {'VS/STD':>7} {'RTT/VS':>7}  atlas"
    )
    for r in rows:
        print(
            f"{r['objects']:>8} {r['vertices']:>9} {r['std_ms']:>8.2f} {r['rtt_ms']:>9.2f} "
            f"{r['rtta_gs_ms']:>8.2f} {r['rtta_vs_ms']:>8.2f} {r['param_ms']:>7.3f} "
            f"{r['rtta_gs_ms'] / r['std_ms']:>7.2f} {r['rtta_vs_ms'] / r['std_ms']:>7.2f} "
            f"{r['rtt_ms'] / r['rtta_vs_ms']:>7.2f}  {r['atlas']}"
        )
    print("parameterization + packing scaling:")
    print(f"{'objects':>8} {'ms':>8} {'ms/(n log2 n) x1e3':>20}")
    for s in scaling:
        n = s["objects"]
        print(f"{n:>8} {s['ms']:>8.3f} {s['ms'] / (n * np.log2(n)) * 1e3:>20.4f}")


def composite_row(
    ctx, name, scene, viewport, frames: int, settings=None, projection: Projection = "perspective"
) -> dict:
    """Full frame per mode (capture + post + composite) against STD at the default settings,
    plus ghosted-ao at full quality (AO and edges on every object, every region at scale 1)
    and transparent in object order (the default is per pixel), all taking turns within each round; the error of the
    default ghosted-ao against the full-quality one; a re-composite after a focus change
    against the full ghosted-ao frame."""
    from ..passes.composite import MODES, Style
    from ..renderer.renderer import Settings

    r = Renderer(ctx, scene, settings)
    full = Renderer(ctx, scene, Settings(border=r.settings.border))
    r.atlas_sizing = full.atlas_sizing = "ahead"  # as the viewer: no frame waits for the GPU to size the atlas
    cam = Camera.orbit(scene.center, scene.radius, 30.0, 20.0, 2.2, projection=projection)
    focus = {0, scene.count // 2}
    styles = {
        "full": Style(focus=focus, ao_objects="all", edge_objects="all"),
        "object": Style(focus=focus, order="object"),
    }

    def frame(renderer, mode, style):
        renderer.capture(cam, viewport, focus=style.focus, normals=renderer.needs_normals(mode), ids=False)
        return renderer.composite(mode, style)

    fns = {"std": _gl_timed(ctx, lambda: r.std(cam, viewport))}
    fns.update({mode: _gl_timed(ctx, lambda mode=mode: frame(r, mode, Style(focus=focus))) for mode in MODES})
    fns["ghosted-ao full"] = _gl_timed(ctx, lambda: frame(full, "ghosted-ao", styles["full"]))
    fns["transparent object"] = _gl_timed(ctx, lambda: frame(r, "transparent", styles["object"]))
    times = _interleaved_ms(fns, frames)
    std = np.array(times["std"])
    names = [n for n in fns if n != "std"]
    row = {
        "name": name,
        "objects": scene.count,
        "vertices": scene.vertex_count,
        "std_ms": float(np.median(std)),
        "modes": {n: float(np.median(times[n])) for n in names},
        "ratios": {n: float(np.median(np.array(times[n]) / std)) for n in names},
        "pixel_over_object": float(np.median(np.divide(times["transparent"], times["transparent object"]))),
    }
    want = frame(full, "ghosted-ao", styles["full"]).read()[0][..., :3].astype(np.int64)
    got = frame(r, "ghosted-ao", Style(focus=focus)).read()[0][..., :3].astype(np.int64)
    diff = np.abs(got - want)
    row["ao_error"] = {"over_8": float((diff.max(-1) > 8).mean()), "mae": float(diff.mean() / 255.0)}
    it = iter([Style(focus={k % scene.count}) for k in range(frames + 2)])
    frame(r, "ghosted-ao", Style(focus=focus))
    row["recomposite_ms"] = _median_ms(_gl_timed(ctx, lambda: r.composite("ghosted-ao", next(it))), frames)
    r.release()
    full.release()
    return row


def composite_scenes(specs: list[str] | None, quick: bool) -> list[tuple[str, object]]:
    """Scenes by name: 'demo', 'table1-N' (a Table 1 row), 'random-N' (N boxes), or a file;
    none given: the demo and the Table 1 rows."""
    from ..scene.generators.demo import demo_path
    from ..scene.loader import load_scene

    if not specs:
        specs = ["demo"] + [f"table1-{objects}" for objects, _ in (TABLE1[:2] if quick else TABLE1)]
    rows = dict(TABLE1)
    out = []
    for spec in specs:
        kind, _, count = spec.partition("-")
        if spec == "demo":
            out.append((spec, load_scene(demo_path())))
        elif kind == "table1" and count.isdigit() and int(count) in rows:
            out.append((spec, table1_scene(int(count), rows[int(count)])))
        elif kind == "random" and count.isdigit():
            n = int(count)
            out.append((spec, random_scene(n, seed=7, spread=4.0 * np.cbrt(n))))
        else:
            out.append((Path(spec).stem, load_scene(spec)))
    return out


def run_composite(
    viewport: tuple[int, int],
    quick: bool = False,
    json_path: str | None = None,
    ctx=None,
    scenes: list[str] | None = None,
    projection: Projection = "perspective",
) -> int:
    """Every mode's frame time against STD, with a perspective or orthographic camera."""
    ctx = ctx or shared_context()
    renderer = str(ctx.info["GL_RENDERER"])
    frames = 3 if quick else 11
    named = composite_scenes(scenes, quick)
    rows = [composite_row(ctx, name, scene, viewport, frames, projection=projection) for name, scene in named]
    _print_composite(rows, f"{renderer}; {projection}", viewport, frames)
    if json_path:
        write_text(json_path, json.dumps({"renderer": renderer, "viewport": list(viewport), "scenes": rows}, indent=1))
    return 0


def _print_composite(rows, renderer, viewport, frames) -> None:
    print(
        f"renderer: {renderer}; viewport {viewport[0]}x{viewport[1]}; median ms per full frame "
        f"(capture + post + composite; the atlas sized ahead, as the viewer draws) over {frames} rounds "
        f"(STD and every column in turn, each turn one "
        f"untimed and one timed frame); in brackets the median over rounds of the frame's ratio to STD "
        f"in the same round"
    )
    names = list(rows[0]["modes"])
    print(
        f"{'scene':>13} {'STD':>8} "
        + " ".join(f"{m:>18}" for m in names)
        + f" {'pixel/obj':>9} {'ao >8/255':>9} {'ao MAE':>7} {'recomposite':>16}"
    )
    for r in rows:
        cells = " ".join(f"{r['modes'][m]:>9.2f} ({r['ratios'][m]:>5.2f}x)" for m in names)
        rc, err = r["recomposite_ms"], r["ao_error"]
        print(
            f"{r['name']:>13} {r['std_ms']:>8.2f} {cells} {r['pixel_over_object']:>8.2f}x "
            f"{100 * err['over_8']:>8.3f}% {255 * err['mae']:>7.3f} {rc:>8.2f} "
            f"({rc / r['modes']['ghosted-ao']:.2f}x)"
        )
    print(
        "columns at the default settings (transparent: --order pixel), except 'ghosted-ao full' (AO and edges on "
        "every object, every region at scale 1) and 'transparent object' (--order object); pixel/obj: transparent "
        "(pixel) over object order, paired per round; ao >8/255, ao MAE (in 1/255): default ghosted-ao against "
        "full quality; "
        "recomposite: ghosted-ao after a focus change (post for the objects whose role changed + "
        "compositing), ratio to a full default ghosted-ao frame"
    )


def _rectpack(w, h, W, H):
    import rectpack

    packer: Any = rectpack.newPacker(rotation=False, pack_algo=rectpack.MaxRectsBssf)  # (untyped: inferred wrong)
    for i, (a, b) in enumerate(zip(w, h, strict=True)):
        packer.add_rect(int(a), int(b), rid=i)
    packer.add_bin(int(W), int(H), count=float("inf"))
    packer.pack()
    rects = np.array(packer.rect_list())  # (bin, x, y, w, h, rid)
    extent = (rects[:, 1] + rects[:, 3]).max() * (rects[:, 2] + rects[:, 4]).max()
    return len(packer), float(extent) * len(packer)


def _rpack(w, h, W, H):
    import rpack

    try:
        pos = np.array(rpack.pack(list(zip(w.tolist(), h.tolist(), strict=True)), max_width=int(W), max_height=int(H)))
    except rpack.PackingImpossibleError:
        return float("nan")
    return float((pos[:, 0] + w).max() * (pos[:, 1] + h).max())


def run_packing(quick: bool = False, json_path: str | None = None) -> int:
    """Utilization (region area / allocated layers' area) and time per frame against n."""
    rng = np.random.default_rng(3)
    W = H = 1024
    rows = []
    counts = [10, 100, 1000] if quick else [10, 100, 1000, 3000, 10000]
    for n in counts:
        side = rng.lognormal(np.log(1024 / np.sqrt(n) / 1.6), 0.5, (n, 2))
        w, h = np.clip(side, 1, W).astype(np.int64).T
        area = float((w * h).sum())
        frames = 5 if quick else 11
        p = pack_shelves(w, h, W, H)
        row = {
            "objects": n,
            "shelf_ms": _median_ms(lambda w=w, h=h: pack_shelves(w, h, W, H), frames),
            "shelf_util": area / (p.width * p.height * p.layers),
            "shelf_layers": p.layers,
        }
        if n <= (100 if quick else 1000):
            t0 = time.perf_counter()
            bins, used = _rectpack(w, h, W, H)
            row["rectpack_ms"] = (time.perf_counter() - t0) * 1e3
            row["rectpack_util"] = area / used
            row["rectpack_layers"] = bins
            t0 = time.perf_counter()
            used = _rpack(w, h, W, H)
            row["rpack_ms"] = (time.perf_counter() - t0) * 1e3
            row["rpack_util"] = area / used
        rows.append(row)
    print("packing into layers of at most 1024x1024; util = region area / (used width x height x layers)")
    print(
        f"{'objects':>8} {'shelf ms':>9} {'util':>6} {'layers':>6} {'rectpack ms':>12} {'util':>6} "
        f"{'layers':>6} {'rpack ms':>9} {'util':>6}"
    )
    for r in rows:
        print(
            f"{r['objects']:>8} {r['shelf_ms']:>9.3f} {r['shelf_util']:>6.3f} {r['shelf_layers']:>6} "
            f"{r.get('rectpack_ms', float('nan')):>12.1f} {r.get('rectpack_util', float('nan')):>6.3f} "
            f"{r.get('rectpack_layers', '-'):>6} {r.get('rpack_ms', float('nan')):>9.1f} "
            f"{r.get('rpack_util', float('nan')):>6.3f}"
        )
    if json_path:
        write_text(json_path, json.dumps({"rows": rows}, indent=1))
    return 0
