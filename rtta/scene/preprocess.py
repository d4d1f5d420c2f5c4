"""Mesh preprocessing at load (Knecht & Mattausch, section 2.2): indexed vertices (identical
position, normal and texture coordinate merged) and normals smoothed by an angle threshold
where a file has none: at each position, a corner's normal is the area-weighted average of
the face normals around that position that lie within the threshold of its own face's
normal, so curved surfaces shade smoothly and hard edges stay hard.
"""

from __future__ import annotations

import numpy as np

DEFAULT_SMOOTH_ANGLE = 30.0
_PAIR_CHUNK = 4_000_000      # corner pairs compared at once (bounds the temporary memory)


def index_vertices(v: np.ndarray, f: np.ndarray, n: np.ndarray | None = None,
                   uv: np.ndarray | None = None) -> tuple[np.ndarray, np.ndarray, np.ndarray | None, np.ndarray | None]:
    """Merge vertices whose position, normal and uv are all identical; unused vertices go."""
    return _index(v, f, n, uv, None)[:4]


def smooth_normals(v: np.ndarray, f: np.ndarray, uv: np.ndarray | None = None,
                   angle: float = DEFAULT_SMOOTH_ANGLE) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray | None]:
    """(vertices, faces, normals, uv) with one normal per corner, smoothed across faces
    within `angle` degrees at the same position, then indexed again."""
    return _smooth(v, f, uv, angle, None)[:4]


def preprocess_objects(parts: list[tuple], angle: float, smooth: bool) -> list[tuple]:
    """index_vertices (parts with normals) or smooth_normals (parts without) for many objects
    at once, each exactly as if alone: [(vertices, faces, normals or None, uv or None)] ->
    [(vertices, faces, normals, uv or None)]. One vectorised pass per kind instead of one
    per object keeps scenes of tens of thousands of small objects fast."""
    out: list[tuple | None] = [None] * len(parts)
    for with_normals in (True, False):
        chosen = [i for i, p in enumerate(parts) if (p[2] is not None) == with_normals and not smooth] \
            if with_normals else [i for i, p in enumerate(parts) if p[2] is None or smooth]
        if not chosen:
            continue
        has_uv = any(parts[i][3] is not None for i in chosen)
        v, f, n, uv, group = _stack([parts[i] for i in chosen], with_normals, has_uv)
        if with_normals:
            result = _index(v, f, n, uv, group)
        else:
            result = _smooth(v, f, uv, angle, group)
        for k, obj in enumerate(_split(*result)):
            i = chosen[k]
            out[i] = (*obj[:3], obj[3] if parts[i][3] is not None else None)
    return out


def _stack(parts: list[tuple], with_normals: bool, has_uv: bool):
    """The parts as one mesh (faces offset) with a per-vertex group (the part's position)."""
    sizes = np.array([len(p[0]) for p in parts])
    offsets = np.concatenate([[0], np.cumsum(sizes)[:-1]])
    v = np.concatenate([np.asarray(p[0], np.float64) for p in parts])
    f = np.concatenate([np.asarray(p[1], np.int64) + o for p, o in zip(parts, offsets, strict=True)])
    n = np.concatenate([np.asarray(p[2], np.float64) for p in parts]) if with_normals else None
    uv = np.concatenate([np.zeros((len(p[0]), 2)) if p[3] is None else np.asarray(p[3], np.float64)
                         for p in parts]) if has_uv else None
    return v, f, n, uv, np.repeat(np.arange(len(parts)), sizes)


def _split(v, f, n, uv, group) -> list[tuple]:
    """Undo _stack: per group, its vertices (in the order a lone call gives) and faces."""
    order = np.argsort(group, kind="stable")
    where = np.empty_like(order)
    where[order] = np.arange(len(order))
    v, n, group = v[order], n[order], group[order]
    uv = None if uv is None else uv[order]
    f = where[f]
    face_group = group[f[:, 0]]
    f = f[np.argsort(face_group, kind="stable")]
    vcount = np.bincount(group)
    fcount = np.bincount(face_group, minlength=len(vcount))
    vstart = np.concatenate([[0], np.cumsum(vcount)[:-1]])
    fstart = np.concatenate([[0], np.cumsum(fcount)[:-1]])
    out = []
    for a, nv, b, nf in zip(vstart, vcount, fstart, fcount, strict=True):
        out.append((v[a:a + nv], f[b:b + nf] - a, n[a:a + nv], None if uv is None else uv[a:a + nv]))
    return out


