"""The capture: scene passes, and the RTTA pass that draws every object into its region.

- `ScenePass`: a program from scene.vert, its variants, culling, sections' caps and draws
  of index runs, shared by every pass that draws the batched scene.
- `CapturePass` (RTTA): the whole batch in ONE pass into the layered atlas, each vertex displaced
  by its object's T to its layer (vertex- or geometry-shader path); regions on the viewport's
  edge alone are clipped (at an extreme zoom, to a guard: rtta.passes.guard). With R on the
  GPU, so are the draw lists (rtta.passes.draw_lists).

The direct renders STD and RTT are in rtta.passes.direct. All cull the back faces of closed
objects (Scene.closed) wholly beyond the near plane, which are never seen.
"""

from __future__ import annotations

from collections.abc import Callable
from typing import Literal

import moderngl
import numpy as np

from ..atlas.parameterize import Records
from ..gl import glsl
from ..gl.context import CapturePath
from ..gl.glsl import mat_bytes
from ..gl.gpu import GpuScene
from ..gl.targets import LayeredTarget
from ..scene.closure import beyond_near
from . import sections
from .draw_lists import CaptureLists, capture_from_records, draw_from_lists, draws_from_lists
from .guard import RegionGuard

DIRECT_RUNS = 1  # more runs of visible objects than this: one indirect multi-draw


