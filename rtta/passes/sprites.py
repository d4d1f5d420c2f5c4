"""Sprite draws (RTTA paper, section 3.2, Figure 3): one point per object, expanded into a quad over its B_viewport
(or the projected outline of its B_world), reading its own unoccluded atlas images; `SpriteDraw` says which kind.
`SpritePass.draw(ids, draw, style, records)` draws `ids` in order into the bound framebuffer, from the atlas, records
and style buffers CompositePass bound (rtta.gl.bindings), with the frame's projector, lens and outline hull
(`SpritePass.frame`). `ids` is a CPU list, or a `Listed`: a list on the GPU (compositing's GPU-driven draws,
order_gpu.GpuOrder), drawn with the CPU's per-draw choices made per sprite in the shaders and no read of R.
"""

from __future__ import annotations

import dataclasses
import functools
from dataclasses import dataclass
from enum import StrEnum
from typing import Literal

import moderngl
import numpy as np

from ..atlas.parameterize import Records
from ..gl import glsl
from ..gl.bindings import Storage
from .outlines import HULL_MIN_AREA, hull_margin, worth_outlines
from .style import Style

UPSAMPLE_BELOW = 0.999  # regions with fewer texels per pixel are upsampled
STAGES = {"vertex_shader": "composite.vert", "geometry_shader": "composite.geom", "fragment_shader": "composite.frag"}


class Kind(StrEnum):  # (a StrEnum hashes in C: a draw's key is hashed every frame)
    """What a draw does with its sprites (composite.frag's MODE_* defines)."""

    OPAQUE = "opaque"  # depth sprites: the STD picture reconstructed, depth written (MODE_SPRITE)
    BLENDED = "blended"  # blended over the target, in the order given (MODE_BLEND)
    COLLECTED = "collected"  # into per-pixel lists only, behind the focus depth dropped (FOCUS_CLIP)
    COLLECTED_BLENDED = "collected+blended"  # listed while blended in object order, order errors marked
    OUTLINES = "outlines"  # the silhouettes of highlighted objects, over everything (MODE_OUTLINE)
    HALOS = "halos"  # a halo around each object where the context lies behind it (MODE_HALO)


class Depth(StrEnum):
    """How a draw uses the depth buffer."""

    OFF = "off"  # neither tested nor written
    TESTED = "tested"  # tested against what is drawn, not written
    NEAREST = "nearest"  # tested and written, the nearest kept
    FARTHEST = "farthest"  # tested and written, the farthest kept