def _index(v, f, n, uv, group):
    """index_vertices, keyed also by `group` (vertices of different groups never merge)."""
    cols = [] if group is None else [np.asarray(group, np.float64)[:, None]]
    cols += [np.asarray(v, np.float64)]
    cols += [np.asarray(a, np.float64) for a in (n, uv) if a is not None]
    key = np.ascontiguousarray(np.hstack(cols))
    used = np.unique(np.asarray(f, np.int64).reshape(-1))
    rows = key[used].view(np.dtype((np.void, key.dtype.itemsize * key.shape[1]))).ravel()
    _, first, inverse = np.unique(rows, return_index=True, return_inverse=True)
    remap = np.full(len(v), -1, np.int64)
    remap[used] = inverse.reshape(-1)
    keep = used[first]
    n, uv = (None if a is None else np.asarray(a)[keep] for a in (n, uv))
    return np.asarray(v)[keep], remap[np.asarray(f, np.int64)], n, uv, None if group is None else group[keep]


def _smooth(v, f, uv, angle, group):
    v = np.asarray(v, np.float64)
    f = np.asarray(f, np.int64)
    fn = np.cross(v[f[:, 1]] - v[f[:, 0]], v[f[:, 2]] - v[f[:, 0]])        # area-weighted
    length = np.linalg.norm(fn, axis=1, keepdims=True)
    unit = fn / np.where(length > 0, length, 1.0)
    corner_vertex = f.reshape(-1)
    corner_face = np.repeat(np.arange(len(f)), 3)
    where = v if group is None else np.hstack([np.asarray(group, np.float64)[:, None], v])
    _, position = np.unique(where, axis=0, return_inverse=True)
    position = position.reshape(-1)[corner_vertex]
    normals = _grouped_sums(position, corner_face, unit, fn, np.cos(np.radians(angle)))
    nlen = np.linalg.norm(normals, axis=1, keepdims=True)
    normals = np.where(nlen > 0, normals / np.where(nlen > 0, nlen, 1.0), unit[corner_face])
    corner_uv = None if uv is None else np.asarray(uv)[corner_vertex]
    return _index(v[corner_vertex], np.arange(len(corner_vertex)).reshape(-1, 3), normals.astype(np.float32),
                  corner_uv, None if group is None else np.asarray(group)[corner_vertex])


def _grouped_sums(position: np.ndarray, corner_face: np.ndarray, unit: np.ndarray, fn: np.ndarray,
                  cos_limit: float) -> np.ndarray:
    """Per corner: the sum of fn over corners at the same position whose face normal is
    within the angle of this corner's face normal (itself included)."""
    order = np.argsort(position, kind="stable")
    sorted_pos = position[order]
    starts = np.flatnonzero(np.r_[True, sorted_pos[1:] != sorted_pos[:-1]])
    sizes = np.diff(np.r_[starts, len(order)])
    group_start = np.repeat(starts, sizes)            # per sorted corner
    group_size = np.repeat(sizes, sizes)
    out = np.zeros((len(order), 3))
    cumulative = np.cumsum(group_size)
    begin = 0
    while begin < len(order):
        end = int(np.searchsorted(cumulative, cumulative[begin] - group_size[begin] + _PAIR_CHUNK, side="right"))
        end = max(end, begin + 1)
        k = group_size[begin:end]
        i = np.repeat(np.arange(begin, end), k)                  # sorted corner
        j = np.repeat(group_start[begin:end], k) + _ramp(k)      # its partners
        fi, fj = corner_face[order[i]], corner_face[order[j]]
        near = np.einsum("ij,ij->i", unit[fi], unit[fj]) >= cos_limit
        np.add.at(out, order[i[near]], fn[fj[near]])
        begin = end
    return out


def _ramp(k: np.ndarray) -> np.ndarray:
    """0..k[0]-1, 0..k[1]-1, ... concatenated."""
    total = int(k.sum())
    offsets = np.repeat(np.cumsum(k) - k, k)
    return np.arange(total) - offsets
