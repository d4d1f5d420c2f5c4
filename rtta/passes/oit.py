"""`--order pixel`: transparency blended per pixel in the order of the objects' own front
surfaces, which the atlas holds for every object (nested and interpenetrating parts blend
correctly, where the object order by bounding-box centre cannot).

Chosen by measurement over depth peeling (BENCHMARKS.md): one pass over the sprite quads
appends every covered (pixel, object) surface to a per-pixel linked list (an atomic counter
and an atomic exchange of the pixel's head, shaders/oit.glsl), then one full-screen pass
sorts each list and blends it (shaders/oit_resolve.frag). Peeling would draw every sprite
quad once per layer. The node buffer holds the sum of the drawn objects' viewport
rectangles, an upper bound on their surfaces, so no surface is dropped; a frame whose bound
passes MAX_NODES is blended in object order instead (the caller is told). More than
oit_resolve.frag's K surfaces at one pixel: the farthest are merged behind the K nearest
(weighted blended, order-independent)."""

from __future__ import annotations

import struct

import moderngl
import numpy as np

from ..atlas.parameterize import Records
from ..gl import glsl

MAX_NODES = 1 << 23            # 8 Mi surfaces, 128 MiB of nodes
NODE_BYTES = 16
HEADER_BYTES = 16
ORDERS = ("object", "pixel")


def node_bound(records: Records, ids: np.ndarray) -> int:
    """Upper bound on the (pixel, object) surfaces of `ids`: their viewport rectangles' area."""
    r = records.viewport_rect[ids]
    return int(((r[:, 2] - r[:, 0]) * (r[:, 3] - r[:, 1])).sum())


class PixelOrderPass:
    """begin(viewport, ids, records) -> bool (False: over MAX_NODES, use object order), then
    the caller draws the sprites with MODE_COLLECT, then resolve()."""

    def __init__(self, ctx: moderngl.Context) -> None:
        self.ctx = ctx
        self.heads = ctx.buffer(reserve=4)
        self.nodes = ctx.buffer(reserve=HEADER_BYTES + NODE_BYTES)
        self.program = ctx.program(vertex_shader=glsl.load("oit_resolve.vert"),
                                   fragment_shader=glsl.load("oit_resolve.frag"))
        self.vao = ctx.vertex_array(self.program, [])
        self._width = 1

    def begin(self, viewport: tuple[int, int], ids: np.ndarray, records: Records) -> bool:
        capacity = max(node_bound(records, ids), 1)
        if capacity > MAX_NODES:
            return False
        w, h = int(viewport[0]), int(viewport[1])
        self._width = w
        if self.heads.size < 4 * w * h:
            self.heads.orphan(4 * w * h)
        need = HEADER_BYTES + NODE_BYTES * capacity
        if self.nodes.size < need or self.nodes.size > 4 * need:     # shrink when far too big
            self.nodes.orphan(need)
        self.heads.clear(size=4 * w * h, chunk=b"\xff\xff\xff\xff")
        self.nodes.write(struct.pack("<4I", 0, capacity, 0, 0))
        self.heads.bind_to_storage_buffer(5)
        self.nodes.bind_to_storage_buffer(6)
        return True

    def resolve(self, fbo) -> None:
        """Sort and blend every pixel's list over what `fbo` holds (the background)."""
        self.ctx.memory_barrier(moderngl.SHADER_STORAGE_BARRIER_BIT)
        self.heads.bind_to_storage_buffer(5)
        self.nodes.bind_to_storage_buffer(6)
        self.program["u_width"].value = self._width
        self.ctx.enable_only(moderngl.BLEND)
        self.ctx.blend_func = moderngl.ONE, moderngl.ONE_MINUS_SRC_ALPHA
        fbo.depth_mask = False
        fbo.use()
        self.vao.render(moderngl.TRIANGLES, vertices=3)
        fbo.depth_mask = True

    @property
    def nbytes(self) -> int:
        return self.heads.size + self.nodes.size

    def release(self) -> None:
        for obj in (self.vao, self.program, self.heads, self.nodes):
            obj.release()
