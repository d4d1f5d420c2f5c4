"""Every object in view as if drawn alone, in the flat layout that encoding reads
(coco.layout): from ONE RTTA capture (each object's atlas region mapped back through T), or,
as the benchmark's baseline, from each object drawn alone with RTT and read back."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ..renderer.renderer import Renderer
from ..scene.camera import Camera
from .coco import flatten, layout


@dataclass
class Alone:
    oids: np.ndarray  # int64 [N]: objects in view (a non-empty rectangle)
    rects: np.ndarray  # int64 [N, 4]: x, y, w, h in image pixels (y down)
    lay: dict  # coco.layout(rects)
    mask: np.ndarray  # bool, flat: where the object alone covers the pixel
    depth: np.ndarray  # float32, flat: its window depth there (1: none)
    colors: list[np.ndarray] | None = None  # RGBA [h, w, 4] per object, top row first


def in_view(records, height: int) -> tuple[np.ndarray, np.ndarray]:
    """Visible objects with a non-empty rectangle, and their rectangles in image pixels."""
    oids = np.flatnonzero(records.visible)
    r = records.viewport_rect[oids].astype(np.int64)
    rects = np.stack([r[:, 0], height - r[:, 3], r[:, 2] - r[:, 0], r[:, 3] - r[:, 1]], 1).reshape(-1, 4)
    keep = (rects[:, 2] > 0) & (rects[:, 3] > 0)
    return oids[keep], rects[keep]


def alone_rtta(
    renderer: Renderer, camera: Camera, viewport: tuple[int, int], appearance: bool = False, queue=None
) -> Alone:
    """ONE capture; every object's atlas region gathered in one numpy pass. `queue()`, when
    given, issues more GPU work after the capture (the STD draw): it runs while the gather does."""
    records = renderer.capture(camera, viewport)
    if queue is not None:
        queue()
    tw, th, td = records.atlas_size
    atlas = renderer.atlas.read((tw, th), td, ("color", "depth") if appearance else ("depth",)) if td else None
    oids, rects = in_view(records, viewport[1])
    lay = layout(rects)
    col, row, co = lay["col"], lay["row"], lay["col_obj"]
    o = oids[co]  # per column
    ax0 = records.atlas_rect[o, 0] + records.border
    ay = records.atlas_rect[o, 1] + records.border
    if np.all(records.scale[oids] == 1):  # T is a shift: texel = the column's base - row
        tx = (ax0 + lay["col_index"])[col]
        ty = (ay + rects[co, 3] - 1)[col] - row
    else:  # scaled-down regions: T's nearest texel per pixel
        s = records.scale[o][col]
        gx = (rects[co, 0] + lay["col_index"])[col]
        gy = viewport[1] - 1 - (rects[co, 1][col] + row)
        tx = np.floor(ax0[col] + s * (gx + 0.5 - records.viewport_rect[o, 0][col]))
        ty = np.floor(ay[col] + s * (gy + 0.5 - records.viewport_rect[o, 1][col]))
        tx, ty = np.clip(tx, 0, tw - 1).astype(np.int64), np.clip(ty, 0, th - 1).astype(np.int64)
    if atlas is None:
        depth = np.ones(len(col), np.float32)
    else:
        layer = records.layer[o].astype(np.int64)[col]
        depth = atlas["depth"].ravel().take((layer * th + ty) * tw + tx, mode="clip")
    colors = [] if appearance else None
    if colors is not None and atlas is not None:  # (no atlas: no object in view)
        for i, oid in enumerate(oids):
            a, b = lay["offsets"][i : i + 2]
            shape = (rects[i, 2], rects[i, 3] + 2)
            cols, rows = (np.clip(v[a:b].reshape(shape)[:, 1:-1].T, 0, lim) for v, lim in ((tx, tw - 1), (ty, th - 1)))
            colors.append(atlas["color"][records.layer[oid], rows, cols])
    return Alone(oids, rects, lay, (depth < 1.0) & lay["pixel"], depth, colors)


def alone_rtt(renderer: Renderer, camera: Camera, viewport: tuple[int, int], appearance: bool = False) -> Alone:
    """The baseline: each object in view (the same frustum culling by projected bounds) drawn
    alone into a full-viewport target and read back, as tools without an atlas do."""
    records = renderer.parameterize(camera, viewport)
    oids, rects = in_view(records, viewport[1])
    parts = ("color", "depth") if appearance else ("depth",)
    depths, colors = [], []

    def consume(oid: int, target) -> None:
        alone = target.read(viewport, 1, parts)
        x0, y0, x1, y1 = (int(v) for v in records.viewport_rect[oid])
        depths.append(alone["depth"][0, y0:y1, x0:x1][::-1])
        if appearance:
            colors.append(alone["color"][0, y0:y1, x0:x1][::-1])

    renderer.rtt(camera, viewport, oids, consume)
    lay = layout(rects)
    depth = flatten(depths, rects, 1.0).astype(np.float32)
    return Alone(oids, rects, lay, (depth < 1.0) & lay["pixel"], depth, colors if appearance else None)