class ScenePass:
    """Shared setup: a program from scene.vert (+ optional geometry shader) and scene.frag
    (or another fragment shader, e.g. depth.frag for the projector's shadow map)."""

    disjoint = False  # objects may share texels (STD): caps are made one object at a time
    guard = 0.0  # the region planes' guard (CapturePass: an extreme zoom's, rtta.passes.guard)
    drawn_size = (1, 1)  # the atlas layers' part drawn into (CapturePass: R's atlas_size; the textures may be larger)

    def __init__(
        self, ctx: moderngl.Context, geometry: str | None = None, fragment: str = "scene.frag", **defines: object
    ) -> None:
        self.ctx = ctx
        self._source = (geometry, fragment, defines)
        self._programs: dict[tuple, moderngl.Program] = {}
        self._indirect: moderngl.Buffer | None = None
        self._cullable = np.zeros(0, bool)  # per object, for the view of the last setup()
        # sections (setup): the capped and cut objects, the program without the cut, what setup drew with
        self._capped: np.ndarray | None = None
        self._cut: np.ndarray | None = None
        self._whole: moderngl.VertexArray | None = None
        self._drawn: tuple | None = None
        self.binder: Callable[[moderngl.Program], None] | None = None  # more uniforms, on every program
        self.program = self.program_for(False)

    def program_for(self, textured: bool, normals: bool = True, **variant: bool) -> moderngl.Program:
        """The pass's program for untextured or textured scenes, writing a normal image or
        not (to match the target: LayeredTarget.normals), with the `variant` defines that are
        true (e.g. REGION_CLIP); compiled on first use."""
        on = tuple(sorted(filter(variant.get, variant)))  # the true ones
        key = (textured, normals, on)
        if key not in self._programs:
            geometry, fragment, defines = self._source
            defines = {**defines, "TEXTURED": textured, **dict.fromkeys(on, True)}
            if not normals:
                defines["NO_NORMAL"] = True
            stages = {"vertex_shader": "scene.vert", "geometry_shader": geometry, "fragment_shader": fragment}
            self._programs[key] = glsl.program(self.ctx, **glsl.stage_sources(stages, **defines))
        return self._programs[key]

    def setup(
        self, gpu: GpuScene, view: np.ndarray, proj: np.ndarray, target: LayeredTarget | None = None, **variant: bool
    ) -> moderngl.VertexArray:
        """Program, matrices, buffers and state for drawing the batch into `target` (its
        attachments pick the program's outputs; None: a target of its own, e.g. a shadow map)."""
        placement = gpu.placement
        self.program = self._program(gpu, view, proj, target, variant)
        scene = gpu.scene
        lo, hi = scene.aabb_min - scene.origin, scene.aabb_max - scene.origin
        if placement is not None and placement.offsets is not None:
            lo, hi = lo + placement.offsets, hi + placement.offsets
        self._cullable = (
            scene.closed & beyond_near(lo, hi, view, proj) if gpu.cull_closed else np.zeros(scene.count, bool)
        )
        self._capped = self._cut = self._whole = None
        if placement is not None and placement.sections:
            self._cullable &= ~placement.cut  # their back faces show through the cut
            self._cut = placement.cut  # the others draw without the sections' discard (early depth test)
            whole = self._program(gpu, view, proj, target, {**variant, "SECTIONS": False})
            gpu.bind_material(whole)
            self._whole = gpu.vao(whole)
            if target is not None and target.stencil and placement.capped.any():
                self._capped = placement.capped
        self._drawn = (gpu, view, proj, target, variant)
        return self._bind(gpu)

    def prepare(
        self, gpu: GpuScene, view, proj, target: LayeredTarget, matrices: tuple | None = None, **variant: bool
    ) -> moderngl.VertexArray:
        """setup() without the per-object work (culling, sections): for draws whose lists the
        GPU built (rtta.passes.draw_lists), a placement without sections. `matrices`: view and
        proj as mat_bytes made them (a frame's draws make them once)."""
        self.program = self._program(gpu, view, proj, target, variant, matrices)
        return self._bind(gpu)

    def _bind(self, gpu: GpuScene) -> moderngl.VertexArray:
        """The buffers, material and depth state for drawing with self.program."""
        gpu.bind_storage()
        gpu.bind_material(self.program)
        self.ctx.enable_only(moderngl.DEPTH_TEST)
        self.ctx.depth_func = "<"
        return gpu.vao(self.program)

    def _program(self, gpu: GpuScene, view, proj, target, variant: dict, matrices=None) -> moderngl.Program:
        """The program for `variant` and the scene's placement (rtta.passes.sections), its
        matrices (`matrices`: as mat_bytes made them) and the placement's uniforms set."""
        placement = gpu.placement
        extra = {**(placement.variant() if placement is not None else {}), **variant}
        program = self.program_for(gpu.textured, target is None or target.normals, **extra)
        view_bytes, proj_bytes = matrices or (mat_bytes(view), mat_bytes(proj))
        glsl.set_uniforms(program, {"u_view": view_bytes, "u_proj": proj_bytes})
        if extra.get("REGION_GUARD"):  # the capture at an extreme zoom (passes.guard)
            glsl.set_uniforms(program, {"u_region_guard": self.guard, "u_atlas_size": self.drawn_size})
        if placement is not None:
            placement.apply(program, proj @ view)
        if self.binder is not None and not variant.get("CAP_COUNT"):  # the count writes the stencil alone
            self.binder(program)
        return program

    def draw_objects(self, vao: moderngl.VertexArray, gpu: GpuScene, objects: np.ndarray | None) -> None:
        """Draw the objects in `objects` (bool [n]; None: all) as setup() prepared them: the
        closed ones (Scene.closed) wholly beyond the near plane with their back faces culled,
        which are never seen then, the others double-sided; one call for each kind there is.
        Then the caps of the capped objects (sections): all at once where each texel belongs
        to one object (the atlas, RTT), else one object after the other (STD)."""
        closed = self._cullable
        placement = gpu.placement
        if placement is not None and placement.removed.any():  # cut away whole
            objects = ~placement.removed if objects is None else objects & ~placement.removed
        cut, whole = self._cut, self._whole  # set together by setup()
        try:
            for cull, kind in ((True, closed), (False, ~closed)):
                mask = kind if objects is None else kind & objects
                for program, part in ((vao, None),) if cut is None or whole is None else ((whole, ~cut), (vao, cut)):
                    drawn = mask if part is None else mask & part
                    if drawn.any():
                        self.cull(cull)
                        self._draw_runs(program, None if drawn.all() else gpu.scene.index_runs(drawn))
        finally:
            self.cull(False)
        capped = self._capped if self._capped is None or objects is None else self._capped & objects
        if capped is None or not capped.any():
            return
        if self.disjoint:
            self._caps(capped)
            return
        one = np.zeros(len(capped), bool)
        for oid in np.flatnonzero(capped):
            one[oid] = True
            self._caps(one)
            one[oid] = False

    def _caps(self, capped: np.ndarray) -> None:
        """Cap `capped` (bool [n]) where the view ray enters the kept region inside them: their
        surfaces beyond that point counted into the stencil (its winding number), then their
        back faces drawn as the cap where the count is not 0, resetting it (rtta.passes.sections)."""
        assert self._drawn is not None, "setup() first"
        gpu, view, proj, target, variant = self._drawn
        assert target is not None, "caps only with a target (setup)"
        runs = gpu.scene.index_runs(capped)
        masks = target.color_writes(False)
        try:
            sections.stencil_count()
            self.ctx.depth_func = "1"
            self._draw_runs(gpu.vao(self._program(gpu, view, proj, target, {**variant, "CAP_COUNT": True})), runs)
            sections.stencil_cap()
            self.ctx.depth_func = "<"
            target.color_writes(masks)
            self.ctx.enable(moderngl.CULL_FACE)
            self.ctx.cull_face, self.ctx.front_face = "front", "ccw"
            program = self._program(gpu, view, proj, target, {**variant, "CAP_DRAW": True})
            gpu.bind_material(program)
            self._draw_runs(gpu.vao(program), runs)
        finally:
            sections.stencil_off()
            self.ctx.depth_func = "<"
            self.ctx.cull_face = "back"
            self.cull(False)
            target.color_writes(masks)

    def cull(self, on: bool) -> None:
        """Back-face culling on (counter-clockwise fronts) or off."""
        if on:
            self.ctx.enable(moderngl.CULL_FACE)
            self.ctx.cull_face, self.ctx.front_face = "back", "ccw"
        else:
            self.ctx.disable(moderngl.CULL_FACE)

    def _draw_runs(self, vao: moderngl.VertexArray, runs: np.ndarray | None) -> None:
        """Draw index runs [(first, count)] in one call (None: the whole batch): one run
        directly, several as one indirect multi-draw, its command buffer grown as needed and
        reused across frames."""
        if runs is None:
            vao.render(moderngl.TRIANGLES)
            return
        if len(runs) <= DIRECT_RUNS:
            for first, count in runs:
                vao.render(moderngl.TRIANGLES, vertices=int(count), first=int(first))
            return
        commands = np.zeros((len(runs), 5), np.uint32)  # count, instances, first index, base vertex, base instance
        commands[:, 0], commands[:, 1], commands[:, 2] = runs[:, 1], 1, runs[:, 0]
        data = commands.tobytes()
        if self._indirect is None or self._indirect.size < len(data):
            if self._indirect is not None:
                self._indirect.release()
            self._indirect = self.ctx.buffer(reserve=max(len(data), 4096) * 2)
        self._indirect.write(data)
        vao.render_indirect(self._indirect, moderngl.TRIANGLES, count=len(runs))

    def release(self) -> None:
        if self._indirect is not None:
            self._indirect.release()
            self._indirect = None
        for program in self._programs.values():
            program.release()
        self._programs.clear()


