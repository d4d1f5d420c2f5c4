"""`rtta bench capture`'s Algorithm 1 rows: the CPU path (numpy, rtta.atlas.parameterize) against
the GPU path (compute shaders, rtta.passes.atlas_gpu) per frame on random scenes.

"outside GL" is the time a frame spends in Python and numpy outside GL calls: on the CPU path
parameterize plus packing the record buffer's contents, on the GPU path what
GpuParameterize.run does between its GL calls (the scales wanted, the records rebuilt from the
read-back buffer). "wall" adds the GL calls (the upload; the dispatches and read-backs) with the
GPU finished. The paths take turns within each frame, so a busy machine slows both alike.
"""

from __future__ import annotations

import statistics
import time

import numpy as np

from ..atlas.parameterize import default_atlas_max, parameterize
from ..gl.context import Capabilities
from ..gl.gpu import GpuScene
from ..passes.atlas_gpu import GpuParameterize
from ..scene.camera import Camera
from ..scene.generators.generate import random_scene


def counts_for(quick: bool, full: bool) -> list[int]:
    """1k parts (quick), 1k and 10k, and 100k with --full."""
    return [1000] if quick else [1000, 10_000, 100_000] if full else [1000, 10_000]


def param_paths(ctx, counts: list[int], viewport: tuple[int, int], frames: int) -> list[dict]:
    """Per scene size: median ms per frame of both paths (outside GL, wall), utilisation and layers."""
    rows = []
    max_layers = min(2048, Capabilities.of(ctx).max_layers)
    for n in counts:
        scene = random_scene(n, seed=1)
        gpu, param = GpuScene(ctx, scene), GpuParameterize(ctx)
        corners = scene.box_corners()
        kw = {"border": 1, "atlas_max": default_atlas_max(viewport, 1), "max_layers": max_layers}
        ms: dict[str, list[float]] = {"cpu": [], "gpu": [], "cpu_wall": [], "gpu_wall": []}
        try:
            for f in range(frames + 1):  # the first warms both up
                cam = Camera.orbit(scene.center, scene.radius, 30.0 + 3 * f, 20.0, 2.2)
                vpm = cam.projection(viewport[0] / viewport[1]) @ cam.view(scene.origin)
                ctx.finish()
                t0 = time.perf_counter()
                cpu = parameterize(corners, vpm, viewport, **kw)
                packed = cpu.packed(reuse=True)
                t1 = time.perf_counter()
                gpu.records.write(packed)
                ctx.finish()
                t2 = time.perf_counter()
                records = param.run(gpu, corners, vpm, viewport, **kw)
                ctx.finish()
                t3 = time.perf_counter()
                if f:
                    for key, value in (("cpu", t1 - t0), ("cpu_wall", t2 - t0), ("gpu_wall", t3 - t2)):
                        ms[key].append(value * 1e3)
                    ms["gpu"].append(param.cpu_seconds * 1e3)
            rows.append(
                {
                    "objects": n,
                    "visible": int(cpu.visible.sum()),
                    **{f"{k}_ms": statistics.median(v) for k, v in ms.items()},
                    "cpu_util": cpu.utilization,
                    "gpu_util": records.utilization,
                    "cpu_layers": cpu.atlas_size[2],
                    "gpu_layers": records.atlas_size[2],
                    "same_rects": bool(np.array_equal(cpu.viewport_rect, records.viewport_rect)),
                }
            )
        finally:
            param.release()
            gpu.release()
    return rows


def print_paths(rows: list[dict]) -> None:
    """The rows as a table under the capture table (its header names the renderer)."""
    print("Algorithm 1 per frame, CPU path (numpy) vs GPU path (compute shaders); median ms:")
    print(
        f"{'objects':>8} {'visible':>8} {'cpu out-GL':>10} {'gpu out-GL':>10} {'cpu wall':>9} {'gpu wall':>9} "
        f"{'util cpu':>8} {'util gpu':>8} {'layers':>9} same B_viewport"
    )
    for r in rows:
        print(
            f"{r['objects']:>8} {r['visible']:>8} {r['cpu_ms']:>10.2f} {r['gpu_ms']:>10.2f} {r['cpu_wall_ms']:>9.2f} "
            f"{r['gpu_wall_ms']:>9.2f} {r['cpu_util']:>8.3f} {r['gpu_util']:>8.3f} "
            f"{r['cpu_layers']:>4}/{r['gpu_layers']:<4} {r['same_rects']}"
        )
