"""Picking from the atlas: every object under a viewport pixel, occluded ones included.

The id image only names the front-most object; the atlas keeps each object's own id and
depth, so the pixel is mapped through each candidate's transform T into its region and the
objects that cover it there are returned front to back. Ghosted views use this to pick a
focus object seen through the context.
"""

from __future__ import annotations

import numpy as np

from ..atlas.parameterize import Records
from ..gl.readback import to_atlas


def objects_at(atlas: dict[str, np.ndarray], records: Records, x: int, y: int) -> list[tuple[int, float]]:
    """(object id, window depth) of every object covering viewport pixel (x, y), nearest
    first. `atlas` holds 'id' and 'depth' arrays [layers, H, W] as `LayeredTarget.read` gives;
    (x, y) counts from the bottom-left pixel."""
    W, H = records.viewport
    if not (0 <= x < W and 0 <= y < H):
        return []
    rect = records.viewport_rect
    inside = records.visible & (rect[:, 0] <= x) & (x < rect[:, 2]) & (rect[:, 1] <= y) & (y < rect[:, 3])
    hits = []
    ids, depth = atlas["id"], atlas["depth"]
    for oid in np.flatnonzero(inside):
        tx, ty = (int(v) for v in to_atlas(records, int(oid), x, y))
        layer = int(records.layer[oid])
        if layer < ids.shape[0] and 0 <= ty < ids.shape[1] and 0 <= tx < ids.shape[2] \
                and ids[layer, ty, tx] == oid:
            hits.append((int(oid), float(depth[layer, ty, tx])))
    return sorted(hits, key=lambda h: (h[1], h[0]))


def pick(hits: list[tuple[int, float]], prefer: set[int] | None = None) -> int | None:
    """The object a click means: the nearest of `prefer` (e.g. the focus set in ghosted
    views, seen through the context) when one is under the cursor, else the nearest."""
    if not hits:
        return None
    preferred = [oid for oid, _ in hits if prefer and oid in prefer]
    return preferred[0] if preferred else hits[0][0]
