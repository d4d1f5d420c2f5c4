"""GPU-side scene data shared by every pass: one vertex buffer, one index buffer, the
object buffer (colours), B_world per object, the record buffer R (one std430 entry per
object ID) and, for a textured scene, the material atlas and its per-object buffer."""

from __future__ import annotations

import weakref

import moderngl
import numpy as np

from ..atlas.records import RECORD_DTYPE, GpuRecords, Records
from ..scene.model import Scene
from .bindings import Storage, Texture

VERTEX_LAYOUT = (("in_position", "3f", "12x"), ("in_normal", "3f", "12x"), ("in_object", "u4", "4x"))
UV_LAYOUT = (("in_uv", "2f", "8x"),)
MATERIAL_DTYPE = np.dtype([("rect", "<f4", 4), ("info", "<i4", 4)])


class GpuScene:
    """Uploads a Scene once; `vao(program)` binds the shared buffers to a pass's program."""

    def __init__(self, ctx: moderngl.Context, scene: Scene) -> None:
        self.ctx = ctx
        self.scene = scene
        self.textured = scene.textured
        self.cull_closed = True  # the scene passes cull the back faces of closed objects (Scene.closed)
        self.placement = None  # rtta.passes.sections.Placement: objects moved and cut, or None
        fields = [("p", "<f4", 3), ("n", "<f4", 3), ("id", "<u4")] + ([("uv", "<f4", 2)] if self.textured else [])
        interleaved = np.zeros(scene.vertex_count, dtype=fields)
        interleaved["p"] = scene.positions
        interleaved["n"] = scene.normals
        interleaved["id"] = scene.object_ids
        self.layout = VERTEX_LAYOUT + (UV_LAYOUT if self.textured else ())
        self.material_atlas = self.materials = self.atlas_info = None
        if self.textured:
            interleaved["uv"] = scene.uvs
            self._upload_materials()
        self.vbo = ctx.buffer(interleaved.tobytes())
        self.ibo = ctx.buffer(scene.indices.astype(np.uint32).tobytes())
        self.objects = ctx.buffer(np.ascontiguousarray(scene.colors, np.float32).tobytes())
        self.records = ctx.buffer(reserve=max(1, scene.count) * RECORD_DTYPE.itemsize)
        self._written: weakref.ref | None = None  # the GpuRecords of the R in `records`, while one is held
        self.serial = 0  # frames of R written into `records`
        self._vaos: dict[int, moderngl.VertexArray] = {}
        # B_world per object as two vec4 (min, max), the scene origin at 0 as for the vertex
        # positions: compositing draws sprites over their projected outlines (composite.geom)
        bounds = np.zeros((max(scene.count, 1), 2, 4), np.float32)
        bounds[: scene.count, 0, :3] = scene.aabb_min - scene.origin
        bounds[: scene.count, 1, :3] = scene.aabb_max - scene.origin
        self.bounds = ctx.buffer(bounds.tobytes())

    def vao(self, program: moderngl.Program) -> moderngl.VertexArray:
        """The shared buffers bound to `program` (one vertex array per program, cached)."""
        key = program.glo
        if key not in self._vaos:
            self._vaos[key] = self.vertex_array(program, self.ibo)
        return self._vaos[key]

    def vertex_array(self, program: moderngl.Program, index_buffer: moderngl.Buffer) -> moderngl.VertexArray:
        """A new vertex array over the scene's vertices with another index buffer (the caller releases it)."""
        # attributes a program does not use (optimized out) are skipped in the layout
        used = [(name, fmt if name in program else skip) for name, fmt, skip in self.layout]
        layout = " ".join(fmt for _, fmt in used)
        names = [name for name, fmt in used if not fmt.endswith("x")]
        return self.ctx.vertex_array(
            program, [(self.vbo, layout, *names)], index_buffer=index_buffer, index_element_size=4
        )

    def _upload_materials(self) -> None:
        """Pack the textures into the material atlas (mip levels 0..levels built by GL from
        the wrapped slots) and write, per object, where its texture lies."""
        from ..scene.material_atlas import DEFAULT_MAX_SIZE, build_atlas

        max_size = min(DEFAULT_MAX_SIZE, self.ctx.info["GL_MAX_TEXTURE_SIZE"])
        atlas = build_atlas(self.scene.textures, max_size=max_size)
        self.atlas_info = atlas
        tex = self.ctx.texture_array((atlas.size, atlas.size, atlas.layers), 4, atlas.image.tobytes())
        tex.build_mipmaps(0, atlas.levels)
        tex.filter = (moderngl.LINEAR_MIPMAP_LINEAR, moderngl.LINEAR)
        tex.repeat_x = tex.repeat_y = False
        self.material_atlas = tex
        rows = np.zeros(self.scene.count, MATERIAL_DTYPE)
        ids = self.scene.texture_ids
        assert ids is not None, "textured scenes have texture ids"
        has = ids >= 0
        rect = atlas.rects[np.where(has, ids, 0)]
        rows["rect"] = rect[:, [1, 2, 3, 4]]
        rows["info"][:, 0] = rect[:, 0]
        rows["info"][:, 3] = has
        self.materials = self.ctx.buffer(rows.tobytes())

    def bind_material(self, program: moderngl.Program) -> None:
        """The material atlas on Texture.MATERIAL_ATLAS for a program that samples it."""
        if self.material_atlas is not None and "u_material_atlas" in program:
            self.material_atlas.use(Texture.MATERIAL_ATLAS)

    def upload_records(self, records: Records) -> None:
        """Write R for this frame (same size every frame: no reallocation)."""
        if records is self.written:  # there already: rtta.passes.atlas_gpu wrote it
            return
        self.keep_held()
        self.serial += 1
        self.records.write(records.packed(reuse=True))  # no copy to bytes: 8 MB a frame at 10^5 objects

    @property
    def written(self) -> Records | None:
        """The GpuRecords of the R in `records` (rtta.passes.atlas_gpu), while someone holds them."""
        return None if self._written is None else self._written()

    def hand(self, records: Records) -> int:
        """`records` (a GpuRecords, R just written by the GPU) now describe the buffer; their frame number."""
        self.serial += 1
        self._written = weakref.ref(records)
        return self.serial

    def keep_held(self) -> None:
        """Before R is written over or freed: a GpuRecords of it that a caller still holds is read
        back now, so records stay what their frame made them (one wait, only when held)."""
        held = self.written
        self._written = None
        if isinstance(held, GpuRecords) and not held.is_read:
            held.read()

    def bind_storage(self) -> None:
        self.records.bind_to_storage_buffer(Storage.RECORDS)
        self.objects.bind_to_storage_buffer(Storage.OBJECTS)
        if self.materials is not None:
            self.materials.bind_to_storage_buffer(Storage.MATERIALS)

    def release(self) -> None:
        self.keep_held()
        for vao in self._vaos.values():
            vao.release()
        self._vaos.clear()
        for buf in (self.vbo, self.ibo, self.objects, self.records, self.materials, self.material_atlas, self.bounds):
            if buf is not None:
                buf.release()
