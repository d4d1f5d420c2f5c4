"""B_world: which per-object bounds parameterization projects (`Settings.bounds`,
`Scene.box_corners`)."""

from __future__ import annotations

from enum import StrEnum
from typing import Literal


class Bounds(StrEnum):
    """The kinds of B_world."""

    AABB = "aabb"  # axis-aligned boxes (the paper's)
    OBB = "obb"  # the AABBs and the principal-axes boxes, their projections intersected


BoundsName = Literal["aabb", "obb"]
BOUNDS: tuple[str, ...] = tuple(b.value for b in Bounds)
