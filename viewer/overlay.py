"""Drawn over the views with imgui's background draw list: atlas region outlines (the
highlighted ones in the outline colour), the name of the region under the cursor, the
atlas size, layers and utilization; the view cube, the measurements and the splitter."""

from __future__ import annotations

from typing import TYPE_CHECKING

import numpy as np
from imgui_bundle import imgui

from . import cutaway, gizmo, ruler
from .commands import records_to_read
from .views import atlas_rects_on_screen, contains

if TYPE_CHECKING:
    from .commands import OverlayHost

REGION = imgui.IM_COL32(120, 200, 255, 140)
TEXT = imgui.IM_COL32(235, 235, 240, 255)
HOVER = imgui.IM_COL32(255, 200, 80, 255)
SPLITTER = imgui.IM_COL32(90, 90, 100, 255)
SPLITTER_HOT = imgui.IM_COL32(255, 200, 80, 255)
HOVER_MAX = 2000  # outlines drawn for a hovered group at most (imgui's buffers are finite)
MAX_OUTLINES = 1000  # region outlines drawn per frame: each is a call into imgui (3,000 took 5-8 ms a frame)


def _col(rgba) -> int:
    r, g, b, a = (int(np.clip(v, 0, 1) * 255) for v in rgba)
    return imgui.IM_COL32(r, g, b, a)


def regions(app: OverlayHost):
    """(object ids, screen boxes x0, y0, x1, y1) of every atlas region shown, per tile."""
    rec = records_to_read(app)
    if rec is None:
        return
    for layer, rect in app.atlas_tiles():
        ids = np.flatnonzero(rec.visible & (rec.layer == layer))
        yield layer, ids, atlas_rects_on_screen(rec.atlas_rect[ids], rec.atlas_size[:2], rect)


def region_under(app: OverlayHost, x: float, y: float) -> int | None:
    """The object whose atlas region is under window point (x, y), if any."""
    if not contains(app.layout.atlas, x, y):
        return None
    for _, ids, boxes in regions(app):
        hit = (boxes[:, 0] <= x) & (x < boxes[:, 2]) & (boxes[:, 1] <= y) & (y < boxes[:, 3])
        if hit.any():
            return int(ids[np.flatnonzero(hit)[0]])
    return None


def hovered(app: OverlayHost) -> np.ndarray:
    """Object ids of the tree row under the mouse that have a region now (at most HOVER_MAX)."""
    s, rec = app.state, records_to_read(app)
    if s.hover is None or rec is None:
        return np.zeros(0, np.int64)
    ids = s.tree.members(s.hover)
    return ids[rec.visible[ids]][:HOVER_MAX]


def _hover(app: OverlayHost, dl) -> None:
    """Outline the hovered row's objects: their projected bounds in the composite."""
    ids, rec = hovered(app), records_to_read(app)
    if not ids.size or rec is None:
        return
    cx, cy, _, ch = app.layout.composite
    for x0, y0, x1, y1 in rec.viewport_rect[ids]:
        dl.add_rect(imgui.ImVec2(cx + x0, cy + ch - y1), imgui.ImVec2(cx + x1, cy + ch - y0), HOVER, 0.0, 0, 2.0)


def _highlight_mask(app: OverlayHost, ids: np.ndarray) -> np.ndarray:
    """Which of `ids` are highlighted (one mask lookup, no loop over 10^5 ids)."""
    return app.state.focus_mask()[ids]


def _outlined(app: OverlayHost) -> tuple[np.ndarray, np.ndarray]:
    """The regions whose outlines are drawn: at most MAX_OUTLINES (highlighted ones first,
    then the largest on screen), none under a pixel, so the overlay costs the same at 10^5
    objects as at 10^3."""
    parts = [(ids, boxes) for _, ids, boxes in regions(app)]
    if not parts:
        return np.zeros(0, np.int64), np.zeros((0, 4))
    ids = np.concatenate([p[0] for p in parts])
    boxes = np.concatenate([p[1] for p in parts]).astype(np.float64)
    area = (boxes[:, 2] - boxes[:, 0]) * (boxes[:, 3] - boxes[:, 1])
    keep = np.flatnonzero(area >= 1.0)
    if len(keep) > MAX_OUTLINES:
        rank = area[keep] + np.where(_highlight_mask(app, ids[keep]), np.inf, 0.0)
        keep = keep[np.argsort(-rank, kind="stable")[:MAX_OUTLINES]]
    return ids[keep], boxes[keep]


def _composite_tools(app: OverlayHost, dl) -> None:
    """The measurements, the view cube and the splitter at the panel's edge."""
    rect, scene = app.layout.composite, app.renderer.scene
    if rect[2] > 0 and rect[3] > 0 and (app.ruler.done or app.ruler.first is not None):
        view, proj = app.renderer.matrices(app.orbit.camera(), (rect[2], rect[3]))
        ruler.draw(dl, app.ruler, proj @ view, rect, scene.origin, scene.unit, scene.radius)
    cutaway.draw(dl, app)  # the section plane and its handle
    if app.state.show_cube:
        gizmo.draw(dl, rect, app.orbit, scene.up_axis, app.mouse)
    _, py, pw, ph = app.layout.panel
    if pw > 0:  # over the panel's edge (the foreground list: above the panel window)
        hot = app.splitting or abs(app.mouse[0] - pw) <= 4
        imgui.get_foreground_draw_list().add_rect_filled(
            imgui.ImVec2(pw - 3, py), imgui.ImVec2(pw, py + ph), SPLITTER_HOT if hot else SPLITTER
        )


def draw(app: OverlayHost) -> None:
    rec = app.records
    dl = imgui.get_background_draw_list()
    _hover(app, dl)
    _composite_tools(app, dl)
    if not app.state.show_atlas or rec is None or app.layout.atlas[2] <= 0:
        return
    focus_col = _col(app.state.style.outline_color)
    hover = set(hovered(app).tolist())
    ids, boxes = _outlined(app)
    on = _highlight_mask(app, ids)
    for oid, (x0, y0, x1, y1), lit in zip(ids.tolist(), boxes.tolist(), on.tolist(), strict=True):
        col = HOVER if oid in hover else focus_col if lit else REGION
        dl.add_rect(imgui.ImVec2(x0, y0), imgui.ImVec2(x1, y1), col, 0.0, 0, 2.0 if lit or col == HOVER else 1.0)
    tw, th, td = rec.atlas_size
    shown = "all layers" if app.state.atlas_layer < 0 else f"layer {app.state.atlas_layer}"
    read = records_to_read(app)  # while the camera moves: no outlines, no utilization (R stays on the GPU)
    used = f"  utilization {100 * read.utilization:.0f}%" if read is not None else ""
    label = f"atlas {tw}x{th}, {td} layers ({shown}){used}"
    ax, ay, _, _ = app.layout.atlas
    dl.add_text(imgui.ImVec2(ax + 6, ay + 4), TEXT, label)
    oid = region_under(app, *app.mouse)
    if oid is not None and read is not None and not imgui.get_io().want_capture_mouse:
        rec = read
        x, y, w, h = rec.atlas_rect[oid]
        imgui.set_tooltip(
            f"{app.renderer.scene.names[oid]}\nregion {w}x{h} at ({x}, {y}), layer "
            f"{rec.layer[oid]}\nscale {rec.scale[oid]:.2f} texels/pixel"
        )
