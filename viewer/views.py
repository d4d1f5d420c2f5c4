"""Screen layout (panel | composite | atlas) and the pass that shows a texture in a rectangle.

Rectangles are (x, y, w, h) in window pixels from the top-left corner, as mouse events
give them; `ViewPass` converts to GL's bottom-left viewport itself.
"""

from __future__ import annotations

from dataclasses import dataclass

import moderngl
import numpy as np

from rtta.gl import glraw, glsl
from rtta.gl.bindings import Texture
from rtta.passes.composite import BACKGROUND

PANEL_WIDTH = 360  # at start; the splitter moves it between PANEL_MIN and PANEL_MAX of the window
PANEL_MIN = 240
PANEL_MAX = 0.6
ATLAS_FRACTION = 0.3
ATLAS_BACKGROUND = (0.16, 0.16, 0.18)

Rect = tuple[int, int, int, int]


@dataclass(frozen=True)
class Layout:
    panel: Rect
    composite: Rect
    atlas: Rect  # zero-sized when the atlas view is hidden

    @classmethod
    def of(cls, size: tuple[int, int], show_atlas: bool, panel_width: int = 0) -> Layout:
        """The rectangles in a window of `size`; `panel_width` 0: PANEL_WIDTH."""
        w, h = max(0, int(size[0])), max(0, int(size[1]))
        panel_w = min(panel_clamp(panel_width or PANEL_WIDTH, w), w)
        rest = w - panel_w
        atlas_w = int(rest * ATLAS_FRACTION) if show_atlas else 0
        comp_w = rest - atlas_w
        return cls(panel=(0, 0, panel_w, h), composite=(panel_w, 0, comp_w, h), atlas=(panel_w + comp_w, 0, atlas_w, h))


def panel_clamp(width: float, window_width: int) -> int:
    """A panel width the splitter may set in a window this wide."""
    return int(max(PANEL_MIN, min(float(width), PANEL_MAX * window_width)))


def contains(rect: Rect, x: float, y: float) -> bool:
    rx, ry, rw, rh = rect
    return rx <= x < rx + rw and ry <= y < ry + rh


def fit(rect: Rect, extent: tuple[int, int]) -> tuple[float, float, float]:
    """Scale and top-left offset that fit an extent (w, h) centred in `rect`, aspect kept."""
    rx, ry, rw, rh = rect
    ew, eh = max(1, extent[0]), max(1, extent[1])
    s = min(rw / ew, rh / eh)
    return s, rx + (rw - ew * s) / 2.0, ry + (rh - eh * s) / 2.0


def fitted(rect: Rect, extent: tuple[int, int]) -> Rect:
    s, ox, oy = fit(rect, extent)
    return int(ox), int(oy), int(extent[0] * s), int(extent[1] * s)


def layer_tiles(rect: Rect, extent: tuple[int, int], layers: int, choice: int) -> list[tuple[int, Rect]]:
    """(layer, screen rect) of the atlas layers shown: `choice`, or all of them (-1) in the
    grid that shows them largest."""
    if layers <= 0 or rect[2] <= 0 or rect[3] <= 0:
        return []
    if choice >= 0:
        return [(min(choice, layers - 1), fitted(rect, extent))]
    rx, ry, rw, rh = rect

    def scale(cols: int) -> float:
        rows = -(-layers // cols)
        return min(rw / cols / max(1, extent[0]), rh / rows / max(1, extent[1]))

    cols = max(range(1, layers + 1), key=scale)
    rows = -(-layers // cols)
    cw, ch = rw // cols, rh // rows
    return [(k, fitted((rx + (k % cols) * cw, ry + (k // cols) * ch, cw - 2, ch - 2), extent)) for k in range(layers)]


def atlas_rects_on_screen(atlas_rect: np.ndarray, extent: tuple[int, int], rect: Rect) -> np.ndarray:
    """B_atlas (x, y, w, h; texels from the bottom-left) as screen boxes (x0, y0, x1, y1)."""
    s, ox, oy = fit(rect, extent)
    a = np.asarray(atlas_rect, np.float64).reshape(-1, 4)
    x0 = ox + a[:, 0] * s
    y0 = oy + (extent[1] - a[:, 1] - a[:, 3]) * s
    return np.stack([x0, y0, x0 + a[:, 2] * s, y0 + a[:, 3] * s], axis=1)


class ViewPass:
    """`render(*, texture, rect, window_height, ...)`: a texture (or an atlas layer) drawn
    into a window rectangle over a background colour."""

    def __init__(self, ctx: moderngl.Context) -> None:
        self.ctx = ctx
        self._programs: dict[bool, moderngl.Program] = {}
        self._vaos: dict[bool, moderngl.VertexArray] = {}

    def _program(self, array: bool) -> tuple[moderngl.Program, moderngl.VertexArray]:
        if array not in self._programs:
            prog = glsl.program(
                self.ctx, vertex_shader=glsl.load("view.vert"), fragment_shader=glsl.load("view.frag", ARRAY=array)
            )
            self._programs[array] = prog
            self._vaos[array] = self.ctx.vertex_array(prog, [])
        return self._programs[array], self._vaos[array]

    def render(
        self,
        *,
        texture,
        rect: Rect,
        window_height: int,
        layer: int | None = None,
        depth: glraw.DepthArray | None = None,
        extent: tuple[float, float] = (1.0, 1.0),
        background=BACKGROUND[:3],
        target: moderngl.Framebuffer,
    ) -> None:
        """Draw `texture` into `rect` of `target`; `layer` selects an array layer (then
        `depth`, the depth-keyed atlas's DepthArray, says which texels are empty), `extent`
        the fraction of the texture shown (fitted into `rect`, aspect kept, for arrays)."""
        rx, ry, rw, rh = rect
        if rw <= 0 or rh <= 0:
            return
        prog, vao = self._program(layer is not None)
        if layer is not None:
            glsl.uniform(prog, "u_layer").value = int(layer)
        glsl.uniform(prog, "u_extent").value = tuple(float(v) for v in extent)
        glsl.uniform(prog, "u_background").value = tuple(float(v) for v in background)
        texture.use(Texture.VIEW_TEXTURE)
        if layer is not None:
            if depth is None:
                raise ValueError("ViewPass.render: an array layer needs the atlas depth")
            glraw.bind_texture_array(Texture.ATLAS_DEPTH, depth.glo)
        self.ctx.enable_only(moderngl.NOTHING)
        target.viewport = (int(rx), int(window_height - ry - rh), int(rw), int(rh))
        target.use()
        vao.render(moderngl.TRIANGLES, vertices=3)

    def release(self) -> None:
        for obj in [*self._vaos.values(), *self._programs.values()]:
            obj.release()
        self._vaos.clear()
        self._programs.clear()
