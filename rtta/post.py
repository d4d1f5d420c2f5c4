"""`AtlasPostPass`: ambient occlusion and edge strength per atlas texel, computed on each
object's own unoccluded images (the `ghosted-ao` mode only).

Two draws: AO at half the atlas resolution (it is low-frequency, and it is most of the
cost), then edges at full resolution, which also picks up each texel's AO."""

from __future__ import annotations

import moderngl
import numpy as np

from . import glraw, glsl
from .gpu import GpuScene
from .parameterize import Records
from .targets import LayeredTarget, release_framebuffer


class _LayerTarget:
    """One RGBA8 texture array with its framebuffer, reallocated only when the shape changes."""

    def __init__(self, ctx: moderngl.Context) -> None:
        self.ctx = ctx
        self.texture = self.fbo = self.shape = None

    def ensure(self, shape: tuple[int, int, int]) -> None:
        if shape != self.shape:
            self.release()
            self.texture = self.ctx.texture_array(shape, 4, dtype="f1")
            self.texture.filter = (moderngl.NEAREST, moderngl.NEAREST)
            self.fbo = self.ctx.framebuffer([self.texture])
            self.shape = shape

    @property
    def nbytes(self) -> int:
        return 0 if self.shape is None else self.shape[0] * self.shape[1] * self.shape[2] * 4

    def release(self) -> None:
        if self.fbo is not None:
            release_framebuffer(self.ctx, self.fbo)
            self.texture.release()
        self.texture = self.fbo = self.shape = None


class AtlasPostPass:
    """render(*, atlas, records, gpu, proj, style) -> `texture`, an RGBA8 texture array
    (ao, edge) shaped like the atlas."""

    def __init__(self, ctx: moderngl.Context) -> None:
        self.ctx = ctx
        self.programs = {ao: ctx.program(vertex_shader=glsl.load("post.vert"), geometry_shader=glsl.load("post.geom"),
                                         fragment_shader=glsl.load("post.frag", AO_PASS=ao))
                         for ao in (True, False)}
        self.vaos = {ao: ctx.vertex_array(p, []) for ao, p in self.programs.items()}
        self._ao = _LayerTarget(ctx)
        self._out = _LayerTarget(ctx)

    @property
    def texture(self):
        return self._out.texture

    @property
    def nbytes(self) -> int:
        return self._ao.nbytes + self._out.nbytes

    def render(self, *, atlas: LayeredTarget, records: Records, gpu: GpuScene, proj: np.ndarray, style) -> None:
        w, h = atlas.size
        self._out.ensure((w, h, atlas.layers))
        self._ao.ensure(((w + 1) // 2, (h + 1) // 2, atlas.layers))
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
        self.ctx.enable_only(moderngl.NOTHING)
        for ao, target, size in ((True, self._ao, ((tw + 1) // 2, (th + 1) // 2)), (False, self._out, (tw, th))):
            prog = self.programs[ao]
            for name, value in uniforms.items():
                if name in prog:      # the compiler drops what a variant does not use
                    prog[name].value = value
            if not ao:
                self._ao.texture.use(3)
            target.fbo.viewport = (0, 0, *size)
            target.fbo.use()
            self.vaos[ao].render(moderngl.TRIANGLES, vertices=3, instances=td)

    def release(self) -> None:
        self._ao.release()
        self._out.release()
        for obj in (*self.vaos.values(), *self.programs.values()):
            obj.release()
