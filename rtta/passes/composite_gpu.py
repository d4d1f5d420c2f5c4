"""Compositing's GPU-driven draws (issue 43): where R stays on the GPU (atlas.records.GpuRecords),
the back-to-front order is sorted on the GPU (order_gpu.GpuOrder) and the sprite draws read
it with its count (sprites.Listed), so that the CPU's work per frame does not grow with the
objects: no read of R, no numpy over them; the style parameters are built and uploaded only
when the style, the mode or the object count changes.

`CompositePass.render` takes this branch (`gpu_driven`) for `ghosted`, `ghosted-ao`, `sprites`
and `transparent` in object order, with outlines and halos; pixel order, a lens and a
projector read R on the CPU (the other branch).
"""

from __future__ import annotations

import moderngl

from .blend_tiles import TileBlend
from .oit import resolved_order
from .order_gpu import FOCUS_COMMANDS, GpuOrder
from .sprites import Listed, upload
from .style import Mode, Order, Style, style_key, style_params


def gpu_driven(records, mode: Mode, style: Style, view, projection, lens) -> bool:
    """Whether compositing `mode` can draw from R on the GPU as it is: `records` a GpuRecords,
    a view matrix given, no projector, no lens in a mode it cuts, and object order where the
    mode blends (`transparent`, the ghosted context)."""
    if not getattr(records, "on_gpu", False) or view is None or projection is not None or lens is not None:
        return False
    return mode is Mode.SPRITES or resolved_order(style.order, mode) is Order.OBJECT


class GpuDraws:
    """What the GPU-driven branch keeps between frames: the sort, the list of every id, and
    which style parameters the style buffer holds.

    Parameters
    ----------
    ctx : moderngl.Context
        The compositing context.
    """

    def __init__(self, ctx: moderngl.Context) -> None:
        self.ctx = ctx
        self.order = GpuOrder(ctx)
        self._tiles: TileBlend | None = None
        self.styles_key: tuple | None = None  # what the style buffer holds (None: unknown)
        self._drawn = Listed(self.order.ids, command=self.order.command)  # the sort's list (its buffers stay)

    def styles(self, buf: moderngl.Buffer, style: Style, mode: Mode, n: int) -> None:
        """Build and upload the style parameters into `buf` where they changed (the ghosted
        modes': the context faded already; the focus sprites do not read opacity)."""
        key = style_key(style, mode, n)
        if key != self.styles_key:
            ghosted = mode in (Mode.GHOSTED, Mode.GHOSTED_AO)
            upload(buf, style_params(style, mode, n, faded=ghosted))
            self.styles_key = key

    def everyone(self, *, n: int, gpu, styles: moderngl.Buffer, focus: Listed | None = None) -> Listed:
        """Every id in ascending order (`sprites`' draw order; the invisible ones draw nothing);
        `focus` (a CPU list, flagged in `styles`): its commands are written too (`focus_drawn`)."""
        listed = 0 if focus is None else focus.count
        self.order.every(count=n, records=gpu.records, bounds=gpu.bounds, styles=styles, focus=listed)
        return self._drawn

    def sorted(
        self, *, n: int, gpu, view, styles: moderngl.Buffer, focus: Listed | None = None, context: bool = True
    ) -> Listed:
        """The visible objects back to front (`context`: the focus flagged in `styles` left
        out), sorted on the GPU; `focus` (a CPU list): its commands are written too (`focus_drawn`)."""
        listed = 0 if focus is None else focus.count
        self.order.sort(
            count=n,
            records=gpu.records,
            bounds=gpu.bounds,
            view=view,
            styles=styles,
            exclude_focus=context,
            focus=listed,
        )
        return self._drawn

    def focus_drawn(self, focus: Listed) -> Listed:
        """The focus list drawn by the three commands the last `sorted` or `everyone` wrote for
        it: the GPU picks the variant (every region at scale 1, none upsampled, or each sprite
        choosing) without a read."""
        return Listed(focus.ids, focus.count, self.order.command, firsts=FOCUS_COMMANDS, variants="focus")

    @property
    def tiles(self) -> TileBlend:
        """The compute blend (blend_tiles.py), made on first use."""
        if self._tiles is None:
            self._tiles = TileBlend(self.ctx)
        return self._tiles

    def release(self) -> None:
        self.order.release()
        if self._tiles is not None:
            self._tiles.release()
