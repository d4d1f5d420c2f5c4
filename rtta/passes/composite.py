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

Here the order of a mode's draws (CompositePass); each draw is a SpriteDraw of sprites.py
(SpritePass), the options are style.py's (Style, Mode, Order, Role). Where R stays on the GPU
(a GpuRecords), the draws come from GPU lists (composite_gpu.py, order_gpu.py).
"""

from __future__ import annotations

import moderngl
import numpy as np

from ..atlas.parameterize import Records
from ..errors import member
from ..gl import glraw, sync
from ..gl.bindings import Storage, Texture
from ..gl.glsl import mat_bytes
from ..gl.gpu import GpuScene
from ..gl.targets import SHRINK_AFTER_FRAMES, CompositeTarget, LayeredTarget, release_framebuffer
from .blend_tiles import BlendOn
from .composite_gpu import GpuDraws, gpu_driven
from .oit import PixelOrderPass, Refusal, blended_in_place, resolved_order
from .sprites import UPSAMPLE_BELOW, Depth, SpriteDraw, SpritePass, upload
from .style import BACKGROUND, LENS_MODES, MODES, ROLES, Mode, ModeName, Order, Style, focus_ids, style_params

# re-exported: what the renderer, the viewer, the benchmarks and the tests import from here
__all__ = ["BACKGROUND", "LENS_MODES", "MODES", "ROLES", "CompositePass", "CompositeTarget", "Style", "back_to_front"]


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
    """The atlas composited into a target: `render(*, atlas, records, gpu, style, mode, view_depth
    or view, target)` draws every sprite draw of the mode (SpritePass), blending in object or
    pixel order (oit.PixelOrderPass); needs `post` (AtlasPostPass) for ghosted-ao. With R on the
    GPU (a GpuRecords) and `view`, most frames draw from GPU lists (`gpu_driven`; composite_gpu.py)."""

    def __init__(self, ctx: moderngl.Context) -> None:
        self.ctx = ctx
        self.sprites = SpritePass(ctx)
        self.styles = ctx.buffer(reserve=16)
        self._pixel_order = None  # PixelOrderPass, made on first use, released after SHRINK_AFTER_FRAMES unused
        self._pixel_order_idle = 0  # renders since the per-pixel lists were last used
        self._context_depth: moderngl.Texture | None = None  # front-most context depth, for halos
        self._context_fbo: moderngl.Framebuffer | None = None
        self.fallbacks = 0  # frames that asked for pixel order and got object order
        self._opacity = np.zeros(0, np.float32)  # per object, as the last render draws them
        self._gpu: GpuDraws | None = None  # the GPU-driven branch's state, made on first use
        self.gpu_driven = False  # whether the last render drew from GPU lists (composite_gpu)
        self.blend: BlendOn = "raster"  # how the GPU-driven branch blends in object order (Settings.blend)

    @property
    def passes(self) -> list[str]:
        """The draws of the last render, for inspection (SpritePass.passes, and 'resolve')."""
        return self.sprites.passes

    @property
    def hull_draws(self) -> int:
        """Draws of the last render whose sprites covered projected outlines."""
        return self.sprites.hull_draws

    def render(
        self,
        *,
        atlas: LayeredTarget,
        records: Records,
        gpu: GpuScene,
        style: Style,
        mode: ModeName | Mode,
        view_depth: np.ndarray | None = None,
        target: CompositeTarget,
        post=None,
        view_proj=None,
        projection=None,
        lens=None,
        eye=None,
        ortho_near: float | None = None,
        view: np.ndarray | None = None,
        offsets: np.ndarray | None = None,
    ) -> None:
        """Composite the captured atlas into `target` (sized to the records' viewport).
        `projection`: (ProjectorPass, Projector, scene origin) to paint with; `lens`: (LensPass,
        Lens, scene origin) cutting the context away in the ghosted modes. Both need `view_proj`.
        `eye`: the camera's position (scene origin at 0); with `view_proj`, sprites cover the
        projected outline of each object's B_world instead of all of B_viewport.

        The back-to-front order is by `view_depth` (per object: the view depth of its bounds
        centre), or from `view` (the view matrix, scene origin at 0) and the bounds centres:
        on the GPU from `gpu.bounds` (moved as drawn), on the CPU from the scene's bounds
        moved by `offsets` ([n, 3] explode offsets; None: none).

        GPU-driven (`gpu_driven` after the call): where `records` is a GpuRecords and `view` is
        given, `ghosted`, `ghosted-ao`, `sprites` and `transparent` in object order (with
        outlines and halos) draw from lists sorted on the GPU and read nothing of R back
        (composite_gpu.py); pixel order, a lens and a projector take the CPU branch, which
        reads R back (GpuRecords.read)."""
        if lens is not None and mode not in LENS_MODES:
            lens = None
        found = member(Mode, mode)
        if found is None:
            raise ValueError(f"unknown mode {mode!r}; modes: {', '.join(MODES)}")
        mode = found
        inv_view_proj = None  # (P V)^-1 once per render, for every draw that rebuilds world positions
        if projection is not None or lens is not None:
            if view_proj is None:
                raise ValueError("a projection or a lens needs view_proj")
            inv_view_proj = mat_bytes(np.linalg.inv(view_proj))
        self.sprites.frame(
            projection=projection,
            lens=lens,
            inv_view_proj=inv_view_proj,
            hull=None if eye is None or view_proj is None else (mat_bytes(view_proj), tuple(np.asarray(eye).tolist())),
            ortho_near=ortho_near,
        )
        self._pixel_order_idle += 1
        if self._pixel_order is not None and self._pixel_order_idle > SHRINK_AFTER_FRAMES:
            self._pixel_order.release()  # its lists and nodes: tens of MB held for a mode no longer shown
            self._pixel_order = None
        self.gpu_driven = gpu_driven(records, mode, style, view, projection, lens)
        if self.gpu_driven:
            return self._render_gpu(atlas, records, gpu, style, mode, view, target, post)
        if self._gpu is not None:
            self._gpu.styles_key = None  # the style buffer is written below
        n = len(records.visible)
        if view_depth is None:
            if view is None:
                raise ValueError("compositing needs view_depth or view")
            view_depth = self.view_depth(gpu, view, offsets)
        params = style_params(style, mode, n)
        focus = focus_ids(style, n)
        upload(self.styles, params)
        self._opacity = params[:n, 0]  # a view: as drawn (the ghosted context's too), for OrderMarks
        self._bind(atlas, gpu, target, records, projection)
        everyone = np.arange(n)
        outlined = style.outline_width >= 1
        draw = self.sprites.draw
        if mode is Mode.SPRITES:
            draw(everyone, SpriteDraw.opaque(), style, records)
            if outlined:
                draw(focus, SpriteDraw.outlines(), style, records)  # highlights, seen through
        elif mode is Mode.TRANSPARENT:
            ordered = back_to_front(records, view_depth, everyone)
            self._blend(ordered, SpriteDraw.transparent(), style, records, target, mode)
            if outlined:
                draw(focus, SpriteDraw.outlines(), style, records)
        else:
            with_ao = _use_post(mode, post)
            in_context = np.ones(n, bool)
            in_context[focus] = False
            context = everyone[in_context]  # (a mask: setdiff1d's sort took 1.6 ms at 10^4 objects)
            # the focus outlines in the focus sprites' pass (at depth 0, so that nothing drawn
            # after covers them), unless a focus region is upsampled (outlines read texels)
            fused = outlined and not (records.scale[focus[records.visible[focus]]] < UPSAMPLE_BELOW).any()
            draw(focus, SpriteDraw.opaque(shaded=with_ao, outlined=fused), style, records)
            params[context, 0] = style.context_opacity * params[context, 0]
            upload(self.styles, params)
            faded = SpriteDraw.context(desaturate=style.desaturate, shaded=with_ao)
            self._blend(back_to_front(records, view_depth, context), faded, style, records, target, mode, focus, fused)
            if style.halo > 0 and len(focus):
                self._halo(focus, context, style, records, target)
            if outlined and not fused:
                draw(focus, SpriteDraw.outlines(), style, records)

    @staticmethod
    def view_depth(gpu: GpuScene, view: np.ndarray, offsets: np.ndarray | None = None) -> np.ndarray:
        """The view depth of each object's bounds centre (moved by `offsets`), for the CPU branch."""
        scene = gpu.scene
        centers = (scene.aabb_min + scene.aabb_max) / 2 - scene.origin + (0.0 if offsets is None else offsets)
        return -(centers @ view[2, :3] + view[2, 3])

    def _bind(self, atlas: LayeredTarget, gpu: GpuScene, target: CompositeTarget, records, projection=None) -> None:
        """The target cleared and bound, the buffers and atlas images bound for the sprite draws."""
        target.ensure(records.viewport)
        target.fbo.use()
        target.fbo.clear(*BACKGROUND, depth=1.0)
        gpu.bind_storage()
        gpu.bounds.bind_to_storage_buffer(Storage.BOUNDS)
        self.styles.bind_to_storage_buffer(Storage.STYLES)
        atlas.color.use(Texture.ATLAS_COLOR)
        glraw.bind_texture_array(Texture.ATLAS_DEPTH, atlas.depth.glo)  # depth-keyed: no id image is read
        if projection is not None:
            if atlas.normal is None:
                raise ValueError("a projection reads the atlas normals: an atlas made with normals=False has none")
            atlas.normal.use(Texture.ATLAS_NORMAL)

    def _render_gpu(self, atlas, records, gpu: GpuScene, style: Style, mode: Mode, view, target, post) -> None:
        """The GPU-driven branch (composite_gpu.py): the same draws as the CPU branch's, from
        GPU lists; the ghosted focus draws its outlines in its own pass (fused) whether its
        regions are upsampled or not (composite.frag draws a silhouette texel that the
        upsampling leaves uncovered, as the outline pass would)."""
        if self._gpu is None:
            self._gpu = GpuDraws(self.ctx)
        n = records.count
        self._gpu.styles(self.styles, style, mode, n)
        focus = focus_ids(style, n)
        focused = self.sprites.listed(focus) if len(focus) else None
        draw = self.sprites.draw
        outlined = style.outline_width >= 1 and focused is not None
        if mode is Mode.SPRITES:
            every = self._gpu.everyone(n=n, gpu=gpu, styles=self.styles, focus=focused)
            self._bind(atlas, gpu, target, records)
            draw(every, SpriteDraw.opaque(), style, records)
        elif mode is Mode.TRANSPARENT:
            ordered = self._gpu.sorted(n=n, gpu=gpu, view=view, styles=self.styles, focus=focused, context=False)
            sync.kick(self.ctx)
            self._bind(atlas, gpu, target, records)
            self._blend_listed(ordered, SpriteDraw.transparent(), style, records, target)
        else:
            with_ao = _use_post(mode, post)
            context = self._gpu.sorted(n=n, gpu=gpu, view=view, styles=self.styles, focus=focused)
            sync.kick(self.ctx)  # a GPU sorts while the draws are made
            self._bind(atlas, gpu, target, records)
            if focused is not None:  # with their outlines (at depth 0: nothing drawn after covers them)
                opaque = SpriteDraw.opaque(shaded=with_ao, outlined=outlined)
                draw(self._gpu.focus_drawn(focused), opaque, style, records)
            faded = SpriteDraw.context(desaturate=style.desaturate, shaded=with_ao)
            self._blend_listed(context, faded, style, records, target)
            if style.halo > 0 and focused is not None:
                self._halo(focused, context, style, records, target)
        if outlined and focused is not None and mode in (Mode.SPRITES, Mode.TRANSPARENT):
            draw(self._gpu.focus_drawn(focused), SpriteDraw.outlines(), style, records)

    def _blend_listed(self, listed, draw: SpriteDraw, style: Style, records, target: CompositeTarget) -> None:
        """A GPU list blended in its order: as sprites, or in a compute pass (`blend`)."""
        if self.blend == "raster":
            return self.sprites.draw(listed, draw, style, records)
        assert self._gpu is not None
        self._gpu.tiles.draw(listed, draw, style, target, self.sprites.ortho_near)
        self.sprites.passes.append("blend_tiles" + ("+ao" if draw.shaded else ""))

    def _halo(self, focus, context, style: Style, records: Records, target: CompositeTarget) -> None:
        """Halos around the focus objects where context lies behind them: the farthest
        context depth per pixel first (a depth-only sprite pass; focus objects are often
        inside the context, so the front-most context surface is in front of them), then one
        quad per focus object reaching `style.halo` pixels beyond its B_viewport."""
        if not 1 <= int(style.halo) <= 32:
            raise ValueError(f"halo width must be 0..32 pixels, got {style.halo}")
        depths = SpriteDraw.depths(farthest=True, cut=True)
        self._sprite_depth(context, depths, style, records, target).use(Texture.CONTEXT_DEPTH)
        self.sprites.draw(focus, SpriteDraw.halos(), style, records)

    def _sprite_depth(
        self, ids, draw: SpriteDraw, style: Style, records: Records, target: CompositeTarget
    ) -> moderngl.Texture:
        """The nearest (or farthest) sprite depth of `ids` per pixel (`draw`: SpriteDraw.depths),
        in a depth texture of the target's size (1, or 0 for farthest, where none); the target
        is bound again after."""
        depth, fbo = self._context_depth, self._context_fbo
        if depth is None or fbo is None or depth.size != target.size:
            self._release_context_depth()
            self._context_depth = depth = self.ctx.depth_texture(target.size)
            depth.compare_func = ""
            self._context_fbo = fbo = self.ctx.framebuffer(depth_attachment=depth)
        fbo.viewport = (0, 0, *target.viewport)
        fbo.use()
        fbo.clear(depth=0.0 if draw.depth is Depth.FARTHEST else 1.0)
        self.sprites.draw(ids, draw, style, records)
        target.fbo.use()
        return depth

    def _release_context_depth(self) -> None:
        if self._context_depth is not None:
            release_framebuffer(self.ctx, self._context_fbo)
            self._context_depth.release()
        self._context_depth = self._context_fbo = None

    def _blend(
        self,
        ids,
        draw: SpriteDraw,
        style: Style,
        records: Records,
        target: CompositeTarget,
        mode: Mode,
        behind=None,
        behind_outlined: bool = False,
    ) -> None:
        """Blend `ids` (back to front) over the target with `draw` (a blended SpriteDraw): object
        by object, or per pixel in the order of their surfaces (style.order 'pixel', or 'auto' in
        `transparent`; object order where PixelOrderPass.begin refuses: over MAX_NODES, or a view
        too large for its targets). `behind`: opaque objects already drawn (the ghosted focus);
        surfaces behind them are hidden, by the depth test in object order and by their depth
        per pixel in pixel order; `behind_outlined`: their outlines were drawn with them (at
        depth 0: nothing covers them). With nothing behind, pixel order blends in object order
        as it collects, marking the pixels that order gets wrong (oit.OrderMarks), and resolves
        only those."""
        if resolved_order(style.order, mode) is Order.PIXEL and len(ids):
            if self._pixel_order is None:
                self._pixel_order = PixelOrderPass(self.ctx)
            self._pixel_order_idle = 0
            ids = np.asarray(ids, np.int64)
            ids = ids[records.visible[ids]]
            if self._pixel_order.begin(records.viewport, ids, records):
                clip = behind is not None and len(behind) > 0
                fetch = self._pixel_order.fetch
                if clip:
                    depths = SpriteDraw.depths(farthest=False, cut=False, outlined=behind_outlined)
                    self._sprite_depth(behind, depths, style, records, target).use(Texture.FOCUS_DEPTH)
                self._pixel_order.collect_into(target, mark=not clip)
                try:  # clip: collected only, writing no depth (clipped by the focus depth instead);
                    # else blended in object order and sorted where that is wrong (oit.OrderMarks)
                    self.sprites.draw(ids, draw.collected(clip=clip, fetched=fetch), style, records)
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
        self.sprites.draw(ids, draw, style, records)

    @property
    def pixel_order_refusal(self) -> Refusal | None:
        """Why the last fallback to object order happened (oit.PixelOrderPass.refusal)."""
        return self._pixel_order.refusal if self._pixel_order is not None else None

    def _in_place(self, ids) -> int:
        """oit.blended_in_place for the least opacity among `ids` (invisible surfaces add no rounding)."""
        a = self._opacity[ids]
        a = a[a > 0]
        return blended_in_place(a.min() if len(a) else 1.0)

    def release(self) -> None:
        self._release_context_depth()
        if self._pixel_order is not None:
            self._pixel_order.release()
        if self._gpu is not None:
            self._gpu.release()
        self.sprites.release()
        self.styles.release()


def _use_post(mode: Mode, post) -> bool:
    """Whether the mode shades with AO and edges (ghosted-ao); then the post-processed atlas
    is bound (`post`: AtlasPostPass, rendered)."""
    if mode is not Mode.GHOSTED_AO:
        return False
    if post is None or post.texture is None:
        raise ValueError("ghosted-ao needs the post-processed atlas (post, AtlasPostPass)")
    post.texture.use(Texture.ATLAS_POST)
    return True
