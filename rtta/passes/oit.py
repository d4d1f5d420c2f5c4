"""`--order pixel`: transparency blended per pixel in the order of the objects' own front
surfaces, which the atlas holds for every object (nested and interpenetrating parts blend
correctly, where the object order by bounding-box centre cannot).

One pass over the sprite quads writes every covered (pixel, object) surface into a per-pixel
linked list (an atomic exchange of the pixel's head; a surface's node is fixed by its
pixel's place in the object's B_viewport, so no counter is shared), then one pass over the
union of the drawn objects' B_viewport walks each list front to back
(shaders/oit_resolve.frag: the K = 8 nearest in exact order, the rest merged behind them,
weighted blended). Chosen over depth peeling, which draws every sprite quad once per layer
(BENCHMARKS.md in git history). The nodes need 16 bytes per pixel of the drawn objects' viewport
rectangles; a frame needing more than MAX_NODES blends in object order instead (the caller
counts it).

Where nothing lies behind the blend (`transparent`), most pixels need no sorting: the pass
that lists the surfaces also blends them in object order (OrderMarks), with a depth test that
marks in the stencil every pixel where a surface lies behind one blended before it. Elsewhere
the object order is the depth order and that blend is exact (within the 8-bit target's
rounding: ROUNDING_BUDGET); only the marked pixels (13% of the demo's covered pixels, 27% of
the engine's, 9-13% of 10,000 parts') are resolved, over the background.

Where the driver reads the framebuffer in the shader, in draw order (FETCH_EXTENSIONS: Mesa's
llvmpipe has them, NVIDIA's driver not), the same pass keeps each pixel's first three surfaces
in two colour attachments and its count and mark in the stencil, all read and written by the
shader itself: no atomics, no depth test, and nodes only for a pixel's fourth surface on
(OrderMarks with `fetched`). On llvmpipe the atomic exchange and the node stores were 40% of
the `transparent` composite: with the first surfaces fetched, the demo's list pass takes 23.5 ms
against 29.1 at 1024², the resolve 4.7 against 8.5 (docs/performance/order.md). Both ways give the same
picture; the tests run both.
"""

from __future__ import annotations

from typing import Literal

import moderngl
import numpy as np

from ..atlas.parameterize import Records
from ..gl import glraw, glsl
from ..gl.bindings import Storage, Texture
from ..gl.targets import release_all
from .style import ORDERS as ORDERS  # re-exported: the choices of --order
from .style import Mode, ModeName, Order, OrderName, choice

Refusal = Literal["surfaces", "target"]  # why PixelOrderPass.begin refused: over MAX_NODES, or LISTS/FETCH bytes
# each pixel's first surfaces in colour attachments and its count and order mark in the stencil,
# read and written in draw order by the shader (no atomics): where the driver has these (Mesa's
# llvmpipe does; NVIDIA's driver not)
FETCH_EXTENSIONS = (
    "GL_EXT_shader_framebuffer_fetch",
    "GL_ARM_shader_framebuffer_fetch_depth_stencil",
    "GL_ARB_shader_stencil_export",
)
MAX_NODES = 1 << 23  # 8 Mi surfaces, 128 MiB of nodes
# the fetched first surfaces take 33 bytes per pixel of the target (two RGBA32UI and a stencil),
# the lists 12 (heads and a depth-stencil): a larger target keeps the lists (4K: 274 MiB, fetched)
FETCHED_BYTES_PER_PIXEL = 33
FETCH_MAX_BYTES = 384 * 2**20
LIST_BYTES_PER_PIXEL = 12
LISTS_MAX_BYTES = 768 * 2**20  # 64 Mpx (8K: 398 MiB); beyond, object order (refusal 'target')
# OrderMarks: a pixel whose surfaces all came in depth order keeps the object-order blend,
# rounded to 8 bits at each surface; the error each rounding leaves is damped by (1 - a) for
# every surface blended over it, so n surfaces of opacity a or more leave at most
# sum_{k<n} (1 - a)^k roundings' worth. Pixels with more surfaces than keep that within
# ROUNDING_BUDGET go to the resolve (float, the K = 8 rule) as out-of-order ones do.
# Measured against the float resolve (demo, engine, cycloidal, 27 composites): opacity 0.5,
# every in-order pixel in place: 2/255 at most; opacity 0.1 with 4 in place: 3/255.
ROUNDING_BUDGET = 2.5
STENCIL_OUT_OF_ORDER = 255
STENCIL_COUNT = 127  # with `fetched` marks: the count's bits (oit.glsl), the flag 128 above them
NODE_BYTES = 16


