"""Picking from the atlas: every object under a viewport pixel, occluded ones included.

The id image only names the front-most object; the atlas keeps each object's own depth
in its own region, so the pixel is mapped through each candidate's transform T into its
region and the objects that cover it there are returned front to back. Ghosted views use this to pick a
focus object seen through the context.
"""

from __future__ import annotations

import numpy as np

from ..atlas.parameterize import Records
from ..gl.readback import to_atlas


def objects_at(atlas, records: Records, x: int, y: int) -> list[tuple[int, float]]:
    """(object id, window depth) of every object covering viewport pixel (x, y), nearest
    first; (x, y) counts from the bottom-left pixel. `atlas` is the atlas target itself,
    of which only the texels under the candidate objects are read (a few, however many
    layers: picking at 10^5 objects stays as quick as at 24), or a dict with its 'depth'
    array [layers, H, W] as `LayeredTarget.read` gives. Only depths are read: each region
    holds its own object's fragments alone (they are clipped to B_viewport before being
    displaced into it), so a texel with depth < 1 there is the object's, and captures for
    the viewer need not write the id image."""
    oids, points = _candidates(records, x, y)
    if not len(oids):
        return []
    if isinstance(atlas, dict):
        depth = atlas["depth"]
        inside = (points[:, 2] < depth.shape[0]) & (points[:, 1] < depth.shape[1]) & (points[:, 0] < depth.shape[2])
        oids, points = oids[inside], points[inside]
        found = {"depth": depth[points[:, 2], points[:, 1], points[:, 0]]}
    else:
        found = atlas.texels(points, ids=False)
    hit = found["depth"] < 1.0  # a region holds its own object's texels alone: depth < 1 is a hit
    hits = zip(oids[hit].tolist(), found["depth"][hit].tolist(), strict=True)
    return sorted(((int(o), float(d)) for o, d in hits), key=lambda h: (h[1], h[0]))


def _candidates(records: Records, x: int, y: int) -> tuple[np.ndarray, np.ndarray]:
    """The visible objects whose viewport bounds hold pixel (x, y), and the atlas texel
    [k, 3] (x, y, layer) the pixel maps to in each one's region (those inside the atlas)."""
    W, H = records.viewport
    if not (0 <= x < W and 0 <= y < H):
        return np.zeros(0, np.int64), np.zeros((0, 3), np.int64)
    rect = records.viewport_rect
    inside = records.visible & (rect[:, 0] <= x) & (x < rect[:, 2]) & (rect[:, 1] <= y) & (y < rect[:, 3])
    oids = np.flatnonzero(inside)
    points = np.array(
        [[*(int(v) for v in to_atlas(records, int(oid), x, y)), int(records.layer[oid])] for oid in oids], np.int64
    ).reshape(-1, 3)
    aw, ah, layers = (int(v) for v in records.atlas_size)
    keep = (
        (points[:, 0] >= 0) & (points[:, 0] < aw) & (points[:, 1] >= 0) & (points[:, 1] < ah) & (points[:, 2] < layers)
    )
    return oids[keep], points[keep]


def pick(hits: list[tuple[int, float]], prefer: set[int] | None = None) -> int | None:
    """The object a click means: the nearest of `prefer` (e.g. the focus set in ghosted
    views, seen through the context) when one is under the cursor, else the nearest."""
    if not hits:
        return None
    preferred = [oid for oid, _ in hits if prefer and oid in prefer]
    return preferred[0] if preferred else hits[0][0]
