"""Memory barriers between the GPU-driven frame's compute dispatches, and a driver that needs none.

Between a compute dispatch that writes a buffer and a later dispatch or draw that reads it,
OpenGL asks for glMemoryBarrier. llvmpipe (Mesa's CPU driver) runs a dispatch to its end before
the call returns and reads what a draw's vertex and geometry stages read (R, the draw lists,
the indirect commands) at the draw call, so those barriers order nothing there; and its
glMemoryBarrier is a full glFinish: it waits for every queued draw to be rasterized. Issued
between the sort of compositing and the capture's draws, it kept the capture's rasterization
from overlapping anything (a 24-part frame 30-40% slower than the CPU path). `barrier` skips it
on llvmpipe alone; fragment shaders' writes (per-pixel lists, rtta.passes.oit) keep theirs.

`kick` hands a GPU the commands made so far (glFlush) between a frame's stages: NVIDIA's driver
holds them until a flush, so without one the GPU waited for the frame's last call to start its
compositing and spent the frame's end alone (a 24-part ghosted-ao frame on an H100: 0.86 ms of
its 2.4 in ctx.finish). llvmpipe rasterizes at a flush in the calling thread: nothing there.
"""

from __future__ import annotations

import moderngl

from . import glraw


def renderer(ctx: moderngl.Context) -> str:
    """GL_RENDERER, asked once per context (moderngl's `ctx.info` makes every glGet each time)."""
    known = getattr(ctx, "_rtta_renderer", None)
    if known is None:
        known = str(ctx.info["GL_RENDERER"])
        ctx._rtta_renderer = known  # type: ignore[attr-defined]
    return known


def synchronous(ctx: moderngl.Context) -> bool:
    """Whether the driver finishes a dispatch within the call (llvmpipe); asked once per context."""
    known = getattr(ctx, "_rtta_synchronous", None)
    if known is None:
        known = ctx._rtta_synchronous = "llvmpipe" in renderer(ctx)  # type: ignore[attr-defined]
    return known


def barrier(ctx: moderngl.Context, bits: int) -> None:
    """glMemoryBarrier(bits) after compute writes that a later dispatch or draw's vertex,
    geometry or indirect stage reads; nothing on a synchronous driver (the module's docstring)."""
    known = getattr(ctx, "_rtta_synchronous", None)  # synchronous(ctx), without its call
    if not (synchronous(ctx) if known is None else known):
        ctx.memory_barrier(bits)


def kick(ctx: moderngl.Context) -> None:
    """glFlush on a GPU: the commands so far start while the CPU makes the next ones; nothing
    on a synchronous driver (the module's docstring)."""
    if not synchronous(ctx):
        glraw.flush_commands()