def resolved_order(order: OrderName | Order, mode: ModeName | Mode) -> Order:
    """Order.OBJECT or Order.PIXEL: what `order` means in `mode` (auto: pixel in transparent, where
    object order leaves 3.5-6.3% of pixels over 8/255 at 1.2-1.4x the frame; object for the
    ghosted context, faded and desaturated, whose frame budget is set against STD)."""
    chosen = choice(Order, order, "order")
    if chosen is not Order.AUTO:
        return chosen
    return Order.PIXEL if mode == Mode.TRANSPARENT else Order.OBJECT


def blended_in_place(min_opacity: float) -> int:
    """How many surfaces, all in depth order, a pixel may have and keep the object-order
    blend, when the drawn objects' opacity is at least `min_opacity` (ROUNDING_BUDGET)."""
    keep = 1.0 - min(max(float(min_opacity), 0.0), 1.0)
    total, n = 0.0, 0
    while n < STENCIL_OUT_OF_ORDER - 1 and total + keep**n <= ROUNDING_BUDGET:
        total += keep**n
        n += 1
    return max(n, 1)


def first_fetched(ctx: moderngl.Context) -> bool:
    """Whether `ctx` lets the collect read and write each pixel's first surfaces, its count and
    its order mark as framebuffer attachments, in draw order (FETCH_EXTENSIONS)."""
    return all(e in ctx.extensions for e in FETCH_EXTENSIONS)


def node_bases(records: Records, ids: np.ndarray) -> tuple[np.ndarray, int]:
    """(first node per object id [n] uint32, nodes in all): one node per pixel of each drawn
    object's B_viewport, objects one after the other."""
    r = records.viewport_rect[ids]
    area = (r[:, 2] - r[:, 0]) * (r[:, 3] - r[:, 1])
    base = np.zeros(len(records.visible), np.int64)
    base[ids] = np.cumsum(area) - area
    total = int(area.sum())
    return np.minimum(base, 0xFFFFFFFF).astype(np.uint32), total


