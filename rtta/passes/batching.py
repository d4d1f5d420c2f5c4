"""The scene drawn without and with batching, for the material atlas's reference and its
benchmark (Knecht & Mattausch):

- `SeparatePass`: unbatched STD, one draw call per object with the object's own texture
  (REPEAT, GL-built mip maps): what a textured scene costs without the atlas, and the
  reference the atlas is checked against.
- `ChunkedStdPass`: the batch regrouped by a SAH BVH into chunks of at most N vertices
  (rtta/bvh.py), each chunk frustum-culled and drawn with one call.
"""

from __future__ import annotations

import moderngl
import numpy as np

from ..gl import glsl
from ..gl.bindings import Texture
from ..gl.gpu import GpuScene
from ..gl.targets import LayeredTarget
from .bvh import Bvh, build_bvh, visible_leaves
from .capture import ScenePass


class SeparatePass(ScenePass):
    """One draw call per object, binding that object's own texture."""

    def __init__(self, ctx: moderngl.Context) -> None:
        super().__init__(ctx, SEPARATE=True)
        self._for: GpuScene | None = None  # the scene whose textures are uploaded
        self._textures: list[moderngl.Texture] = []
        self.draw_calls = 0

    def _uploaded(self, gpu: GpuScene) -> list[moderngl.Texture]:
        if self._for is not gpu:
            self._release_textures()
            for image in gpu.scene.textures:
                h, w = image.shape[:2]
                tex = self.ctx.texture((w, h), 4, np.ascontiguousarray(image).tobytes())
                tex.build_mipmaps()
                tex.filter = (moderngl.LINEAR_MIPMAP_LINEAR, moderngl.LINEAR)
                self._textures.append(tex)
            self._for = gpu
        return self._textures

    def render(
        self, *, gpu: GpuScene, view: np.ndarray, proj: np.ndarray, target: LayeredTarget, viewport: tuple[int, int]
    ) -> None:
        target.ensure(viewport, 1)
        target.clear()
        vao = self.setup(gpu, view, proj, target)
        target.bind((0, 0, *viewport))
        textures = self._uploaded(gpu) if gpu.textured else []
        ids = gpu.scene.texture_ids if gpu.textured else None
        self.draw_calls = 0
        try:
            for oid, (first, count) in enumerate(gpu.scene.index_ranges):
                if ids is not None:
                    has = ids[oid] >= 0
                    glsl.uniform(self.program, "u_textured").value = bool(has)
                    if has:
                        textures[ids[oid]].use(Texture.SCENE_TEXTURE)
                self.cull(bool(self._cullable[oid]))  # as STD culls (ScenePass.draw_objects)
                vao.render(moderngl.TRIANGLES, vertices=int(count), first=int(first))
                self.draw_calls += 1
        finally:
            self.cull(False)

    def _release_textures(self) -> None:
        for tex in self._textures:
            tex.release()
        self._textures, self._for = [], None

    def release(self) -> None:
        self._release_textures()
        super().release()


class ChunkedStdPass(ScenePass):
    """STD through BVH chunks: frustum-culled leaves, contiguous visible ones drawn together."""

    def __init__(self, ctx: moderngl.Context, max_vertices: int = 5000) -> None:
        super().__init__(ctx)
        self.max_vertices = max_vertices
        self._built: tuple[GpuScene, Bvh, moderngl.Buffer, dict] | None = None
        self.draw_calls = 0
        self.visible = 0

    def bvh(self, gpu: GpuScene) -> Bvh:
        return self._chunks(gpu)[1]

    def _chunks(self, gpu: GpuScene):
        if self._built is None or self._built[0] is not gpu:
            self._release_chunks()
            bvh = build_bvh(gpu.scene.positions, gpu.scene.indices.reshape(-1, 3), self.max_vertices)
            ibo = self.ctx.buffer(bvh.indices.astype(np.uint32).tobytes())
            self._built = (gpu, bvh, ibo, {})
        return self._built

    def render(
        self, *, gpu: GpuScene, view: np.ndarray, proj: np.ndarray, target: LayeredTarget, viewport: tuple[int, int]
    ) -> None:
        target.ensure(viewport, 1)
        target.clear()
        self.setup(gpu, view, proj, target)
        _, bvh, ibo, vaos = self._chunks(gpu)
        key = self.program.glo
        if key not in vaos:
            vaos[key] = gpu.vertex_array(self.program, ibo)
        target.bind((0, 0, *viewport))
        ranges = visible_leaves(bvh, proj @ view)
        self.visible = int(ranges[:, 2].sum()) if len(ranges) else 0
        self.draw_calls = len(ranges)
        self.cull(bool(self._cullable.all()))  # chunks mix objects: culled when every object may be
        try:
            for first, count, _ in ranges:
                vaos[key].render(moderngl.TRIANGLES, vertices=int(count), first=int(first))
        finally:
            self.cull(False)

    def _release_chunks(self) -> None:
        if self._built is not None:
            for vao in self._built[3].values():
                vao.release()
            self._built[2].release()
            self._built = None

    def release(self) -> None:
        self._release_chunks()
        super().release()
