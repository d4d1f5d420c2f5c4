"""GPU-side scene data shared by every pass: one vertex buffer, one index buffer, the
object buffer (colours) and the record buffer R (one std430 entry per object ID)."""

from __future__ import annotations

import moderngl
import numpy as np

from .parameterize import RECORD_DTYPE, Records
from .scene import Scene

VERTEX_LAYOUT = (("in_position", "3f", "12x"), ("in_normal", "3f", "12x"), ("in_object", "u4", "4x"))


class GpuScene:
    """Uploads a Scene once; `vao(program)` binds the shared buffers to a pass's program."""

    def __init__(self, ctx: moderngl.Context, scene: Scene) -> None:
        self.ctx = ctx
        self.scene = scene
        interleaved = np.zeros(scene.vertex_count, dtype=[("p", "<f4", 3), ("n", "<f4", 3), ("id", "<u4")])
        interleaved["p"] = scene.positions
        interleaved["n"] = scene.normals
        interleaved["id"] = scene.object_ids
        self.vbo = ctx.buffer(interleaved.tobytes())
        self.ibo = ctx.buffer(scene.indices.astype(np.uint32).tobytes())
        self.objects = ctx.buffer(np.ascontiguousarray(scene.colors, np.float32).tobytes())
        self.records = ctx.buffer(reserve=max(1, scene.count) * RECORD_DTYPE.itemsize)
        self._vaos: dict[int, moderngl.VertexArray] = {}

    def vao(self, program: moderngl.Program) -> moderngl.VertexArray:
        key = program.glo
        if key not in self._vaos:
            # attributes a program does not use (optimized out) are skipped in the layout
            used = [(name, fmt if name in program else skip) for name, fmt, skip in VERTEX_LAYOUT]
            layout = " ".join(fmt for _, fmt in used)
            names = [name for name, fmt in used if not fmt.endswith("x")]
            self._vaos[key] = self.ctx.vertex_array(
                program, [(self.vbo, layout, *names)], index_buffer=self.ibo, index_element_size=4)
        return self._vaos[key]

    def upload_records(self, records: Records) -> None:
        """Write R for this frame (same size every frame: no reallocation)."""
        self.records.write(records.packed().tobytes())

    def bind_storage(self) -> None:
        self.records.bind_to_storage_buffer(0)
        self.objects.bind_to_storage_buffer(1)

    def release(self) -> None:
        for vao in self._vaos.values():
            vao.release()
        self._vaos.clear()
        for buf in (self.vbo, self.ibo, self.objects, self.records):
            buf.release()
