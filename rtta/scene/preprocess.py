"""Mesh preprocessing at load (Knecht & Mattausch, section 2.2): indexed vertices (identical
position, normal and texture coordinate merged) and normals smoothed by an angle threshold
where a file has none: at each position, a corner's normal is the area-weighted average of
the face normals around that position that lie within the threshold of its own face's
normal, so curved surfaces shade smoothly and hard edges stay hard.
"""

from __future__ import annotations

import numpy as np

from .batch import ramp

DEFAULT_SMOOTH_ANGLE = 30.0
_PAIR_CHUNK = 4_000_000  # corner pairs compared at once (bounds the temporary memory)


def index_vertices(
    v: np.ndarray, f: np.ndarray, n: np.ndarray | None = None, uv: np.ndarray | None = None
) -> tuple[np.ndarray, np.ndarray, np.ndarray | None, np.ndarray | None]:
    """Merge vertices whose position, normal and uv are all identical; unused vertices go."""
    return _index(v, f, n, uv)


def smooth_normals(
    v: np.ndarray, f: np.ndarray, uv: np.ndarray | None = None, angle: float = DEFAULT_SMOOTH_ANGLE
) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray | None]:
    """(vertices, faces, normals, uv) with one normal per corner, smoothed across faces
    within `angle` degrees at the same position, then indexed again."""
    return _smooth(v, f, uv, angle)


def _index(v, f, n, uv):
    """index_vertices: vertices equal in position, normal and uv merged."""
    cols = [np.asarray(v, np.float64)]
    cols += [np.asarray(a, np.float64) for a in (n, uv) if a is not None]
    key = np.ascontiguousarray(np.hstack(cols))
    used = np.unique(np.asarray(f, np.int64).reshape(-1))
    rows = key[used].view(np.dtype((np.void, key.dtype.itemsize * key.shape[1]))).ravel()
    _, first, inverse = np.unique(rows, return_index=True, return_inverse=True)
    remap = np.full(len(v), -1, np.int64)
    remap[used] = inverse.reshape(-1)
    keep = used[first]
    n, uv = (None if a is None else np.asarray(a)[keep] for a in (n, uv))
    return np.asarray(v)[keep], remap[np.asarray(f, np.int64)], n, uv


def _smooth(v, f, uv, angle):
    v = np.asarray(v, np.float64)
    f = np.asarray(f, np.int64)
    fn = np.cross(v[f[:, 1]] - v[f[:, 0]], v[f[:, 2]] - v[f[:, 0]])  # area-weighted
    length = np.linalg.norm(fn, axis=1, keepdims=True)
    unit = fn / np.where(length > 0, length, 1.0)
    corner_vertex = f.reshape(-1)
    corner_face = np.repeat(np.arange(len(f)), 3)
    _, position = np.unique(v, axis=0, return_inverse=True)
    position = position.reshape(-1)[corner_vertex]
    normals = _grouped_sums(position, corner_face, unit, fn, np.cos(np.radians(angle)))
    nlen = np.linalg.norm(normals, axis=1, keepdims=True)
    normals = np.where(nlen > 0, normals / np.where(nlen > 0, nlen, 1.0), unit[corner_face])
    corner_uv = None if uv is None else np.asarray(uv)[corner_vertex]
    v, f, n, uv = _index(
        v[corner_vertex], np.arange(len(corner_vertex)).reshape(-1, 3), normals.astype(np.float32), corner_uv
    )
    assert n is not None  # (given)
    return v, f, n, uv


def _grouped_sums(
    position: np.ndarray, corner_face: np.ndarray, unit: np.ndarray, fn: np.ndarray, cos_limit: float
) -> np.ndarray:
    """Per corner: the sum of fn over corners at the same position whose face normal is
    within the angle of this corner's face normal (itself included)."""
    order = np.argsort(position, kind="stable")
    sorted_pos = position[order]
    starts = np.flatnonzero(np.r_[True, sorted_pos[1:] != sorted_pos[:-1]])
    sizes = np.diff(np.r_[starts, len(order)])
    group_start = np.repeat(starts, sizes)  # per sorted corner
    group_size = np.repeat(sizes, sizes)
    out = np.zeros((len(order), 3))
    cumulative = np.cumsum(group_size)
    begin = 0
    while begin < len(order):
        end = int(np.searchsorted(cumulative, cumulative[begin] - group_size[begin] + _PAIR_CHUNK, side="right"))
        end = max(end, begin + 1)
        k = group_size[begin:end]
        i = np.repeat(np.arange(begin, end), k)  # sorted corner
        j = np.repeat(group_start[begin:end], k) + ramp(k)  # its partners
        fi, fj = corner_face[order[i]], corner_face[order[j]]
        near = np.einsum("ij,ij->i", unit[fi], unit[fj]) >= cos_limit
        np.add.at(out, order[i[near]], fn[fj[near]])
        begin = end
    return out
