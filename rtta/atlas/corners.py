"""The corners of each object's B_world in clip space, for Algorithm 1's projection of the
bounds (parameterize.project_bounds): the rows of one corner of every box in a chunk, the test
for axis-aligned boxes (whose corners reuse per-axis products), and the bounds of boxes the
near plane cuts (corners in front plus edge/plane intersections)."""

from __future__ import annotations

import weakref

import numpy as np

from ..scene.model import BOX_EDGES
from .scratch import scratch


def points_clip(points: np.ndarray, m: np.ndarray) -> np.ndarray:
    """m @ (p, 1) for points [..., 3] as [..., 4] (few: the boxes crossing the near plane)."""
    return points[..., 0, None] * m[:, 0] + points[..., 1, None] * m[:, 1] + points[..., 2, None] * m[:, 2] + m[:, 3]


class CornerClip:
    """Clip rows (x, y, z, w) of corner k of every box in a chunk, in buffers reused from chunk
    to chunk. Axis-aligned boxes (corner k built from corners 0 and 7 by its bits, as Scene's
    are) reuse per-axis products: two adds per row and corner instead of three multiply-adds."""

    def __init__(self, m: np.ndarray, size: int, aligned: bool):
        self.m, self.aligned = m, aligned
        self.out = scratch("clip.out", (4, size))
        self.prod = scratch("clip.prod", (3, 2, 4, size)) if aligned else None  # axis, end, clip row
        self.q = scratch("clip.q", size)
        self.front = scratch("clip.front", size, bool)

    def start(self, planar: np.ndarray):
        """The function k -> rows [4, c] for the chunk planar [3, 8, c] (overwritten per call)."""
        c, m = planar.shape[2], self.m
        out = self.out[:, :c]
        if self.prod is None:  # not axis-aligned

            def rows(k: int) -> np.ndarray:
                p = planar[:, k]
                for r in range(4):
                    row = np.multiply(p[0], m[r, 0], out=out[r])
                    row += p[1] * m[r, 1]
                    row += p[2] * m[r, 2]
                    row += m[r, 3]
                return out

            return rows
        prod = self.prod[..., :c]
        for j in range(3):
            for e, corner in enumerate((0, 7)):  # min and max corner
                np.multiply(m[:, j, None], planar[j, corner], out=prod[j, e])
        prod[0] += m[:, 3, None]

        def rows_aabb(k: int) -> np.ndarray:
            np.add(prod[0, k & 1], prod[1, (k >> 1) & 1], out=out)
            np.add(out, prod[2, k >> 2], out=out)
            return out

        return rows_aabb


_ALIGNED: dict[int, tuple[weakref.ref, dict]] = {}  # id of a read-only corner array: (its ref, answers per view)


def axis_aligned(planar: np.ndarray) -> bool:
    """True if every corner k of planar [3, 8, n] takes coordinate j from corner 7 where
    bit j of k is set and from corner 0 where not (the AABB corner order of Scene). Read-only
    arrays (Scene's corners) are checked once: 18 comparisons of n values each, ~2 ms at
    10^5 objects, were a tenth of every frame's parameterization."""
    owner = planar
    while isinstance(owner.base, np.ndarray):
        owner = owner.base
    if owner.flags.writeable:
        return _check_aligned(planar)
    view = (planar.__array_interface__["data"][0], planar.shape, planar.strides)
    entry = _ALIGNED.get(id(owner))
    if entry is None or entry[0]() is not owner:
        key = id(owner)
        entry = _ALIGNED[key] = (weakref.ref(owner, lambda _, key=key: _ALIGNED.pop(key, None)), {})
    known = entry[1]
    if view not in known:
        known[view] = _check_aligned(planar)
    return known[view]


def _check_aligned(planar: np.ndarray) -> bool:
    for k in range(1, 7):
        for j in range(3):
            if not np.array_equal(planar[j, k], planar[j, 7 if (k >> j) & 1 else 0]):
                return False
    return True


def clipped_bounds(clip: np.ndarray, d: np.ndarray):
    """NDC bounds of boxes cut by the near plane: corners in front plus edge/plane intersections."""
    a, b = clip[:, BOX_EDGES[:, 0]], clip[:, BOX_EDGES[:, 1]]
    da, db = d[:, BOX_EDGES[:, 0]], d[:, BOX_EDGES[:, 1]]
    crossing = (da * db) < 0
    t = np.where(crossing, da / np.where(crossing, da - db, 1.0), 0.0)
    hits = a + t[..., None] * (b - a)  # [m, 12, 4], on the plane: w = near > 0
    pts = np.concatenate([clip, hits], axis=1)  # [m, 20, 4]
    valid = np.concatenate([d >= 0, crossing], axis=1)
    w = np.maximum(np.where(valid, pts[..., 3], 1.0), np.finfo(np.float64).tiny)
    xyz = pts[..., :3] / w[..., None]
    lo = np.where(valid[..., None], xyz, np.inf).min(axis=1)
    hi = np.where(valid[..., None], xyz, -np.inf).max(axis=1)
    return lo, hi