class PixelOrderPass:
    """begin(viewport, ids, records) -> bool (False: use object order, `refusal` says why), then
    collect_into(target, mark), the caller's sprites drawn with MODE_COLLECT (and FIRST_FETCHED
    where `fetch`), end_collect(), then resolve(). `fetch` (first_fetched, and a target within
    FETCH_MAX_BYTES; set by begin): each pixel's first three surfaces and its count are
    framebuffer attachments (OrderMarks), only later surfaces nodes; else every surface is a
    node, linked by an atomic exchange of the pixel's head. `fetch=False` keeps the lists."""

    def __init__(self, ctx: moderngl.Context, fetch: bool | None = None) -> None:
        self.ctx = ctx
        self.can_fetch = first_fetched(ctx) if fetch is None else bool(fetch)
        self.fetch = self.can_fetch  # this frame's way (begin: FETCH_MAX_BYTES)
        self.heads = ctx.buffer(reserve=4)
        self.nodes = ctx.buffer(reserve=NODE_BYTES)
        self.bases = ctx.buffer(reserve=4)
        self.programs: dict[tuple[bool, bool], moderngl.Program] = {}  # (over, fetch), made on first use
        self.vaos: dict[tuple[bool, bool], moderngl.VertexArray] = {}
        self._marks: dict[bool, OrderMarks] = {}  # by fetch; one kept at a time
        self.refusal: Refusal | None = None  # why begin() last returned False
        self._width = 1
        self._rect = (-1.0, -1.0, 1.0, 1.0)

    @property
    def marks(self) -> OrderMarks | None:
        return self._marks.get(self.fetch)

    def begin(self, viewport: tuple[int, int], ids: np.ndarray, records: Records) -> bool:
        """Ready the buffers for `ids` in this viewport; False (the caller blends in object
        order) where the surfaces would pass MAX_NODES (`refusal` 'surfaces') or the per-pixel
        targets LISTS_MAX_BYTES ('target')."""
        bases, capacity = node_bases(records, ids)
        w, h = int(viewport[0]), int(viewport[1])
        self.fetch = self.can_fetch and w * h * FETCHED_BYTES_PER_PIXEL <= FETCH_MAX_BYTES
        self.refusal = (
            "surfaces"
            if capacity > MAX_NODES
            else "target"
            if not self.fetch and w * h * LIST_BYTES_PER_PIXEL > LISTS_MAX_BYTES
            else None
        )
        if self.refusal:
            return False
        self._width = w
        rects = records.viewport_rect[ids].reshape(-1, 4)
        lo, hi = (rects[:, :2].min(axis=0), rects[:, 2:].max(axis=0)) if len(rects) else ((0, 0), (0, 0))
        self._rect = (*(np.asarray(lo) / (w, h) * 2 - 1), *(np.asarray(hi) / (w, h) * 2 - 1))  # NDC
        if not self.fetch and self.heads.size < 4 * w * h:
            self.heads.orphan(4 * w * h)
        need = NODE_BYTES * max(capacity, 1)
        if self.nodes.size < need or self.nodes.size > 4 * need:  # shrink when far too big
            self.nodes.orphan(need)
        if self.bases.size < bases.nbytes:
            self.bases.orphan(max(bases.nbytes, 2 * self.bases.size))
        self.bases.write(bases.tobytes())
        if not self.fetch:
            self.heads.clear(size=4 * w * h)  # 0: no node (a pattern clear took 8 ms at 1024²)
            self.heads.bind_to_storage_buffer(Storage.OIT_HEADS)
        self.nodes.bind_to_storage_buffer(Storage.OIT_NODES)
        self.bases.bind_to_storage_buffer(Storage.OIT_BASES)
        return True

    def collect_into(self, target, mark: bool) -> None:
        """Bind the framebuffer the sprites are collected into (begin first): with `mark`,
        OrderMarks' for the object-order blend that lists and marks; else the target's, the
        colour left alone."""
        if not mark and not self.fetch:
            target.fbo.use()
            return
        marks = self.marks
        if marks is None:
            for other in self._marks.values():  # the other way's targets: released
                other.release()
            marks = OrderMarks(self.ctx, fetched=self.fetch)
            self._marks = {self.fetch: marks}
        marks.begin(target, mark)

    def end_collect(self) -> None:
        glraw.stencil_off()

    def resolve(self, fbo, over: tuple[float, ...] | None = None, in_place: int = 1) -> None:
        """Sort and blend every pixel's list over what `fbo` holds (the background); with
        `over`, over that colour, written as it is, on the pixels OrderMarks left to it only:
        out of order, or with more than `in_place` surfaces (blended_in_place)."""
        self.ctx.memory_barrier(moderngl.SHADER_STORAGE_BARRIER_BIT)
        marks = self.marks
        if marks is None and (self.fetch or over is not None):
            raise RuntimeError("PixelOrderPass.resolve: collect_into() first (the marks hold this way's surfaces)")
        if self.fetch and marks is not None:
            for unit, texture in zip((Texture.OIT_FIRST, Texture.OIT_MORE), marks.first, strict=True):
                texture.use(unit)
        else:
            self.heads.bind_to_storage_buffer(Storage.OIT_HEADS)
        self.nodes.bind_to_storage_buffer(Storage.OIT_NODES)
        key = (over is not None, self.fetch)
        if key not in self.programs:
            self.programs[key] = glsl.program(
                self.ctx,
                vertex_shader=glsl.load("oit_resolve.vert"),
                fragment_shader=glsl.load("oit_resolve.frag", OVER=key[0], FIRST_FETCHED=key[1]),
            )
            self.vaos[key] = self.ctx.vertex_array(self.programs[key], [])
        program = self.programs[key]
        if "u_width" in program:  # the heads as a texture need no width
            glsl.uniform(program, "u_width").value = self._width
        glsl.uniform(program, "u_rect").value = tuple(float(v) for v in self._rect)
        if over is not None and marks is not None:  # the stencil test, before the shader (it has no side effects)
            glsl.uniform(program, "u_background").value = tuple(float(v) for v in over[:3])
            self.ctx.enable_only(moderngl.NOTHING)
            fbo = marks.fbo
            glraw.stencil_above(min(int(in_place), marks.in_place_limit))
        else:
            self.ctx.enable_only(moderngl.BLEND)
            self.ctx.blend_func = moderngl.ONE, moderngl.ONE_MINUS_SRC_ALPHA
            if self.fetch and marks is not None:  # the counts are in OrderMarks' stencil: the covered pixels only
                fbo = marks.fbo
                glraw.stencil_above(0)
        assert fbo is not None, "the marks' framebuffer, made by collect_into"
        fbo.depth_mask = False
        fbo.use()
        try:
            self.vaos[key].render(moderngl.TRIANGLES, vertices=6)
        finally:
            fbo.depth_mask = True
            glraw.stencil_off()

    @property
    def nbytes(self) -> int:
        return self.heads.size + self.nodes.size + self.bases.size + sum(m.nbytes for m in self._marks.values())

    def release(self) -> None:
        for marks in self._marks.values():
            marks.release()
        for obj in (*self.vaos.values(), *self.programs.values(), self.heads, self.nodes, self.bases):
            obj.release()


