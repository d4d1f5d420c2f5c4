"""`AtlasPostPass`: ambient occlusion and edge strength per atlas texel, computed on each
object's own unoccluded images (the `ghosted-ao` mode only)."""

from __future__ import annotations

import moderngl
import numpy as np

from . import glraw, glsl
from .gpu import GpuScene
from .parameterize import Records
from .targets import LayeredTarget, release_framebuffer


class AtlasPostPass:
    """render(*, atlas, records, gpu, proj, style) -> an RGBA8 texture array (ao, edge) like the atlas."""

    def __init__(self, ctx: moderngl.Context) -> None:
        self.ctx = ctx
        self.program = ctx.program(vertex_shader=glsl.load("post.vert"), geometry_shader=glsl.load("post.geom"),
                                   fragment_shader=glsl.load("post.frag"))
        self.vao = ctx.vertex_array(self.program, [])
        self.texture = None
        self.fbo = None
        self._shape = None

    def _ensure(self, atlas: LayeredTarget) -> None:
        shape = (*atlas.size, atlas.layers)
        if shape == self._shape:
            return
        self._free()
        self.texture = self.ctx.texture_array(shape, 4, dtype="f1")
        self.texture.filter = (moderngl.NEAREST, moderngl.NEAREST)
        self.fbo = self.ctx.framebuffer([self.texture])
        self._shape = shape

    def render(self, *, atlas: LayeredTarget, records: Records, gpu: GpuScene, proj: np.ndarray, style) -> None:
        self._ensure(atlas)
        tw, th, td = records.atlas_size
        if td == 0:
            return
        gpu.bind_storage()
        glraw.bind_texture_array(0, atlas.depth.glo)
        atlas.normal.use(1)
        atlas.ids.use(2)
        uniforms = {"u_proj": (float(proj[0, 0]), float(proj[1, 1]), float(proj[2, 2]), float(proj[2, 3])),
                    "u_viewport": tuple(float(v) for v in records.viewport),
                    "u_ao_radius": float(style.ao_radius), "u_ao_strength": float(style.ao_strength),
                    "u_edge_width": int(style.edge_width)}
        for name, value in uniforms.items():
            if name in self.program:      # the compiler may drop unused ones
                self.program[name].value = value
        self.ctx.enable_only(moderngl.NOTHING)
        self.fbo.viewport = (0, 0, tw, th)
        self.fbo.use()
        self.vao.render(moderngl.TRIANGLES, vertices=3, instances=td)

    def _free(self) -> None:
        if self.fbo is not None:
            release_framebuffer(self.ctx, self.fbo)
            self.texture.release()
        self.fbo = self.texture = None
        self._shape = None

    def release(self) -> None:
        self._free()
        self.vao.release()
        self.program.release()
