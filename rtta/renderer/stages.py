"""The renderer's stages, timed when it measures (`Renderer.measure`, `Renderer.timings`)."""

from __future__ import annotations

import time

STAGES = ("parameterize", "capture", "lens", "composite", "projector", "post", "std")


class Stage:
    """`with renderer.stages[name]:` the stage's wall ms into `renderer.timings[name]` when
    `renderer.measure` (waiting for the GPU at its end, so its GPU work counts); nothing else.
    A context manager made once per stage: entering it costs two calls, where a
    `contextlib.contextmanager` costs six (issue 43 counts a frame's Python calls)."""

    __slots__ = ("renderer", "name", "start")

    def __init__(self, renderer, name: str) -> None:
        self.renderer, self.name, self.start = renderer, name, 0.0

    def __enter__(self) -> None:
        if self.renderer.measure:
            self.start = time.perf_counter()

    def __exit__(self, kind, value, trace) -> None:
        r = self.renderer
        if r.measure and kind is None:
            r.ctx.finish()
            r.timings[self.name] = (time.perf_counter() - self.start) * 1e3


def stages_of(renderer) -> dict[str, Stage]:
    """A Stage for each of STAGES."""
    return {name: Stage(renderer, name) for name in STAGES}
