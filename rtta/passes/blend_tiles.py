"""Object-order blending in a compute pass: the ghosted context (and `transparent` in object
order) blended by shaders/blend_tiles.comp instead of as sprites through the raster pipeline.

The result is the sprites': each pixel blends the objects that cover it in the list's order,
premultiplied and rounded to 8 bits after each as the RGBA8 target's blend unit does, depth
tested against the focus sprites where the draw is. What differs is the hardware it runs on.
A sprite draw is fragment and blend work, and NVIDIA's data-centre GPUs keep only a little of
the raster hardware (the H100: 8 ROPs), where the ghosted context's blend of 10,000 parts took
4.7 ms for some 9 million fragments; a compute pass runs on every SM (`Settings.blend`).
"""

from __future__ import annotations

from typing import Literal

import moderngl

from ..gl import glsl, sync
from ..gl.bindings import Image, Storage, Texture
from ..gl.targets import CompositeTarget
from .sprites import UPSAMPLE_BELOW, Depth, Listed, SpriteDraw
from .style import Style

BlendOn = Literal["raster", "compute"]  # how object order is blended (CompositePass.blend)
SPAN = 2  # pixels a side per invocation (blend_tiles.comp): 16 SPAN a side per workgroup
AFTER = (
    moderngl.FRAMEBUFFER_BARRIER_BIT | moderngl.TEXTURE_FETCH_BARRIER_BIT | moderngl.TEXTURE_UPDATE_BARRIER_BIT
)  # what reads the blended target next: draws into it, samplers, read-back


class TileBlend:
    """Blends a GPU list into a composite target in one dispatch (module docstring).

    Parameters
    ----------
    ctx : moderngl.Context
        An OpenGL 4.3+ context (compute shaders, image load and store).
    """

    def __init__(self, ctx: moderngl.Context) -> None:
        self.ctx = ctx
        self.span = SPAN  # as the module says when made (scripts/gpu_timers.py sets it to compare)
        self._programs: dict[tuple[bool, bool, int], moderngl.ComputeShader] = {}

    def _program(self, shaded: bool, tested: bool) -> moderngl.ComputeShader:
        key = (shaded, tested, self.span)
        if key not in self._programs:
            source = glsl.load("blend_tiles.comp", WITH_AO=shaded, DEPTH_TESTED=tested, SPAN=self.span)
            self._programs[key] = self.ctx.compute_shader(source)
        return self._programs[key]

    def draw(self, listed: Listed, draw: SpriteDraw, style: Style, target: CompositeTarget, ortho_near) -> None:
        """Blend `listed` (a GPU list with its command buffer, order_gpu.GpuOrder's) over
        `target` as `SpritePass.draw_listed` would draw `draw` (blended; the context's depth
        test where `draw` has one). R, the styles and the atlas images are bound already
        (CompositePass._bind); `ortho_near` as `SpritePass.frame` takes it."""
        if listed.command is None:
            raise ValueError("the compute blend draws a GPU-sorted list (with its command buffer)")
        tested = draw.depth is not Depth.OFF
        prog = self._program(draw.shaded, tested)
        width, height = target.viewport
        for name, value in (
            ("u_viewport", (float(width), float(height))),
            ("u_desaturate", float(draw.desaturate)),
            ("u_edge_color", tuple(style.edge_color)),
            ("u_upsample_below", UPSAMPLE_BELOW),
            ("u_ortho_depth", (0.0, 0.0) if ortho_near is None else (1.0, ortho_near)),
        ):
            if glsl.has(prog, name):
                glsl.set_uniform(prog, name, value)
        listed.ids.bind_to_storage_buffer(Storage.DRAW_LIST)
        listed.command.bind_to_storage_buffer(Storage.COMPOSITE_COMMAND)
        if tested:
            target.depth.compare_func = ""  # read as a value
            target.depth.use(Texture.TARGET_DEPTH)
        target.color.bind_to_image(Image.TARGET_COLOR, read=True, write=True)
        tile = 16 * self.span
        prog.run(-(-width // tile), -(-height // tile))
        sync.barrier(self.ctx, AFTER)

    def release(self) -> None:
        for prog in self._programs.values():
            prog.release()
        self._programs.clear()
