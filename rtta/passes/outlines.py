"""Sprites over the projected outline of B_world (composite.geom's u_hull): where a draw
uses them instead of B_viewport's rectangle, and how far they are grown."""

from __future__ import annotations

import numpy as np

from ..atlas.parameterize import Records

HULL_MIN_AREA = 2048  # pixels per B_viewport, on average over a draw, for outline sprites


def worth_outlines(records: Records, ids: np.ndarray) -> bool:
    """Whether the B_viewport of `ids` cover HULL_MIN_AREA pixels each on average: there, a
    sprite over the projected outline of B_world (about a quarter fewer fragments) is worth
    the geometry shader's work for it (about a microsecond an object on llvmpipe)."""
    r = records.viewport_rect
    if 8 * len(ids) < len(r):
        r = r[ids]
        return bool(((r[:, 2] - r[:, 0]) * (r[:, 3] - r[:, 1])).mean() >= HULL_MIN_AREA)
    # most objects: the areas of all (the columns are contiguous rows of the planar records),
    # then a gather of one value each; gathering rows of the transposed [n, 4] took 2.3 ms at 10^5
    area = (r[:, 2] - r[:, 0]) * (r[:, 3] - r[:, 1])
    return bool(area[ids].mean() >= HULL_MIN_AREA)


def hull_margin(scale: np.ndarray) -> float:
    """How far (pixels) the outline sprites of objects at these region scales are grown: 1/16
    for float32 and the rasterizer's snapping, and at any other scale than 1 the reach of the
    nearest texel (a pixel takes the texel its centre falls in, whose own centre, the one the
    capture tested, lies up to half a texel away on each axis: 0.5 / scale pixels)."""
    return 1 / 16 if (scale == 1.0).all() else 1 / 16 + 0.75 / float(scale.min())