class OrderMarks:
    """Which pixels the back-to-front object order blends exactly. begin(target) binds a
    framebuffer over the target's colour with a stencil of its own; the caller blends in
    object order there, listing every fragment as it goes (MODE_BLEND + MODE_COLLECT: one
    sprite pass). The stencil counts the surfaces blended in depth order and records one at or
    behind the nearest before it. The resolve then runs (`fbo`, the stencil test first) only
    where the stencil is above blended_in_place(): out of order, or many surfaces of low opacity.
    Without `fetched`, the depth test (with depth writes) decides: a surface that fails it sets
    255 (STENCIL_OUT_OF_ORDER). The shader's list writes make the depth and stencil tests come
    after it, so every fragment is listed, failing or not; on a GPU too (GL runs such a shader
    whatever the tests give), where they keep the draw order.
    With `fetched` (first_fetched), the shader reads and writes the stencil itself (a count in
    the low 7 bits, saturating, and a flag of 128), and a pixel's first three surfaces are two
    colour attachments it reads and writes (`first`), with no depth test: every fragment is
    blended, those out of order too, as their pixels are resolved anyway; with mark=False
    (surfaces collected only) the colour is left alone and the stencil keeps the counts."""

    def __init__(self, ctx: moderngl.Context, fetched: bool = False) -> None:
        self.ctx = ctx
        self.fetched = fetched
        # stencil_above's bound: with the count in 7 bits, a bound of 127 or more hides the flag
        self.in_place_limit = STENCIL_COUNT - 1 if fetched else STENCIL_OUT_OF_ORDER - 1
        self._key = None
        self.stencil: glraw.DepthStencil | None = None
        self.fbo: moderngl.Framebuffer | None = None  # over the target's colour (begin)
        self.collect_fbo: moderngl.Framebuffer | None = None  # with `first` too (fetched)
        self.first: list[moderngl.Texture] = []

    def begin(self, target, mark: bool = True) -> moderngl.Framebuffer:
        # the texture object itself, not its GL name: a target reallocated at the same size may
        # get the name of the texture it released, and a stale framebuffer would draw into that
        key = (target.color, target.size)
        if self._key is None or key[0] is not self._key[0] or key[1] != self._key[1]:
            self._allocate(target)
            self._key = key
        fbo, collect = self.fbo, self.collect_fbo
        assert fbo is not None and (collect is not None or not self.fetched), "made by _allocate"
        fbo.viewport = (0, 0, *target.viewport)
        if collect is not None:
            collect.viewport = fbo.viewport
            on = (True,) * 4
            # one mask per colour attachment, which moderngl takes (its stubs say one mask in all)
            collect.color_mask = (on if mark else (False,) * 4, on, on)  # pyright: ignore[reportAttributeAccessIssue]
            collect.depth_mask = False
            collect.use()
            glraw.clear_stencil(0)  # no surface yet: `first` holds last frame's
            glraw.stencil_from_shader()
            return collect
        fbo.depth_mask = True
        fbo.use()
        glraw.clear_depth_stencil(1.0, 0)
        glraw.stencil_count_surfaces()
        return fbo

    def _allocate(self, target) -> None:
        self.release()
        self.stencil = stencil = glraw.DepthStencil(*target.size, stencil_only=self.fetched)
        self.fbo = fbo = self.ctx.framebuffer(color_attachments=[target.color])
        fbo.use()
        stencil.attach_to_bound_framebuffer()
        if self.fetched:
            self.first = [self.ctx.texture(target.size, 4, dtype="u4") for _ in range(2)]
            for t in self.first:
                t.filter = moderngl.NEAREST, moderngl.NEAREST
            self.collect_fbo = collect = self.ctx.framebuffer(color_attachments=[target.color, *self.first])
            collect.use()
            stencil.attach_to_bound_framebuffer()

    @property
    def nbytes(self) -> int:
        return (self.stencil.nbytes if self.stencil else 0) + sum(t.width * t.height * 16 for t in self.first)

    def release(self) -> None:
        glraw.stencil_off()
        parts = (self.collect_fbo, self.fbo, *self.first, self.stencil)
        release_all(self.ctx, [p for p in parts if p is not None])
        self.stencil = self.fbo = self.collect_fbo = None
        self.first = []
        self._key = None


def fallback_message(refusal: Refusal | None, viewport: tuple[int, int]) -> str:
    """What a frame that asked for per-pixel order and was blended in object order says."""
    if refusal == "target":
        w, h = viewport
        need = w * h * LIST_BYTES_PER_PIXEL / 2**20
        return (
            f"per-pixel order would need {need:,.0f} MiB of per-pixel targets for this {w}x{h} "
            "view: blended in object order (a smaller viewport keeps it per pixel)"
        )
    return (
        f"per-pixel order would need more than {MAX_NODES:,} surfaces in this view: "
        "blended in object order (a smaller viewport or fewer objects keep it per pixel)"
    )
