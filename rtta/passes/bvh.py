"""Geometry grouping (Knecht & Mattausch, section 2.3): the batched triangles split by a
bounding volume hierarchy with the surface area heuristic (binned SAH) until each leaf has
at most `max_vertices` distinct vertices. Leaves are drawn as chunks, each frustum-culled."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

BINS = 16


@dataclass
class Bvh:
    """indices: the triangles regrouped so each leaf is contiguous (uint32 [F*3]);
    leaves: (first index, index count) per leaf; lo/hi: each leaf's bounds (float32 space)."""

    indices: np.ndarray
    leaves: np.ndarray  # int64 [L, 2]
    lo: np.ndarray  # float64 [L, 3]
    hi: np.ndarray


def build_bvh(positions: np.ndarray, triangles: np.ndarray, max_vertices: int = 5000) -> Bvh:
    """Split top-down with binned SAH along the axis of largest centroid extent."""
    if max_vertices < 3:
        raise ValueError(f"max_vertices must be at least 3, got {max_vertices}")
    p = np.asarray(positions, np.float64)
    tri = np.asarray(triangles, np.int64)
    corners = p[tri]  # [F, 3, 3]
    tlo, thi = corners.min(axis=1), corners.max(axis=1)
    centroid = (tlo + thi) / 2
    order: list[np.ndarray] = []
    stack = [np.arange(len(tri))]
    while stack:
        members = stack.pop()
        if len(members) * 3 <= max_vertices or np.unique(tri[members]).size <= max_vertices:
            order.append(members)
            continue
        left, right = _sah_split(members, centroid, tlo, thi)
        stack.extend((right, left))
    leaves, first = [], 0
    for members in order:
        leaves.append((first, 3 * len(members)))
        first += 3 * len(members)
    lo = np.array([tlo[m].min(axis=0) for m in order])
    hi = np.array([thi[m].max(axis=0) for m in order])
    indices = tri[np.concatenate(order)].reshape(-1).astype(np.uint32)
    return Bvh(indices=indices, leaves=np.array(leaves, np.int64), lo=lo, hi=hi)


def _sah_split(members: np.ndarray, centroid: np.ndarray, tlo: np.ndarray, thi: np.ndarray):
    """The binned SAH split of `members` (a median split when all centroids coincide)."""
    c = centroid[members]
    extent = c.max(axis=0) - c.min(axis=0)
    axis = int(np.argmax(extent))
    if extent[axis] <= 0:
        half = len(members) // 2
        return members[:half], members[half:]
    lo_c = c[:, axis].min()
    bins = np.minimum(((c[:, axis] - lo_c) / extent[axis] * BINS).astype(np.int64), BINS - 1)
    counts = np.bincount(bins, minlength=BINS)
    blo = np.full((BINS, 3), np.inf)
    bhi = np.full((BINS, 3), -np.inf)
    np.minimum.at(blo, bins, tlo[members])
    np.maximum.at(bhi, bins, thi[members])
    costs = np.full(BINS - 1, np.inf)
    for k in range(1, BINS):
        nl, nr = counts[:k].sum(), counts[k:].sum()
        if nl and nr:
            costs[k - 1] = nl * _area(blo[:k].min(0), bhi[:k].max(0)) + nr * _area(blo[k:].min(0), bhi[k:].max(0))
    k = int(np.argmin(costs)) + 1
    if not np.isfinite(costs[k - 1]):
        half = len(members) // 2
        sorted_members = members[np.argsort(c[:, axis], kind="stable")]
        return sorted_members[:half], sorted_members[half:]
    return members[bins < k], members[bins >= k]


def _area(lo: np.ndarray, hi: np.ndarray) -> float:
    d = np.maximum(hi - lo, 0)
    return float(d[0] * d[1] + d[1] * d[2] + d[2] * d[0])


def visible_leaves(bvh: Bvh, view_proj: np.ndarray) -> np.ndarray:
    """(first, count, leaves) per run of consecutive leaves whose boxes meet the frustum."""
    m = np.asarray(view_proj, np.float64)
    planes = np.array([m[3] + m[0], m[3] - m[0], m[3] + m[1], m[3] - m[1], m[3] + m[2], m[3] - m[2]])
    # the box corner furthest along each plane normal: outside if even that one is behind
    far = np.where(planes[None, :, :3] > 0, bvh.hi[:, None, :], bvh.lo[:, None, :])
    inside = ((far * planes[None, :, :3]).sum(-1) + planes[None, :, 3] >= 0).all(axis=1)
    idx = np.flatnonzero(inside)
    if not idx.size:
        return np.zeros((0, 3), np.int64)
    breaks = np.flatnonzero(np.diff(idx) != 1) + 1
    runs = np.split(idx, breaks)
    return np.array(
        [(bvh.leaves[r[0], 0], bvh.leaves[r[-1]].sum() - bvh.leaves[r[0], 0], len(r)) for r in runs], np.int64
    )