@dataclass(frozen=True)
class SpriteDraw:
    """One kind of sprite draw; the named constructors give the combinations compositing uses
    (one instance per choice, cached: frames make them without a call to __init__).

    Attributes
    ----------
    kind : Kind
        What the draw does with its sprites.
    depth : Depth
        How it uses the depth buffer.
    shaded : bool
        With the atlas post-processing's AO and edges (ghosted-ao).
    cut : bool
        The lens cuts these objects away where it holds them (the context).
    outlined : bool
        Opaque sprites that draw their own outlines, at depth 0 (the fused focus pass).
    fetched : bool
        Collected with each pixel's first surfaces in colour attachments (oit.OrderMarks).
    desaturate : float
        Desaturation of the blended colour, in [0, 1] (the ghosted context).
    upsample : bool
        The objects' regions are captured below one texel per pixel (UPSAMPLE_BELOW).
    """

    kind: Kind
    depth: Depth = Depth.OFF
    shaded: bool = False
    cut: bool = False
    outlined: bool = False
    fetched: bool = False
    desaturate: float = 0.0
    upsample: bool = False

    def __post_init__(self) -> None:
        collects = self.kind in (Kind.COLLECTED, Kind.COLLECTED_BLENDED)
        if self.outlined and self.kind is not Kind.OPAQUE:
            raise ValueError(f"only opaque sprites draw their own outlines, not {self.kind.value}")
        if self.fetched and not collects:
            raise ValueError(f"only collected sprites fetch their first surfaces, not {self.kind.value}")

    @classmethod
    @functools.cache
    def opaque(cls, *, shaded: bool = False, outlined: bool = False) -> SpriteDraw:
        """Depth sprites over the target (`sprites`; the ghosted focus)."""
        return cls(Kind.OPAQUE, Depth.NEAREST, shaded=shaded, outlined=outlined)

    @classmethod
    @functools.cache
    def depths(cls, *, farthest: bool, cut: bool, outlined: bool = False) -> SpriteDraw:
        """The nearest (or farthest) sprite depth per pixel, into a depth-only target."""
        return cls(Kind.OPAQUE, Depth.FARTHEST if farthest else Depth.NEAREST, cut=cut, outlined=outlined)

    @classmethod
    @functools.cache
    def transparent(cls) -> SpriteDraw:
        """Every object blended with its opacity, over nothing opaque (`transparent`)."""
        return cls(Kind.BLENDED)

    @classmethod
    @functools.cache
    def context(cls, *, desaturate: float, shaded: bool) -> SpriteDraw:
        """The ghosted context: faded, desaturated, blended behind-tested against the focus, cut by a lens."""
        return cls(Kind.BLENDED, Depth.TESTED, shaded=shaded, cut=True, desaturate=desaturate)

    @classmethod
    @functools.cache
    def outlines(cls) -> SpriteDraw:
        """The highlighted objects' silhouettes, seen through everything."""
        return cls(Kind.OUTLINES)

    @classmethod
    @functools.cache
    def halos(cls) -> SpriteDraw:
        """Halos around the focus objects, where the context lies behind them."""
        return cls(Kind.HALOS, Depth.TESTED)

    def collected(self, *, clip: bool, fetched: bool) -> SpriteDraw:
        """This blend collected per pixel (oit.PixelOrderPass): with `clip`, listed only and
        clipped by the focus depth; else blended in object order as it lists, depth tested and
        written (where not `fetched`) to mark the pixels that order gets wrong."""
        tested = not clip and not fetched
        kind = Kind.COLLECTED if clip else Kind.COLLECTED_BLENDED
        return dataclasses.replace(self, kind=kind, depth=Depth.NEAREST if tested else Depth.OFF, fetched=fetched)


@dataclass(frozen=True)
class Listed:
    """Ids to draw from a buffer on the GPU, in its order: the first `count`, or as many as the
    indirect DrawArrays commands in `command` say (order_gpu.GpuOrder's: one per variant).
    Objects not visible in R draw nothing (composite.geom), so a list may hold them.

    Attributes
    ----------
    ids : moderngl.Buffer
        int32 object ids.
    count : int
        How many to draw, where `command` is None.
    command : moderngl.Buffer or None
        (count, 1, 0, 0) uint32 commands 20 bytes apart, written on the GPU, of which the three
        at `firsts` are drawn, one variant each (SpritePass.draw_listed).
    firsts : tuple of int
        The commands of `command` to draw.
    variants : {"regions", "focus"}
        What those commands choose between. "regions" (order_gpu's first three): the regions
        drawn upsampled none, all, or some. "focus" (a focus list's, order_gpu.FOCUS_COMMANDS):
        every region at one texel per pixel (outlines by quads), none upsampled, or some.
    """

    ids: moderngl.Buffer
    count: int = 0
    command: moderngl.Buffer | None = None
    firsts: tuple[int, ...] = (0, 1, 2)
    variants: Literal["regions", "focus"] = "regions"


def quad_outlines(draw: SpriteDraw, style: Style, records) -> bool:
    """Whether `draw`'s outlines may be found by quads (composite.frag's OUTLINE_QUAD) where
    its regions are at one texel per pixel: outlines drawn, of width 1, with a border."""
    outlined = draw.kind is Kind.OUTLINES or draw.outlined
    return outlined and int(style.outline_width) == 1 and records.border >= 1


@functools.lru_cache(maxsize=256)
def _pass_name(on: tuple[str, ...]) -> str:
    """A draw's name in `SpritePass.passes`, from the defines it turned on."""
    skip = ("OUTLINE_QUAD", "FIRST_FETCHED")
    return "+".join(k.removeprefix("MODE_").removeprefix("SPRITE_").lower() for k in on if k not in skip)


def upload(buf: moderngl.Buffer, data) -> None:
    """`data`: bytes or a contiguous array (written as it is: no copy to bytes)."""
    size = memoryview(data).nbytes
    if buf.size < size:
        buf.orphan(max(size, 2 * buf.size))
    buf.write(data)


