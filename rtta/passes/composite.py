"""Compositing from the atlas (RTTA paper, section 3.2, Figure 3): one point per object,
expanded into a quad over its B_viewport, reading its own unoccluded atlas images.

Modes: `sprites` (depth sprites, reconstruct STD), `transparent` (every object blended
with its opacity, back to front); in both, highlighted (focus) objects get their silhouette
drawn over everything. `ghosted` (focus opaque and visible through the faded,
desaturated context, with silhouettes), `ghosted-ao` (ghosted, shaded with ambient
occlusion and edges computed on each object's own atlas images; by default AO on the focus
objects only, Style.ao_objects / edge_objects). Regions captured below one texel per pixel
(context objects at Settings.context_scale) are upsampled depth-aware (UPSAMPLE variant);
`transparent` blends per pixel in surface order (Style.order 'pixel', and 'auto', the default;
oit.py), the ghosted context with 'pixel'; Style.halo draws halos around focus objects where
context lies behind them.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import moderngl
import numpy as np

from ..atlas.parameterize import Records
from ..gl import glraw, glsl
from ..gl.bindings import Storage, Texture
from ..gl.gpu import GpuScene
from ..gl.targets import CompositeTarget, LayeredTarget, release_framebuffer
from .capture import mat_bytes
from .oit import PixelOrderPass, blended_in_place, resolved_order
from .outlines import hull_margin, worth_outlines

MODES = ("sprites", "transparent", "ghosted", "ghosted-ao")
LENS_MODES = ("ghosted", "ghosted-ao")  # where a lens cuts the context away
BACKGROUND = (0.93, 0.93, 0.95, 1.0)
UPSAMPLE_BELOW = 0.999  # regions with fewer texels per pixel are upsampled
ROLES = ("focus", "all")  # which objects get AO / edges in ghosted-ao


@dataclass
class Style:
    """What compositing needs besides the atlas; changing it never re-runs the capture."""

    opacity: dict[int, float] = field(default_factory=dict)  # per object id
    default_opacity: float = 0.5  # `transparent`: objects not in `opacity`
    focus: set[int] = field(default_factory=set)
    context_opacity: float = 0.3
    desaturate: float = 0.8
    edge_color: tuple[float, float, float, float] = (0.05, 0.05, 0.08, 1.0)
    outline_color: tuple[float, float, float, float] = (1.0, 0.75, 0.1, 1.0)
    outline_width: int = 1
    edge_width: int = 1
    ao_radius: float = 6.0
    ao_strength: float = 1.0
    # defaults from `rtta bench composite` on the demo at 1024² (README, BENCHMARKS.md)
    ao_objects: str = "focus"  # ghosted-ao: AO on 'focus' objects only (the paper) or on 'all'
    edge_objects: str = "all"  # ghosted-ao: edges on 'focus' objects only or on 'all'
    order: str = "auto"  # transparent and ghosted context: 'object' (bounds centres), 'pixel'
    # (surface depths), or 'auto' (oit.resolved_order: pixel in transparent)
    halo: int = 0  # ghosted modes: halo width (pixels) around focus objects, 0: none
    halo_color: tuple[float, float, float, float] = (0.0, 0.0, 0.0, 0.6)  # (rgb, strength)

    def shaded(self, n: int) -> tuple[np.ndarray, np.ndarray]:
        """(uses AO, uses edges) per object [n] bool, in ghosted-ao."""
        focus = np.zeros(n, bool)
        focus[[o for o in self.focus if 0 <= o < n]] = True
        for name, value in (("ao_objects", self.ao_objects), ("edge_objects", self.edge_objects)):
            if value not in ROLES:
                raise ValueError(f"{name} must be one of {', '.join(ROLES)}, got {value!r}")
        every = np.ones(n, bool)
        return (every if self.ao_objects == "all" else focus), (every if self.edge_objects == "all" else focus)


def back_to_front(records: Records, view_depth: np.ndarray, ids: np.ndarray) -> np.ndarray:
    """`ids` ordered farthest first by the view depth of their bounds centre; ties by id,
    so the order is stable and intersecting parts do not flicker."""
    ids = np.asarray(ids, np.int64)
    ids = ids[records.visible[ids]]
    key = -view_depth[ids]
    order = np.argsort(key)  # half a lexsort's time (7 against 15 ms at 10^5 objects)
    ranked = key[order]
    if (ranked[1:] == ranked[:-1]).any():  # a tie: the order among equals must be by id
        return ids[np.lexsort((ids, key))]
    return ids[order]


class CompositePass:
    """`render(*, atlas, records, gpu, style, mode, target)`; needs `post` for ghosted-ao."""

    def __init__(self, ctx: moderngl.Context) -> None:
        self.ctx = ctx
        self._programs: dict[tuple, moderngl.Program] = {}
        self._vaos: dict[tuple, moderngl.VertexArray] = {}
        self.styles = ctx.buffer(reserve=16)
        self.order = ctx.buffer(reserve=16)
        self.passes: list[str] = []  # the draws of the last render, for inspection
        self._pixel_order = None  # PixelOrderPass, made on first use
        self._context_depth = self._context_fbo = None  # front-most context depth, for halos
        self.fallbacks = 0  # frames that asked for pixel order and got object order
        self._projection = self._lens = self._inv_view_proj = None
        self._hull = None  # (P V bytes, eye): sprites over the projected outlines of B_world
        self._opacity = np.zeros(0, np.float32)  # per object, as the last render draws them
        self.hull_draws = 0  # draws of the last render whose sprites covered projected outlines

    def _program(self, **defines) -> tuple[moderngl.Program, moderngl.VertexArray]:
        key = tuple(sorted(defines.items()))
        if key not in self._programs:
            sources = glsl.stage_sources(
                {
                    "vertex_shader": "composite.vert",
                    "geometry_shader": "composite.geom",
                    "fragment_shader": "composite.frag",
                },
                **defines,
            )
            prog = glsl.program(self.ctx, **sources)
            self._programs[key] = prog
            self._vaos[key] = self.ctx.vertex_array(prog, [])
        return self._programs[key], self._vaos[key]

    def _upload(self, buf: moderngl.Buffer, data) -> None:
        """`data`: bytes or a contiguous array (written as it is: no copy to bytes)."""
        size = memoryview(data).nbytes
        if buf.size < size:
            buf.orphan(max(size, 2 * buf.size))
        buf.write(data)

    def render(
        self,
        *,
        atlas: LayeredTarget,
        records: Records,
        gpu: GpuScene,
        style: Style,
        mode: str,
        view_depth: np.ndarray,
        target: CompositeTarget,
        post=None,
        view_proj=None,
        projection=None,
        lens=None,
        eye=None,
    ) -> None:
        """Composite the captured atlas into `target` (sized to the records' viewport).
        `projection`: (ProjectorPass, Projector, scene origin) to paint with; `lens`: (LensPass,
        Lens, scene origin) cutting the context away in the ghosted modes. Both need `view_proj`.
        `eye`: the camera's position (scene origin at 0); with `view_proj`, sprites cover the
        projected outline of each object's B_world instead of all of B_viewport."""
        if lens is not None and mode not in LENS_MODES:
            lens = None
        self._projection, self._lens = projection, lens
        # (P V)^-1 once per render, for every draw that rebuilds world positions
        self._inv_view_proj = None if projection is None and lens is None else mat_bytes(np.linalg.inv(view_proj))
        self._hull = None if eye is None or view_proj is None else (mat_bytes(view_proj), tuple(float(v) for v in eye))
        if mode not in MODES:
            raise ValueError(f"unknown mode {mode!r}; modes: {', '.join(MODES)}")
        n = len(records.visible)
        params = np.zeros((max(n, 1), 4), np.float32)
        params[:n, 0] = style.default_opacity if mode == "transparent" else 1.0
        for oid, a in style.opacity.items():
            params[oid, 0] = float(np.clip(a, 0.0, 1.0))
        focus = np.array(sorted(o for o in style.focus if 0 <= o < n), np.int64)
        params[focus, 1] = 1.0
        if mode == "ghosted-ao":
            ao, edges = style.shaded(n)
            params[:n, 2], params[:n, 3] = ao, edges
        self._upload(self.styles, params)
        self._opacity = params[:n, 0]  # a view: as drawn (the ghosted context's too), for OrderMarks
        self.passes = []
        self.hull_draws = 0
        target.ensure(records.viewport)
        target.fbo.use()
        target.fbo.clear(*BACKGROUND, depth=1.0)
        gpu.bind_storage()
        gpu.bounds.bind_to_storage_buffer(Storage.BOUNDS)
        self.styles.bind_to_storage_buffer(Storage.STYLES)
        atlas.color.use(Texture.ATLAS_COLOR)
        glraw.bind_texture_array(Texture.ATLAS_DEPTH, atlas.depth.glo)  # depth-keyed: no id image is read
        if projection is not None:
            atlas.normal.use(Texture.ATLAS_NORMAL)
        everyone = np.arange(n)
        outlined = style.outline_width >= 1
        if mode == "sprites":
            self._draw(everyone, style, records, sprite=True)
            if outlined:
                self._draw(focus, style, records, outline=True)  # highlights, seen through
        elif mode == "transparent":
            self._blend(back_to_front(records, view_depth, everyone), style, records, target, mode, desaturate=0.0)
            if outlined:
                self._draw(focus, style, records, outline=True)
        else:
            with_ao = mode == "ghosted-ao"
            if with_ao:
                post.texture.use(Texture.ATLAS_POST)
            in_context = np.ones(n, bool)
            in_context[focus] = False
            context = everyone[in_context]  # (a mask: setdiff1d's sort took 1.6 ms at 10^4 objects)
            # the focus outlines in the focus sprites' pass (at depth 0, so that nothing drawn
            # after covers them), unless a focus region is upsampled (outlines read texels)
            fused = outlined and not (records.scale[focus[records.visible[focus]]] < UPSAMPLE_BELOW).any()
            self._draw(focus, style, records, sprite=True, ao=with_ao, outlined=fused)
            params[context, 0] = style.context_opacity * params[context, 0]
            self._upload(self.styles, params)
            self._blend(
                back_to_front(records, view_depth, context),
                style,
                records,
                target,
                mode,
                behind=focus,
                behind_outlined=fused,
                desaturate=style.desaturate,
                depth_test=True,
                ao=with_ao,
                cut=True,
            )
            if style.halo > 0 and len(focus):
                self._halo(focus, context, style, records, target)
            if outlined and not fused:
                self._draw(focus, style, records, outline=True)

    def _halo(self, focus, context, style: Style, records: Records, target: CompositeTarget) -> None:
        """Halos around the focus objects where context lies behind them: the farthest
        context depth per pixel first (a depth-only sprite pass; focus objects are often
        inside the context, so the front-most context surface is in front of them), then one
        quad per focus object reaching `style.halo` pixels beyond its B_viewport."""
        if not 1 <= int(style.halo) <= 32:
            raise ValueError(f"halo width must be 0..32 pixels, got {style.halo}")
        self._sprite_depth(context, style, records, target, farthest=True, cut=True).use(Texture.CONTEXT_DEPTH)
        self._draw(focus, style, records, halo=True, depth_test=True)

    def _sprite_depth(
        self,
        ids,
        style: Style,
        records: Records,
        target: CompositeTarget,
        *,
        farthest: bool,
        cut: bool,
        outlined: bool = False,
    ) -> moderngl.Texture:
        """The nearest (or farthest) sprite depth of `ids` per pixel, in a depth texture of
        the target's size (1, or 0 for farthest, where none); the target is bound again after.
        `outlined`: their outlines at depth 0 (as the fused focus pass draws them)."""
        if self._context_depth is None or self._context_depth.size != target.size:
            self._release_context_depth()
            self._context_depth = self.ctx.depth_texture(target.size)
            self._context_depth.compare_func = ""
            self._context_fbo = self.ctx.framebuffer(depth_attachment=self._context_depth)
        self._context_fbo.viewport = (0, 0, *target.viewport)
        self._context_fbo.use()
        self._context_fbo.clear(depth=0.0 if farthest else 1.0)
        self._draw(ids, style, records, sprite=True, cut=cut, farthest=farthest, outlined=outlined)
        target.fbo.use()
        return self._context_depth

    def _release_context_depth(self) -> None:
        if self._context_depth is not None:
            release_framebuffer(self.ctx, self._context_fbo)
            self._context_depth.release()
        self._context_depth = self._context_fbo = None

    def _blend(
        self,
        ids,
        style: Style,
        records: Records,
        target: CompositeTarget,
        mode: str,
        behind=None,
        behind_outlined: bool = False,
        **how,
    ) -> None:
        """Blend `ids` (back to front) over the target: object by object, or per pixel in the
        order of their surfaces (style.order 'pixel', or 'auto' in `transparent`; object order
        where PixelOrderPass.begin refuses: over MAX_NODES, or a view too large for its targets).
        `behind`: opaque objects already drawn (the ghosted focus); surfaces behind them are
        hidden, by the depth test in object order and by their depth per pixel in pixel order;
        `behind_outlined`: their outlines were drawn with them (at depth 0: nothing covers them).
        With nothing behind, pixel order blends in object order as it collects, marking the
        pixels that order gets wrong (oit.OrderMarks), and resolves only those."""
        if resolved_order(style.order, mode) == "pixel" and len(ids):
            if self._pixel_order is None:
                self._pixel_order = PixelOrderPass(self.ctx)
            ids = np.asarray(ids, np.int64)
            ids = ids[records.visible[ids]]
            if self._pixel_order.begin(records.viewport, ids, records):
                clip = behind is not None and len(behind) > 0
                fetch = self._pixel_order.fetch
                if clip:
                    self._sprite_depth(
                        behind, style, records, target, farthest=False, cut=False, outlined=behind_outlined
                    ).use(Texture.FOCUS_DEPTH)
                self._pixel_order.collect_into(target, mark=not clip)
                try:  # clip: collected only, writing no depth (clipped by the focus depth instead);
                    # else blended in object order and sorted where that is wrong (oit.OrderMarks)
                    tested = not clip and not fetch
                    self._draw(
                        ids,
                        style,
                        records,
                        collect=True,
                        blend=not clip,
                        focus_clip=clip,
                        first_fetched=fetch,
                        **{**how, "depth_test": tested, "depth_write": tested},
                    )
                finally:
                    self._pixel_order.end_collect()
                if clip:
                    self._pixel_order.resolve(target.fbo)
                else:
                    self._pixel_order.resolve(target.fbo, over=BACKGROUND, in_place=self._in_place(ids))
                target.fbo.use()
                self.passes.append("resolve")
                return
            self.fallbacks += 1
        self._draw(ids, style, records, blend=True, **how)

    @property
    def pixel_order_refusal(self) -> str | None:
        """Why the last fallback to object order happened (oit.PixelOrderPass.refusal)."""
        return self._pixel_order.refusal if self._pixel_order is not None else None

    def _in_place(self, ids) -> int:
        """oit.blended_in_place for the least opacity among `ids` (invisible surfaces add no rounding)."""
        a = self._opacity[ids]
        a = a[a > 0]
        return blended_in_place(a.min() if len(a) else 1.0)

    def _draw(self, ids, style: Style, records: Records, **how) -> None:
        """Draw `ids` in order: one draw per run of objects captured at one texel per pixel
        or more, and per run below it (those are upsampled); outlines read texels as they are."""
        ids = np.asarray(ids, np.int32)
        ids = ids[records.visible[ids]] if len(ids) else ids
        if len(ids) == 0:
            return
        low = records.scale[ids] < UPSAMPLE_BELOW
        if how.get("outline") or how.get("halo") or not low.any():
            return self._draw_run(ids, style, records, **how)
        cuts = np.flatnonzero(np.diff(low.astype(np.int8))) + 1
        for run in np.split(ids, cuts):
            self._draw_run(run, style, records, upsample=bool(records.scale[run[0]] < UPSAMPLE_BELOW), **how)

    def _draw_run(
        self,
        ids,
        style: Style,
        records: Records,
        *,
        sprite=False,
        blend=False,
        outline=False,
        desaturate=0.0,
        depth_test=False,
        ao=False,
        cut=False,
        upsample=False,
        collect=False,
        halo=False,
        farthest=False,
        focus_clip=False,
        outlined=False,
        depth_write=False,
        first_fetched=False,
    ) -> None:
        self._upload(self.order, np.ascontiguousarray(ids, np.int32))
        self.order.bind_to_storage_buffer(Storage.DRAW_LIST)
        projection = None if outline or halo else self._projection
        lens = self._lens if cut else None
        # upsampled pixels reach past the outline; small sprites do not repay the outline's cost
        hull = None if halo or upsample or self._hull is None or not worth_outlines(records, ids) else self._hull
        mode = {
            "MODE_SPRITE": sprite,
            "MODE_BLEND": blend,
            "MODE_OUTLINE": outline,
            "MODE_COLLECT": collect,
            "FIRST_FETCHED": collect and first_fetched,
            "MODE_HALO": halo,
            "FOCUS_CLIP": focus_clip,
            "SPRITE_OUTLINE": outlined and sprite,
            "OUTLINE_QUAD": (
                (outline or outlined)
                and int(style.outline_width) == 1
                and records.border >= 1
                and bool((records.scale[ids] == 1.0).all())
            ),
            "WITH_AO": ao and not outline,
            "PROJECTOR": projection is not None,
            "LENS": lens is not None,
            "UPSAMPLE": upsample,
        }
        on = [k for k, v in mode.items() if v]
        self.passes.append(
            "+".join(
                k.removeprefix("MODE_").removeprefix("SPRITE_").lower()
                for k in on
                if k not in ("OUTLINE_QUAD", "FIRST_FETCHED")
            )
        )
        prog, vao = self._program(**{k: True for k in on})
        prog["u_viewport"].value = tuple(float(v) for v in records.viewport)
        if projection is not None or lens is not None:
            prog["u_inv_view_proj"].write(self._inv_view_proj)
        prog["u_hull"].value = hull is not None
        if hull is not None:
            self.hull_draws += 1
            view_proj, eye = hull
            prog["u_view_proj"].write(view_proj)
            prog["u_eye"].value = eye
            prog["u_hull_margin"].value = hull_margin(records.scale[ids])
        if projection is not None:
            pass_, projector, origin = projection
            pass_.bind(prog, projector, origin)
        if lens is not None:
            lens_pass, lens_, origin = lens
            lens_pass.bind(prog, lens_, origin)
        for name, value in (
            ("u_desaturate", desaturate),
            ("u_edge_color", style.edge_color),
            ("u_outline_color", style.outline_color),
            ("u_outline_width", style.outline_width),
            ("u_halo_width", int(style.halo)),
            ("u_halo_color", tuple(style.halo_color)),
        ):
            if name in prog:  # the compiler drops what a variant does not use
                prog[name].value = value
        flags = moderngl.NOTHING
        if sprite or depth_test:
            flags |= moderngl.DEPTH_TEST
        if blend or halo:
            flags |= moderngl.BLEND
        self.ctx.enable_only(flags)
        self.ctx.depth_func = ">" if farthest else "<"
        self.ctx.blend_func = moderngl.ONE, moderngl.ONE_MINUS_SRC_ALPHA
        fbo = self.ctx.fbo
        fbo.depth_mask = bool(sprite or depth_write)
        masked = collect and not blend and not first_fetched  # else the collect framebuffer masks it
        if masked:
            fbo.color_mask = (False,) * 4
        fbo.use()
        vao.render(moderngl.POINTS, vertices=len(ids))
        fbo.depth_mask = True
        self.ctx.depth_func = "<"
        if masked:
            fbo.color_mask = (True,) * 4

    def release(self) -> None:
        self._release_context_depth()
        if self._pixel_order is not None:
            self._pixel_order.release()
        for obj in [*self._vaos.values(), *self._programs.values(), self.styles, self.order]:
            obj.release()
        self._vaos.clear()
        self._programs.clear()
