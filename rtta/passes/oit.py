"""`--order pixel`: transparency blended per pixel in the order of the objects' own front
surfaces, which the atlas holds for every object (nested and interpenetrating parts blend
correctly, where the object order by bounding-box centre cannot).

One pass over the sprite quads writes every covered (pixel, object) surface into a per-pixel
linked list (an atomic exchange of the pixel's head; a surface's node is fixed by its
pixel's place in the object's B_viewport, so no counter is shared), then one pass over the
union of the drawn objects' B_viewport walks each list front to back
(shaders/oit_resolve.frag: the K = 8 nearest in exact order, the rest merged behind them,
weighted blended). Chosen over depth peeling, which draws every sprite quad once per layer
(BENCHMARKS.md). The nodes need 16 bytes per pixel of the drawn objects' viewport
rectangles; a frame needing more than MAX_NODES blends in object order instead (the caller
counts it).
"""

from __future__ import annotations

import moderngl
import numpy as np

from ..atlas.parameterize import Records
from ..gl import glsl

MAX_NODES = 1 << 23            # 8 Mi surfaces, 128 MiB of nodes
NODE_BYTES = 16
ORDERS = ("auto", "object", "pixel")   # auto: pixel in `transparent`, object for the ghosted context


def resolved_order(order: str, mode: str) -> str:
    """'object' or 'pixel': what `order` means in `mode` (auto: pixel in transparent, where
    object order leaves 3.5-6.3% of pixels over 8/255 at 1.2-1.4x the frame; object for the
    ghosted context, faded and desaturated, whose frame budget is set against STD)."""
    if order not in ORDERS:
        raise ValueError(f"order must be one of {', '.join(ORDERS)}, got {order!r}")
    return order if order != "auto" else ("pixel" if mode == "transparent" else "object")


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
    """begin(viewport, ids, records) -> bool (False: over MAX_NODES, use object order), then
    the caller draws the sprites with MODE_COLLECT, then resolve()."""

    def __init__(self, ctx: moderngl.Context) -> None:
        self.ctx = ctx
        self.heads = ctx.buffer(reserve=4)
        self.nodes = ctx.buffer(reserve=NODE_BYTES)
        self.bases = ctx.buffer(reserve=4)
        self.program = glsl.program(ctx, vertex_shader=glsl.load("oit_resolve.vert"),
                                    fragment_shader=glsl.load("oit_resolve.frag"))
        self.vao = ctx.vertex_array(self.program, [])
        self._width = 1
        self._rect = (-1.0, -1.0, 1.0, 1.0)

    def begin(self, viewport: tuple[int, int], ids: np.ndarray, records: Records) -> bool:
        bases, capacity = node_bases(records, ids)
        if capacity > MAX_NODES:
            return False
        w, h = int(viewport[0]), int(viewport[1])
        self._width = w
        rects = records.viewport_rect[ids].reshape(-1, 4)
        lo, hi = (rects[:, :2].min(axis=0), rects[:, 2:].max(axis=0)) if len(rects) else ((0, 0), (0, 0))
        self._rect = (*(np.asarray(lo) / (w, h) * 2 - 1), *(np.asarray(hi) / (w, h) * 2 - 1))   # NDC
        if self.heads.size < 4 * w * h:
            self.heads.orphan(4 * w * h)
        need = NODE_BYTES * max(capacity, 1)
        if self.nodes.size < need or self.nodes.size > 4 * need:     # shrink when far too big
            self.nodes.orphan(need)
        if self.bases.size < bases.nbytes:
            self.bases.orphan(max(bases.nbytes, 2 * self.bases.size))
        self.bases.write(bases.tobytes())
        self.heads.clear(size=4 * w * h)       # 0: no node (a pattern clear took 8 ms at 1024²)
        self.heads.bind_to_storage_buffer(5)
        self.nodes.bind_to_storage_buffer(6)
        self.bases.bind_to_storage_buffer(7)
        return True

    def resolve(self, fbo) -> None:
        """Sort and blend every pixel's list over what `fbo` holds (the background)."""
        self.ctx.memory_barrier(moderngl.SHADER_STORAGE_BARRIER_BIT)
        self.heads.bind_to_storage_buffer(5)
        self.nodes.bind_to_storage_buffer(6)
        self.program["u_width"].value = self._width
        self.program["u_rect"].value = tuple(float(v) for v in self._rect)
        self.ctx.enable_only(moderngl.BLEND)
        self.ctx.blend_func = moderngl.ONE, moderngl.ONE_MINUS_SRC_ALPHA
        fbo.depth_mask = False
        fbo.use()
        self.vao.render(moderngl.TRIANGLES, vertices=6)
        fbo.depth_mask = True

    @property
    def nbytes(self) -> int:
        return self.heads.size + self.nodes.size + self.bases.size

    def release(self) -> None:
        for obj in (self.vao, self.program, self.heads, self.nodes, self.bases):
            obj.release()