class SpritePass:
    """Draws sprites of one SpriteDraw kind; `passes` and `hull_draws` describe the frame's draws."""

    def __init__(self, ctx: moderngl.Context) -> None:
        self.ctx = ctx
        self._programs: dict[tuple, moderngl.Program] = {}
        self._vaos: dict[tuple, moderngl.VertexArray] = {}
        self._listed: dict[tuple, list] = {}  # draw_listed's variants per kind of draw
        self.order = ctx.buffer(reserve=16)
        self.passes: list[str] = []  # the draws of the last frame, for inspection
        self.hull_draws = 0  # draws of the last frame whose sprites covered projected outlines
        self._projection = self._lens = self._inv_view_proj = self._hull = None
        self.ortho_near: float | None = None

    def frame(
        self, *, projection=None, lens=None, inv_view_proj: bytes | None = None, hull=None, ortho_near=None
    ) -> None:
        """Start a frame: `projection` (ProjectorPass, Projector, origin) and `lens` (LensPass,
        Lens, origin) with `inv_view_proj` ((P V)^-1 bytes) to rebuild world positions; `hull`
        (P V bytes, eye): sprites over the projected outlines of B_world, else B_viewport."""
        self._projection, self._lens, self._inv_view_proj, self._hull = projection, lens, inv_view_proj, hull
        self.ortho_near = ortho_near  # an orthographic view: near / (far - near); None: perspective
        self.passes = []
        self.hull_draws = 0

    def _program(self, **defines) -> tuple[moderngl.Program, moderngl.VertexArray]:
        key = tuple(sorted(defines.items()))
        if key not in self._programs:
            prog = glsl.program(self.ctx, **glsl.stage_sources(STAGES, **defines))
            self._programs[key] = prog
            self._vaos[key] = self.ctx.vertex_array(prog, [])
        return self._programs[key], self._vaos[key]

    def listed(self, ids) -> Listed:
        """A small CPU list of ids (the focus) as a `Listed` (uploaded; no read of R)."""
        ids = np.ascontiguousarray(ids, np.int32)
        if len(ids):
            upload(self.order, ids)
        return Listed(self.order, len(ids))

    def draw(self, ids, draw: SpriteDraw, style: Style, records: Records) -> None:
        """Draw `ids` in order: one draw per run of objects captured at one texel per pixel
        or more, and per run below it (those are upsampled); outlines read texels as they are.
        A `Listed` is drawn as one run, each sprite choosing for itself (`draw_listed`)."""
        if isinstance(ids, Listed):
            return self.draw_listed(ids, draw, style, records)
        ids = np.asarray(ids, np.int32)
        ids = ids[records.visible[ids]] if len(ids) else ids
        if len(ids) == 0:
            return
        low = records.scale[ids] < UPSAMPLE_BELOW
        if draw.kind in (Kind.OUTLINES, Kind.HALOS) or not low.any():
            return self._run(ids, draw, style, records)
        cuts = np.flatnonzero(np.diff(low.astype(np.int8))) + 1
        for run in np.split(ids, cuts):
            upsample = bool(records.scale[run[0]] < UPSAMPLE_BELOW)
            self._run(run, dataclasses.replace(draw, upsample=upsample), style, records)

    def draw_listed(self, listed: Listed, draw: SpriteDraw, style: Style, records) -> None:
        """Draw a GPU list: each sprite over its projected outline where its own B_viewport is
        large enough (composite.geom's HULL_PER_SPRITE); with a `command` (order_gpu.GpuOrder's
        three), one draw call per variant, of which the GPU gave one the list and the others
        nothing: regions upsampled none, all (UPSAMPLE), or some (UPSAMPLE_DYNAMIC: each sprite
        chooses; on llvmpipe a branch costs both sides); a CPU-made list draws UPSAMPLE_DYNAMIC.
        The general outline variant (OUTLINE_QUAD needs every scale). `records` need only
        `viewport` (a GpuRecords is not read)."""
        if listed.command is None and listed.count == 0:
            return
        listed.ids.bind_to_storage_buffer(Storage.DRAW_LIST)
        quad = listed.variants == "focus" and quad_outlines(draw, style, records)
        on = (self._projection is not None, self._lens is not None)
        key = (draw, listed.command is None, listed.variants, quad, on)
        variants = self._listed.get(key)
        if variants is None:  # the variants' programs: made once per kind of draw, not every frame
            variants = self._listed[key] = self._listed_variants(listed, draw, style, records, quad)
        hull = None if draw.kind is Kind.HALOS else self._hull
        values = self._values(draw, style, records, hull)  # the same for each variant's program
        values["u_upsample_below"], values["u_hull_min_area"] = UPSAMPLE_BELOW, float(HULL_MIN_AREA)
        held = self._state(draw)  # the variants' calls share it: set once, not once a variant
        for i, (prog, vao, name, projector, lens_on) in variants:
            self.passes.append(name)
            glsl.set_uniforms(prog, values)
            if projector or lens_on:
                self._bind_cuts(prog, projector, lens_on)
            if i is None:
                vao.render(moderngl.POINTS, vertices=listed.count)
            else:
                vao.render_indirect(listed.command, moderngl.POINTS, count=1, first=listed.firsts[i])
        self._defaults(*held)
        self.hull_draws += hull is not None  # one list: one draw, whichever variant

    def _listed_variants(self, listed: Listed, draw: SpriteDraw, style: Style, records, quad: bool) -> list:
        """(which of `listed.firsts`, or None for a CPU list's count; `_variant`) per draw call."""
        sampled = draw.kind not in (Kind.OUTLINES, Kind.HALOS)
        chosen: list[tuple[int | None, dict]] = [(None, {"UPSAMPLE_DYNAMIC": sampled})]
        if listed.command is not None and listed.variants == "regions":
            chosen = [(0, {}), (1, {"UPSAMPLE": sampled}), (2, {"UPSAMPLE_DYNAMIC": sampled})]
        elif listed.command is not None:  # a focus list: its outlines by quads where every region is at scale 1
            chosen = [(0, {"OUTLINE_QUAD": quad}), (1, {}), (2, {"UPSAMPLE_DYNAMIC": sampled})]
        base = {**self._defines(None, draw, style, records), "HULL_PER_SPRITE": True}
        return [(i, self._variant({**base, **extra})) for i, extra in chosen]

    def _defines(self, ids, draw: SpriteDraw, style: Style, records: Records) -> dict[str, bool]:
        """The draw's variant; `ids` None: a GPU list (no OUTLINE_QUAD: it needs their scales)."""
        kind, outline = draw.kind, draw.kind is Kind.OUTLINES
        return {
            "MODE_SPRITE": kind is Kind.OPAQUE,
            "MODE_BLEND": kind in (Kind.BLENDED, Kind.COLLECTED_BLENDED),
            "MODE_OUTLINE": outline,
            "MODE_COLLECT": kind in (Kind.COLLECTED, Kind.COLLECTED_BLENDED),
            "FIRST_FETCHED": draw.fetched,
            "MODE_HALO": kind is Kind.HALOS,
            "FOCUS_CLIP": kind is Kind.COLLECTED,
            "SPRITE_OUTLINE": draw.outlined,
            "OUTLINE_QUAD": (
                ids is not None and quad_outlines(draw, style, records) and bool((records.scale[ids] == 1.0).all())
            ),
            "WITH_AO": draw.shaded and not outline,
            "PROJECTOR": self._projection is not None and kind not in (Kind.OUTLINES, Kind.HALOS),
            "LENS": self._lens is not None and draw.cut,
            "UPSAMPLE": draw.upsample,
        }

    def _run(self, ids, draw: SpriteDraw, style: Style, records: Records) -> None:
        upload(self.order, np.ascontiguousarray(ids, np.int32))
        self.order.bind_to_storage_buffer(Storage.DRAW_LIST)
        defines = self._defines(ids, draw, style, records)
        # upsampled pixels reach past the outline; small sprites do not repay the outline's cost
        halo = draw.kind is Kind.HALOS
        hull = None if halo or draw.upsample or self._hull is None or not worth_outlines(records, ids) else self._hull
        margin = hull_margin(records.scale[ids]) if hull is not None else 0.0
        vao = self._use(self._variant(defines), draw, style, records, hull, margin)
        held = self._state(draw)  # the draw's GL state around its call, then the defaults back
        vao.render(moderngl.POINTS, vertices=len(ids))
        self._defaults(*held)

    def _variant(self, defines: dict[str, bool]) -> tuple:
        """(program, vertex array, pass name, projector on, lens on) of a draw's defines."""
        on = tuple(k for k, v in defines.items() if v)
        prog, vao = self._program(**dict.fromkeys(on, True))
        return prog, vao, _pass_name(on), defines["PROJECTOR"], defines["LENS"]

    def _use(self, variant: tuple, draw: SpriteDraw, style: Style, records, hull, margin=0.0):
        """A `_variant`'s uniforms set for this draw (`hull`: (P V bytes, eye) or None, `margin`
        its growth in pixels); returns its vertex array."""
        prog, vao, name, projector, lens_on = variant
        self.passes.append(name)
        self.hull_draws += hull is not None
        glsl.set_uniforms(prog, self._values(draw, style, records, hull, margin))
        if projector or lens_on:
            self._bind_cuts(prog, projector, lens_on)
        return vao

    def _values(self, draw: SpriteDraw, style: Style, records, hull, margin=0.0) -> dict:
        viewport = records.viewport  # (set_uniforms skips the uniforms a variant's compiler dropped)
        values = {  # a draw's uniforms
            "u_viewport": (float(viewport[0]), float(viewport[1])),
            "u_hull": hull is not None,
            "u_desaturate": draw.desaturate,
            "u_edge_color": style.edge_color,
            "u_outline_color": style.outline_color,
            "u_outline_width": style.outline_width,
            "u_halo_width": int(style.halo),
            "u_halo_color": tuple(style.halo_color),
            "u_ortho_depth": (0.0, 0.0) if self.ortho_near is None else (1.0, self.ortho_near),
        }
        if self._projection is not None or self._lens is not None:
            values["u_inv_view_proj"] = self._inv_view_proj
        if hull is not None:
            values["u_view_proj"], values["u_eye"] = hull
            values["u_hull_margin"] = margin  # UPSAMPLE_DYNAMIC: each sprite's own
        return values

    def _bind_cuts(self, prog: moderngl.Program, projector: bool, lens_on: bool) -> None:
        """The frame's projector and lens bound for a variant that reads them."""
        if projector and self._projection is not None:
            pass_, projector_, origin = self._projection
            pass_.bind(prog, projector_, origin)
        if lens_on and self._lens is not None:
            lens_pass, lens_, origin = self._lens
            lens_pass.bind(prog, lens_, origin)

    def _state(self, draw: SpriteDraw) -> tuple:
        """The GL state of `draw`'s calls; what `_defaults` needs back. `ctx.fbo` is bound again
        only for a colour mask: moderngl applies one of a single attachment at `use()` alone."""
        blended = draw.kind in (Kind.BLENDED, Kind.COLLECTED_BLENDED, Kind.HALOS)
        tested = draw.depth is not Depth.OFF
        self.ctx.enable_only((moderngl.DEPTH_TEST if tested else 0) | (moderngl.BLEND if blended else 0))
        self.ctx.depth_func = ">" if draw.depth is Depth.FARTHEST else "<"
        self.ctx.blend_func = moderngl.ONE, moderngl.ONE_MINUS_SRC_ALPHA
        fbo = self.ctx.fbo
        fbo.depth_mask = draw.depth in (Depth.NEAREST, Depth.FARTHEST)
        masked = draw.kind is Kind.COLLECTED and not draw.fetched  # else the collect framebuffer masks it
        if masked:
            fbo.color_mask = (False, False, False, False)
            fbo.use()
        return fbo, masked

    def _defaults(self, fbo: moderngl.Framebuffer, masked: bool) -> None:
        """The state `_state` changed, back to the defaults."""
        fbo.depth_mask = True
        self.ctx.depth_func = "<"
        if masked:
            fbo.color_mask = (True, True, True, True)
            fbo.use()

    def release(self) -> None:
        for obj in [*self._vaos.values(), *self._programs.values(), self.order]:
            obj.release()
        self._vaos.clear()
        self._programs.clear()
        self._listed.clear()
