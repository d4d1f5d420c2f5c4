"""Fast navigation's thinning on the GPU (issue 43): parameterize.comp's stages 7 and 8 rank
the visible objects by the area of their B_viewport in classes of a quarter octave, count the
classes' triangles, and cut where the largest classes hold the share asked
(`rtta.atlas.thinning.KeepShare`); the rounds of Algorithm 1 then pack the others only. Nothing
is read: the count left out is copied aside and read a frame late (`left_late`)."""

from __future__ import annotations

import moderngl
import numpy as np

from ..atlas.thinning import KeepShare
from ..gl import sync
from ..gl.bindings import Storage

RANK, CUT = 7, 8  # parameterize.comp's stages
BINS = 128  # its THIN_BINS
HEADER = 4 * (2 * BINS + 4)  # bytes before the per-object classes


class GpuThinning:
    """The buffers of the thinning stages: per-object weights (uploaded per `KeepShare.key`)
    and the classes, their counts and the cut.

    Parameters
    ----------
    ctx : moderngl.Context
        The context of the GpuParameterize whose programs run the stages.
    """

    def __init__(self, ctx: moderngl.Context) -> None:
        self.ctx = ctx
        self.thin = ctx.buffer(reserve=HEADER + 4)
        self.weights = ctx.buffer(reserve=4)
        self.late = ctx.buffer(reserve=4)  # thin_left of the frame before
        self._key: object = None
        self._pending = False
        self.left_late: int | None = None  # objects the last frame read left out (None: not known)

    def run(self, programs: dict[int, moderngl.ComputeShader], share: KeepShare, n: int, groups: int) -> None:
        """Rank and cut for `share` (the programs' uniforms set: u_keep among them); the rounds
        that follow leave out the objects below the cut."""
        self._read_late()
        share.left = self.left_late or 0  # the frame before's count: this frame's is on the GPU
        if share.key is None or share.key != self._key or self.weights.size != 4 * max(n, 1):
            w = share.weights()
            if self.weights.size != 4 * max(n, 1):
                self.weights.orphan(4 * max(n, 1))
                self.thin.orphan(HEADER + 4 * max(n, 1))
            self.weights.write(w.tobytes())
            self._key = share.key
        self.thin.clear(size=HEADER)
        self.thin.bind_to_storage_buffer(Storage.PARAM_THIN)
        self.weights.bind_to_storage_buffer(Storage.PARAM_WEIGHTS)
        programs[RANK].run(groups)
        sync.barrier(self.ctx, moderngl.SHADER_STORAGE_BARRIER_BIT)
        programs[CUT].run(1)
        sync.barrier(self.ctx, moderngl.SHADER_STORAGE_BARRIER_BIT | moderngl.BUFFER_UPDATE_BARRIER_BIT)  # and the copy
        self.ctx.copy_buffer(self.late, self.thin, size=4, read_offset=4 * (2 * BINS + 1))
        self._pending = True

    def _read_late(self) -> None:
        if self._pending:
            self.left_late = int(np.frombuffer(self.late.read(), np.uint32)[0])
            self._pending = False

    def release(self) -> None:
        for buf in (self.thin, self.weights, self.late):
            buf.release()
