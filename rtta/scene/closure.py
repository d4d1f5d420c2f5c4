"""Which objects are closed surfaces facing outward: from outside, each of their back faces
lies behind one of their front faces, so the scene passes cull back faces for them. On
llvmpipe a large scene's draw is mostly triangle setup: at 10,000 parts culling cut STD and
capture by about 30%, and in the atlas each object keeps the same front surface.

An object qualifies when every directed edge of its triangles (between positions: vertices
split for normals or uvs are one position) is matched by the opposite edge of another of
its triangles (no boundary, consistent winding) and its signed volume is positive. The
matching is tested without sorting: per object, a 64-bit hash summed over the directed
edges equals the sum over the reversed edges exactly when the edges pair up (up to hash
collisions, about 2^-64). A degenerate triangle (two corners at one position) adds the same
to both sums, so it neither opens nor closes a surface. Open sheets, cut or one-sided
surfaces and inside-out meshes stay double-sided."""

from __future__ import annotations

import numpy as np

from .camera import view_depth

CHUNK_TRIANGLES = 1 << 18
_M1, _M2 = np.uint64(0xBF58476D1CE4E5B9), np.uint64(0x94D049BB133111EB)
_K = np.uint64(0x9E3779B97F4A7C15)


def _mix(x: np.ndarray) -> np.ndarray:
    """splitmix64's finaliser, elementwise on uint64 (wrapping)."""
    x = (x ^ (x >> np.uint64(30))) * _M1
    x = (x ^ (x >> np.uint64(27))) * _M2
    return x ^ (x >> np.uint64(31))


def _position_hashes(positions: np.ndarray) -> np.ndarray:
    """A 64-bit hash of each vertex's exact float32 position (equal positions, equal hashes)."""
    bits = np.ascontiguousarray(positions, np.float32).view(np.uint32).astype(np.uint64)
    bits[bits == np.uint64(0x80000000)] = 0  # -0.0 is 0.0
    h = _mix(bits[:, 0] + _K)
    h = _mix(h ^ bits[:, 1])
    return _mix(h ^ (bits[:, 2] << np.uint64(7)))


def closed_objects(
    positions: np.ndarray, indices: np.ndarray, index_ranges: np.ndarray, centers: np.ndarray
) -> np.ndarray:
    """bool [N]: whether object i (triangles indices[first:first + count] of index_ranges,
    in object order) is a closed surface with positive volume. `centers`: float64 [N, 3], a
    point near each object (its bounds' centre), so the volume is summed in small numbers."""
    n = len(index_ranges)
    hp = _position_hashes(positions)
    tri_first, tri_count = index_ranges[:, 0] // 3, index_ranges[:, 1] // 3
    total = int(tri_count.sum())
    owner = np.repeat(np.arange(n), tri_count)
    tris = np.asarray(indices).reshape(-1, 3)
    imbalance = np.zeros(n, np.uint64)
    volume = np.zeros(n, np.float64)
    offset = tri_first - (np.cumsum(tri_count) - tri_count)  # triangle k of the scene lies at row k + offset
    used = offset[tri_count > 0]
    uniform = len(used) == 0 or bool((used == used[0]).all())
    with np.errstate(over="ignore"):
        for a in range(0, total, CHUNK_TRIANGLES):
            o = owner[a : a + CHUNK_TRIANGLES]
            k = np.arange(a, a + len(o))
            t = tris[k + (offset[o[0]] if uniform else offset[o])]
            h = hp[t]  # [k, 3]
            fwd = _mix(h * _K + np.roll(h, -1, axis=1))  # edges (a, b), (b, c), (c, a)
            rev = _mix(np.roll(h, -1, axis=1) * _K + h)  # the same edges reversed
            diff = fwd.sum(axis=1) - rev.sum(axis=1)  # wraps: exact modulo 2^64
            p = positions[t].astype(np.float64) - centers[o][:, None, :]
            vol = np.einsum("ij,ij->i", p[:, 0], np.cross(p[:, 1], p[:, 2]))
            cuts = np.flatnonzero(np.r_[True, o[1:] != o[:-1]])
            imbalance[o[cuts]] += np.add.reduceat(diff, cuts)
            volume[o[cuts]] += np.add.reduceat(vol, cuts)
    return (imbalance == 0) & (volume > 0) & (tri_count > 0)


def beyond_near(aabb_min: np.ndarray, aabb_max: np.ndarray, view: np.ndarray, proj: np.ndarray) -> np.ndarray:
    """bool [N]: whether each box (relative to the scene origin, as `view` expects) lies
    wholly beyond the near plane of the perspective or orthographic `proj`. Culling back faces
    is exact only there: where the near plane cuts an object (or the camera is inside it), its
    back faces show through the cut, as the file's surface does without culling."""
    near = float(view_depth(0.0, proj))  # window depth 0 lies on the near plane
    row = np.asarray(view, np.float64)[2]
    center, half = (aabb_max + aabb_min) / 2.0, (aabb_max - aabb_min) / 2.0
    nearest = center @ row[:3] + row[3] + half @ np.abs(row[:3])  # the box's largest view z (forward is -z)
    return nearest < -near