class CapturePass(ScenePass):
    """The RTTA capture: every visible object drawn once into its own atlas region.

    One draw call over the batched scene, each vertex displaced by its object's transform T
    into its region and layer (a second call for the regions on the viewport's edge, the only
    ones clipped). `Renderer.capture` runs it.

    Parameters
    ----------
    ctx : moderngl.Context
        An OpenGL 4.3 core context.
    path : {"vs", "gs"}
        "vs": the layer chosen in the vertex shader (GL_ARB_shader_viewport_layer_array);
        "gs": the paper's geometry shader.
    """

    disjoint = True  # every texel belongs to one object's region: all caps at once

    def __init__(self, ctx: moderngl.Context, path: Literal["vs", "gs"] | CapturePath) -> None:
        if path not in (CapturePath.VS, CapturePath.GS):
            raise ValueError(f"capture path must be 'vs' or 'gs', got {path!r}")
        self.path = CapturePath(path)
        self.frames = 0
        self.lists: CaptureLists | None = None  # made on the first frame of R on the GPU
        self.gpu_lists_used = False  # whether the last frame drew from GPU-built lists
        self._guards, self._guarded = RegionGuard(), None  # an extreme zoom (rtta.passes.guard)
        if self.path is CapturePath.VS:
            super().__init__(ctx, CAPTURE_VS=True)
        else:
            super().__init__(ctx, geometry="capture.geom", CAPTURE_GS=True)

    def render(
        self,
        *,
        gpu: GpuScene,
        records: Records,
        view: np.ndarray,
        proj: np.ndarray,
        atlas: LayeredTarget,
        normals: bool = True,
        ids: bool = True,
    ) -> None:
        """Upload R, then draw the whole batch once into `atlas` (sized to records.atlas_size):
        one draw call, two on the vertex-shader path when some regions meet the viewport's edge
        (those alone are clipped); objects without a region (culled, hidden) are left out. R on
        the GPU (GpuRecords), no sections: lists built there (draw_lists; `gpu_lists_used`).
        normals=False or ids=False: that image is not written (a colour mask). Compositing never
        reads ids and reads normals only for AO, edges and the projector; picking reads depths."""
        tw, th, td = records.atlas_size
        self.frames += 1
        self.guard, self.drawn_size = self._guards.of(gpu, view, proj, records.viewport), (tw, th)
        if self.guard > 0 and self.path is CapturePath.VS:  # the geometry shader cuts to the guard
            self._guarded = self._guarded or CapturePass(self.ctx, CapturePath.GS)
            self._guarded.render(gpu=gpu, records=records, view=view, proj=proj, atlas=atlas, normals=normals, ids=ids)
            self.gpu_lists_used = self._guarded.gpu_lists_used
            return
        self.gpu_lists_used = td > 0 and draws_from_lists(records, gpu)
        lists = None
        if self.gpu_lists_used:  # built before the clear: llvmpipe's memory barrier waits for all queued work
            lists = self.lists = self.lists or CaptureLists(self.ctx)
            lists.build(gpu, view, proj, records.viewport, clip_all=self.path is CapturePath.GS)
        atlas.ensure((tw, th), td)
        atlas.clear()
        atlas.normals_written, atlas.ids_written = normals and atlas.normals, ids
        if td == 0:
            return
        gpu.upload_records(records)  # nothing to write where the GPU wrote R itself
        atlas.bind((0, 0, tw, th))
        atlas.write_mask(normals, ids)
        try:
            if lists is not None:
                draw_from_lists(self, lists, gpu, view, proj, atlas)
            else:
                capture_from_records(self, gpu, view, proj, atlas, records)
        finally:
            atlas.write_mask()

    def release(self) -> None:
        super().release()
        for part in (self.lists, self._guarded):
            if part is not None:
                part.release()
        self.lists = self._guarded = None
