"""The direct renders the capture is held against, one class each.

- `StdPass`: the scene drawn normally into one target (baseline STD).
- `RttPass`: each object drawn alone into its own full-viewport target (baseline RTT).

Both cull the back faces of closed objects (Scene.closed) wholly beyond the near plane, as
the capture does (rtta.passes.capture.ScenePass).
"""

from __future__ import annotations

from collections.abc import Callable

import moderngl
import numpy as np

from ..gl.gpu import GpuScene
from ..gl.targets import LayeredTarget
from .capture import ScenePass


class StdPass(ScenePass):
    """STD, the direct render: the scene drawn normally into a one-layer target of the viewport.

    The reference every "x STD" figure is held against. With `projection` (ProjectorPass,
    Projector), painted by the projector per fragment. `Renderer.std` runs it.

    Parameters
    ----------
    ctx : moderngl.Context
        An OpenGL 4.3 core context.
    """

    def __init__(self, ctx: moderngl.Context) -> None:
        super().__init__(ctx)
        self._painted: ScenePass | None = None

    def render(
        self,
        *,
        gpu: GpuScene,
        view: np.ndarray,
        proj: np.ndarray,
        target: LayeredTarget,
        viewport: tuple[int, int],
        projection=None,
        objects: np.ndarray | None = None,
    ) -> None:
        """objects: bool [n], the objects to draw (None: all)."""
        target.ensure(viewport, 1)
        target.clear()
        scene_pass: ScenePass = self
        if projection is not None:
            if self._painted is None:
                self._painted = ScenePass(self.ctx, PROJECTOR=True)
            scene_pass = self._painted
        if projection is not None:  # every program the pass draws with (sections: several)
            pass_, projector = projection
            scene_pass.binder = lambda program: pass_.bind(program, projector, gpu.scene.origin)
        vao = scene_pass.setup(gpu, view, proj, target)
        target.bind((0, 0, *viewport))
        scene_pass.draw_objects(vao, gpu, objects)

    def release(self) -> None:
        super().release()
        if self._painted is not None:
            self._painted.release()


class RttPass(ScenePass):
    """RTT, the per-object baseline: every listed object drawn alone into a full-viewport target.

    One target is reused: after each object is drawn, `consume(object_id, target)` is called
    (read it back, composite it...), as an application of plain RTT would. `Renderer.rtt` runs
    it; the tests hold every atlas region against it.

    Parameters
    ----------
    ctx : moderngl.Context
        An OpenGL 4.3 core context.
    """

    def __init__(self, ctx: moderngl.Context) -> None:
        super().__init__(ctx)

    def render(
        self,
        *,
        gpu: GpuScene,
        view: np.ndarray,
        proj: np.ndarray,
        target: LayeredTarget,
        viewport: tuple[int, int],
        objects,
        consume: Callable[[int, LayeredTarget], None] | None = None,
    ) -> None:
        target.ensure(viewport, 1)
        vao = self.setup(gpu, view, proj, target)
        ranges, closed = gpu.scene.index_ranges, self._cullable
        one = np.zeros(gpu.scene.count, bool)
        try:
            for oid in objects:
                target.clear()
                target.bind((0, 0, *viewport))
                if self._capped is not None:  # as STD caps them (draw_objects)
                    one[oid] = True
                    self.draw_objects(vao, gpu, one)
                    one[oid] = False
                    if consume is not None:
                        consume(int(oid), target)
                    continue
                first, count = ranges[oid]
                self.cull(bool(closed[oid]))  # as draw_objects does
                vao.render(moderngl.TRIANGLES, vertices=int(count), first=int(first))
                if consume is not None:
                    consume(int(oid), target)
        finally:
            self.cull(False)
