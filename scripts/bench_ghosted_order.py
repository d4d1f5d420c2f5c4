"""The `ghosted` composite in object and in per-pixel order, in turns on one capture.

    python scripts/bench_ghosted_order.py [SCENE]     (default: the demo; 1024x1024)

Prints the medians of 9 composites each and the median of their ratios (docs/performance/order.md,
"Whole frames").
"""

from __future__ import annotations

import sys
import time

import numpy as np

from rtta.gl.context import create_headless_context
from rtta.passes.composite import Style
from rtta.renderer.renderer import Renderer
from rtta.scene.camera import Camera
from rtta.scene.loader import load_scene_or_demo


def main() -> None:
    ctx = create_headless_context()
    scene = load_scene_or_demo(sys.argv[1] if len(sys.argv) > 1 else None)
    renderer = Renderer(ctx, scene)
    renderer.capture(Camera.orbit(scene.center, scene.radius, 35, 25, 2.2), (1024, 1024))
    focus = {0, scene.count // 2}
    times: dict[str, list[float]] = {"object": [], "pixel": []}
    for _ in range(9):
        for order in times:
            start = time.perf_counter()
            renderer.composite("ghosted", Style(focus=focus, order=order))
            ctx.finish()
            times[order].append(time.perf_counter() - start)
    obj, pix = np.array(times["object"]), np.array(times["pixel"])
    print(
        f"{ctx.info['GL_RENDERER']}; {scene.count} objects; ghosted composite ms: object "
        f"{np.median(obj) * 1e3:.1f}, pixel {np.median(pix) * 1e3:.1f}, ratio {np.median(pix / obj):.2f}"
    )
    renderer.release()


if __name__ == "__main__":
    main()
