"""`rtta bench ldi`: the seed's table (slide 18) for our shapes, GPU parity-test throughput
against trimesh's `contains` (embreex backend), and classification error against LDI resolution."""

from __future__ import annotations

import json
import platform
import time
from collections.abc import Callable
from pathlib import Path

import numpy as np

from ..outputs import write_text
from .tables import print_table

GPU_REPEATS = 9  # the GPU paths take ~15 ms: more repeats steady the best on a noisy VM


def _cow() -> Path:
    from .render import shared_data

    return shared_data() / "cow.glb"


def bench_meshes(quick: bool):
    """(name, trimesh) of the benchmark shapes; the cow when ../shared/data has it."""
    import trimesh

    from ..scene.generators import shapes

    out = [(k, shapes.SHAPES[k]()) for k in ("sphere", "torus", "torus-knot", "vase")]
    if _cow().is_file() and not quick:
        out.append(("cow", trimesh.load(_cow(), force="mesh")))
    return out


def _best_ms(fn: Callable[[], np.ndarray], repeats: int) -> tuple[float, np.ndarray]:
    t0 = time.perf_counter()
    result = fn()
    best = (time.perf_counter() - t0) * 1e3
    for _ in range(repeats - 1):
        t0 = time.perf_counter()
        result = fn()
        best = min(best, (time.perf_counter() - t0) * 1e3)
    return best, result


def error_by_resolution(
    ctx, name: str, mesh, points: int, resolutions, *, peeler=None, pts=None, ref=None, direction=None
) -> list[dict]:
    """Parity-test error against trimesh.contains (fraction of points classified differently)
    for LDIs of one mesh at each resolution, with peel and test times. Points are uniform in
    the bounding box; the viewpoint is chosen once (at the first resolution) unless given."""
    from ..ldi.gpu import ParityTest
    from ..ldi.peel import Peeler, build, closed_mesh

    v, f = closed_mesh(mesh.vertices, mesh.faces, name)
    own = peeler is None
    peeler = peeler or Peeler(ctx)
    if pts is None:
        lo, hi = mesh.bounds
        pts = np.random.default_rng(1).uniform(lo, hi, (points, 3))
        ref = mesh.contains(pts)
    if direction is None:  # choose the viewpoint once; this also compiles the shaders
        direction = build(ctx, v, f, resolutions[0], peeler=peeler).direction
    rows = []
    for n in resolutions:
        ldi_n = build(ctx, v, f, n, peeler=peeler, direction=direction)
        test = ParityTest(ctx, ldi_n)
        ms, got = _best_ms(lambda t=test, p=pts: t.classify(p), 3)
        test.release()
        rows.append(
            {
                "mesh": name,
                "resolution": n,
                "points": len(pts),
                "error": float((got != ref).mean()),
                "peel_ms": ldi_n.timings["peel"],
                "test_ms": ms,
                "layers": ldi_n.depth,
            }
        )
    if own:
        peeler.release()
    return rows


def run_ldi(quick: bool = False, points: int = 1_000_000, resolution: int = 512, json_path: str | None = None) -> int:
    from ..gl.context import shared_context
    from ..ldi.gpu import ParityTest
    from ..ldi.pack import compress
    from ..ldi.peel import Peeler, build, closed_mesh
    from ..ldi.stats import STATS_COLUMNS, stats_row

    ctx = shared_context()
    peeler = Peeler(ctx)
    points = 20_000 if quick else points
    resolutions = (64, 256) if quick else (64, 128, 256, 512, 1024)
    renderer = ctx.info["GL_RENDERER"]
    print(
        f"renderer: {renderer}; cpu: {platform.processor() or platform.machine()}; "
        f"date: {time.strftime('%Y-%m-%d')}; command: rtta bench ldi{' --quick' if quick else ''}"
    )
    table, speed, error = [], [], []
    for name, mesh in bench_meshes(quick):
        v, f = closed_mesh(mesh.vertices, mesh.faces, name)
        build(ctx, v, f, resolution, peeler=peeler)  # warm-up: shader compilation
        ldi = build(ctx, v, f, resolution, peeler=peeler)
        packed = compress(ldi)
        table.append(stats_row(name, v, ldi, packed))
        lo, hi = mesh.bounds
        pts = np.random.default_rng(1).uniform(lo, hi, (points, 3))
        test = ParityTest(ctx, ldi, packed)
        kernel = []

        def run(t=test, p=pts, k=kernel):
            inside = t.classify(p)
            k.append(t.last_ms["test"])  # the test pass alone, of the same runs
            return inside

        gpu_ms, inside = _best_ms(run, GPU_REPEATS)
        kernel_ms = min(kernel)
        comp_ms, inside_c = _best_ms(lambda t=test, p=pts: t.classify(p, compressed=True), GPU_REPEATS)
        test.release()
        ref_ms, ref = _best_ms(lambda m=mesh, p=pts: m.contains(p), 3 if not quick else 1)
        speed.append(
            {
                "mesh": name,
                "points": points,
                "gpu_ms": gpu_ms,
                "kernel_ms": kernel_ms,
                "compressed_ms": comp_ms,
                "trimesh_ms": ref_ms,
                "agree": float((inside == ref).mean()),
                "compressed_equal": bool((inside == inside_c).all()),
            }
        )
        error += error_by_resolution(
            ctx, name, mesh, points, resolutions, peeler=peeler, pts=pts, ref=ref, direction=ldi.direction
        )
    peeler.release()
    print(f"\nLDI figures at {resolution}x{resolution} (the seed's table; times in ms, memory in bytes)")
    print_table(STATS_COLUMNS, table)
    runs = 3 if not quick else 1
    print(
        f"\nparity test of {points} random points in the bounding box (best of {GPU_REPEATS}; trimesh: best of {runs})"
    )
    print_table(
        (
            "mesh",
            "GPU ms",
            "kernel ms",
            "compressed ms",
            "trimesh+embree ms",
            "speed-up",
            "agree",
            "plain == compressed",
        ),
        [
            (
                s["mesh"],
                f"{s['gpu_ms']:.1f}",
                f"{s['kernel_ms']:.1f}",
                f"{s['compressed_ms']:.1f}",
                f"{s['trimesh_ms']:.0f}",
                f"{s['trimesh_ms'] / s['gpu_ms']:.0f}x",
                f"{s['agree']:.5f}",
                s["compressed_equal"],
            )
            for s in speed
        ],
    )
    print("GPU ms: points in (float64 -> float32 upload), test, result back; kernel ms: the test pass alone")
    print("\nclassification error against trimesh.contains by LDI resolution")
    print_table(
        ("mesh", "N", "layers", "error", "peel ms", "test ms"),
        [
            (e["mesh"], e["resolution"], e["layers"], f"{e['error']:.5f}", f"{e['peel_ms']:.1f}", f"{e['test_ms']:.1f}")
            for e in error
        ],
    )
    if json_path:
        write_text(
            json_path,
            json.dumps(
                {
                    "renderer": renderer,
                    "table": [dict(zip(STATS_COLUMNS, map(str, r), strict=True)) for r in table],
                    "throughput": speed,
                    "resolution": error,
                },
                indent=1,
            ),
        )
    return 0
