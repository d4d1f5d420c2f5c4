"""Whole-scene preprocessing: indexing and normal smoothing of many meshes at once.

The meshes (each a "group") are concatenated and every step runs as one numpy pass over
a chunk of groups, keyed by group, so nothing merges across meshes and no Python loop runs
per mesh: 10^5 parts cost a few dozen passes, not 10^5 small ones. The results match
preprocess.index_vertices / smooth_normals applied to each mesh alone: the same triangles
and normals, the vertices in order of first appearance (those functions sort them).
"""

from __future__ import annotations

import os
from concurrent.futures import ThreadPoolExecutor
from dataclasses import dataclass

import numpy as np

CHUNK_CORNERS = 100_000  # corners per pass (bounds the temporary memory: one pass per thread)
THREADS = min(4, os.cpu_count() or 1)  # passes run at once


_MIX = np.uint64(0x9E3779B97F4A7C15)


def _words(a: np.ndarray) -> np.ndarray:
    """The rows of a as uint32 or uint64 words [N, k] (their exact bits)."""
    a = np.ascontiguousarray(a)
    a = a.reshape(len(a), -1)
    return a.view(np.uint64 if a.dtype.itemsize == 8 else np.uint32)


def unique_rows(*cols: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """(first, inverse) for the distinct rows of the columns side by side, bit for bit:
    `first` is the first row of each distinct value, in order of first appearance (so rows
    in group order stay in group order), and inverse[i] the distinct value of row i. One
    64-bit hash per row is sorted (not the rows); a hash collision is detected and then
    the rows themselves are compared."""
    words = [_words(c) for c in cols]
    h = np.zeros(len(words[0]), np.uint64)
    with np.errstate(over="ignore"):
        for w in words:
            for j in range(w.shape[1]):
                h = (h ^ w[:, j].astype(np.uint64)) * _MIX
                h ^= h >> np.uint64(31)
    first, inverse = _distinct(h)
    if not all((w[first][inverse] == w).all() for w in words):  # a collision: exact but slower
        key = np.ascontiguousarray(np.hstack([w.view(np.uint8).reshape(len(w), -1) for w in words]))
        _, first, inverse = np.unique(
            key.view(np.dtype((np.void, key.shape[1]))).ravel(), return_index=True, return_inverse=True
        )
        inverse = inverse.reshape(-1)
    mark = np.full(len(h), -1, np.int64)  # the distinct values in order of first appearance:
    mark[first] = np.arange(len(first))  # first indices are distinct rows, so no sort is needed
    order = mark[mark >= 0]
    rank = np.empty_like(order)
    rank[order] = np.arange(len(order))
    return first[order], rank[inverse]


def _distinct(h: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """np.unique(h, return_index=True, return_inverse=True)[1:], with an unstable sort (about
    twice as fast as the stable one np.unique needs for return_index) and each value's first
    row found as the least row of its run."""
    order = np.argsort(h)
    hs = h[order]
    new = np.empty(len(h), bool)
    new[:1] = True
    np.not_equal(hs[1:], hs[:-1], out=new[1:])
    starts = np.flatnonzero(new)
    first = np.minimum.reduceat(order, starts) if len(h) else order
    inverse = np.empty(len(h), np.int64)
    inverse[order] = np.cumsum(new) - 1
    return first, inverse


def index_grouped(
    v: np.ndarray,
    f: np.ndarray,
    group: np.ndarray,
    n: np.ndarray | None = None,
    uv: np.ndarray | None = None,
    position: np.ndarray | None = None,
) -> tuple:
    """index_vertices for many meshes at once: `group` names each vertex's mesh, and f's
    indices are into the concatenated `v` (which is in group order). Returns (v, f, n, uv,
    group), the kept vertices in group order, so each mesh's stay contiguous. `position`,
    when given, identifies equal (group, vertex position) pairs and stands in for them."""
    f = np.asarray(f, np.int64)
    used = np.flatnonzero(np.bincount(f.reshape(-1), minlength=len(v)))
    where = [np.asarray(group)[used], np.asarray(v)[used]] if position is None else [position[used]]
    cols = where + [np.asarray(a)[used] for a in (n, uv) if a is not None]
    first, inverse = unique_rows(*cols)
    remap = np.full(len(v), -1, np.int64)
    remap[used] = inverse
    keep = used[first]
    n, uv = (None if a is None else np.asarray(a)[keep] for a in (n, uv))
    return np.asarray(v)[keep], remap[f], n, uv, np.asarray(group)[keep]


def smooth_grouped(v: np.ndarray, f: np.ndarray, group: np.ndarray, uv: np.ndarray | None, angle: float) -> tuple:
    """smooth_normals for many meshes at once (see index_grouped for the arguments)."""
    v = np.asarray(v, np.float64)
    f = np.asarray(f, np.int64)
    fn = np.cross(v[f[:, 1]] - v[f[:, 0]], v[f[:, 2]] - v[f[:, 0]])
    length = np.linalg.norm(fn, axis=1, keepdims=True)
    unit = fn / np.where(length > 0, length, 1.0)
    corner_vertex = f.reshape(-1)
    corner_face = np.repeat(np.arange(len(f)), 3)
    position = unique_rows(np.asarray(group, np.int64), v)[1][corner_vertex]
    normals = grouped_sums(position, corner_face, unit, fn, np.cos(np.radians(angle)))
    nlen = np.linalg.norm(normals, axis=1, keepdims=True)
    normals = np.where(nlen > 0, normals / np.where(nlen > 0, nlen, 1.0), unit[corner_face])
    corner_uv = None if uv is None else np.asarray(uv)[corner_vertex]
    return index_grouped(
        v[corner_vertex],
        np.arange(len(corner_vertex)).reshape(-1, 3),
        group[corner_vertex],
        normals.astype(np.float32),
        corner_uv,
        position=position,
    )


def grouped_sums(
    position: np.ndarray, corner_face: np.ndarray, unit: np.ndarray, fn: np.ndarray, cos_limit: float
) -> np.ndarray:
    """preprocess._grouped_sums, faster: per corner, the sum of fn over corners at the same
    position whose face normal is within the angle of this corner's face normal (itself
    included). Where every face normal at a position lies within half the angle of their
    mean direction, all pairs there are within the angle (triangle inequality), so the sum
    is the position's total; corner pairs are compared only at the other positions (box
    edges, creases), and summed with bincount (np.add.at is slow)."""
    count = int(position.max()) + 1 if len(position) else 0
    u, w = unit[corner_face], fn[corner_face]
    mean = np.stack([np.bincount(position, weights=u[:, c], minlength=count) for c in range(3)], axis=1)
    length = np.linalg.norm(mean, axis=1, keepdims=True)
    mean = mean / np.where(length > 0, length, 1.0)
    half = np.cos(np.arccos(np.clip(cos_limit, -1.0, 1.0)) / 2.0) + 1e-9
    uniform = length[:, 0] > 0
    uniform[position[np.einsum("ij,ij->i", u, mean[position]) < half]] = False
    total = np.stack([np.bincount(position, weights=w[:, c], minlength=count) for c in range(3)], axis=1)
    out = total[position]
    rest = np.flatnonzero(~uniform[position])
    if len(rest):
        out[rest] = _pair_sums(position[rest], corner_face[rest], unit, fn, cos_limit)
    return out


PAIR_BLOCK, MAX_PAIR_CORNERS = 1 << 21, 2048  # pairs per block (memory); most corners at a position compared


def _pair_sums(
    position: np.ndarray, corner_face: np.ndarray, unit: np.ndarray, fn: np.ndarray, cos_limit: float
) -> np.ndarray:
    """grouped_sums by comparing every pair of corners at a position. Positions are taken
    by their corner count s, all positions of one count as dense [P, s] blocks: the s x s
    dot products, the within-angle mask and the masked sums are whole-block products, so
    each corner's normal and weight are gathered once, not once per partner. Over PAIR_BLOCK
    pairs a position is compared some rows at a time; over MAX_PAIR_CORNERS corners (a 40,000-
    sided cone's apex: 1.6e9 pairs) each keeps its own face's normal, as a symmetric apex sums."""
    small = position.max(initial=0) < 1 << 16  # a pass's positions mostly are: radix sort, O(n)
    order = np.argsort(position.astype(np.uint16) if small else position, kind="stable")
    sorted_pos = position[order]
    starts = np.flatnonzero(np.r_[True, sorted_pos[1:] != sorted_pos[:-1]])
    sizes = np.diff(np.r_[starts, len(order)])
    faces = corner_face[order]
    out = np.empty((len(order), 3))
    for s in np.unique(sizes).tolist():
        first = starts[sizes == s]
        if s * s > PAIR_BLOCK:  # one position at a time
            for at, own in ((at, faces[at : at + s]) for at in first.tolist()):
                out[order[at : at + s]] = fn[own] if s > MAX_PAIR_CORNERS else _wide_sums(own, unit, fn, cos_limit)
            continue
        step = max(1, PAIR_BLOCK // (s * s))
        for b in range(0, len(first), step):
            corners = first[b : b + step, None] + np.arange(s)  # [P, s] sorted corners
            u = unit[faces[corners]]  # [P, s, 3]
            w = fn[faces[corners]]
            dots = u[:, :, None, 0] * u[:, None, :, 0]
            dots += u[:, :, None, 1] * u[:, None, :, 1]
            dots += u[:, :, None, 2] * u[:, None, :, 2]  # [P, s, s]
            near = (dots >= cos_limit).astype(np.float64)
            out[order[corners.reshape(-1)]] = np.matmul(near, w).reshape(-1, 3)
    return out


def _wide_sums(faces: np.ndarray, unit: np.ndarray, fn: np.ndarray, cos_limit: float) -> np.ndarray:
    """_pair_sums at one position of many corners (their `faces`), a block of rows at a time."""
    u, w = unit[faces], fn[faces]
    out = np.empty((len(faces), 3))
    for r in range(0, len(faces), rows := max(1, PAIR_BLOCK // len(faces))):
        dots = u[r : r + rows, None, 0] * u[None, :, 0] + u[r : r + rows, None, 1] * u[None, :, 1]
        dots += u[r : r + rows, None, 2] * u[None, :, 2]
        out[r : r + rows] = np.matmul((dots >= cos_limit).astype(np.float64), w)
    return out


@dataclass
class Meshes:
    """Many meshes concatenated: vertices [V, 3], faces [F, 3] (indices local to their
    mesh), per-vertex normals (float32, or None: none given) and uvs (or None), and per
    mesh its vertex and face counts."""

    vertices: np.ndarray
    faces: np.ndarray
    vcount: np.ndarray
    fcount: np.ndarray
    normals: np.ndarray | None = None
    uvs: np.ndarray | None = None

    @property
    def vstart(self) -> np.ndarray:
        return np.concatenate([[0], np.cumsum(self.vcount)[:-1]]).astype(np.int64)

    @property
    def fstart(self) -> np.ndarray:
        return np.concatenate([[0], np.cumsum(self.fcount)[:-1]]).astype(np.int64)


def ramp(k: np.ndarray) -> np.ndarray:
    """0..k[0]-1, 0..k[1]-1, ... concatenated."""
    k = np.asarray(k, np.int64)
    return np.arange(int(k.sum())) - np.repeat(np.cumsum(k) - k, k)


def fans(starts: np.ndarray, sizes: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Polygons of `sizes` corners from `starts` in a flat corner array, as triangle fans
    (0, k, k + 1) around each one's first corner: (the polygon of each triangle [T], the
    triangles' places in the corner array [T, 3]). OBJ and USD faces are convex polygons."""
    per = np.asarray(sizes, np.int64) - 2
    polygon = np.repeat(np.arange(len(per)), per)
    k = ramp(per)
    s = np.asarray(starts, np.int64)[polygon]
    return polygon, np.stack([s, s + k + 1, s + k + 2], axis=1)


def preprocess(meshes: Meshes, smooth: np.ndarray, angle: float) -> Meshes:
    """Index every mesh, smoothing the normals of those where `smooth` is set (the others
    keep meshes.normals), in passes of whole meshes of at most CHUNK_CORNERS corners."""
    n = len(meshes.vcount)
    order = np.concatenate([np.flatnonzero(smooth), np.flatnonzero(~smooth)])
    cumulative = np.cumsum(3 * meshes.fcount[order])
    vstart, fstart = meshes.vstart, meshes.fstart
    jobs, begin = [], 0
    while begin < len(order):
        base = int(cumulative[begin - 1]) if begin else 0
        end = max(begin + 1, int(np.searchsorted(cumulative, base + CHUNK_CORNERS, side="right")))
        ids, begin = order[begin:end], end
        jobs += [(sel, flag) for flag in (True, False) if len(sel := ids[smooth[ids] == flag])]

    def run(job: tuple) -> tuple:
        return _compact(job[0], _pass(meshes, job[0], vstart, fstart, job[1], angle))

    return _gather(parallel(run, jobs), n)


def parallel(fn, jobs: list) -> list:
    """[fn(job) for job in jobs] on up to THREADS threads (numpy releases the GIL in the
    passes' sorts, sums and products). On an error or an interrupt (a signal's exception
    in the waiting main thread) the jobs not yet started are cancelled, so a stopped load
    stops within one pass, not after all of them."""
    workers = min(len(jobs), THREADS)
    if workers <= 1:
        return [fn(job) for job in jobs]
    pool = ThreadPoolExecutor(workers)
    try:
        return list(pool.map(fn, jobs))
    finally:
        pool.shutdown(wait=True, cancel_futures=True)


def _pass(
    meshes: Meshes, sel: np.ndarray, vstart: np.ndarray, fstart: np.ndarray, smoothed: bool, angle: float
) -> tuple:
    vi = np.repeat(vstart[sel], meshes.vcount[sel]) + ramp(meshes.vcount[sel])
    fi = np.repeat(fstart[sel], meshes.fcount[sel]) + ramp(meshes.fcount[sel])
    local_base = np.repeat(np.concatenate([[0], np.cumsum(meshes.vcount[sel])[:-1]]), meshes.fcount[sel])
    f = meshes.faces[fi] + local_base[:, None]
    group = np.repeat(np.arange(len(sel)), meshes.vcount[sel])
    uv = None if meshes.uvs is None else meshes.uvs[vi]
    v = meshes.vertices[vi]
    if smoothed:
        return smooth_grouped(v, f, group, uv, angle)
    if meshes.normals is None:
        raise ValueError("meshes without normals need `smooth` set (smoothing makes their normals)")
    return index_grouped(v, f, group, meshes.normals[vi], uv)


def _compact(sel: np.ndarray, result: tuple) -> tuple:
    """A pass's output as (meshes, vcount, fcount, v, faces local to their mesh as int32,
    normals, uvs): the per-vertex group ids are dropped as soon as they are counted."""
    v, f, nrm, uv, group = result
    vcount = np.bincount(group, minlength=len(sel))
    first = np.concatenate([[0], np.cumsum(vcount)[:-1]])
    owner = group[f[:, 0]]
    return sel, vcount, np.bincount(owner, minlength=len(sel)), v, (f - first[owner][:, None]).astype(np.int32), nrm, uv


def _gather(passes: list[tuple], n: int) -> Meshes:
    """The passes' outputs copied straight into mesh order (each pass's meshes are
    ascending, so a pass fills its meshes' slots in one assignment); each pass is freed
    once copied."""
    vcount = np.zeros(n, np.int64)
    fcount = np.zeros(n, np.int64)
    for sel, vc, fc, *_ in passes:
        vcount[sel], fcount[sel] = vc, fc
    vstart = np.concatenate([[0], np.cumsum(vcount)[:-1]])
    fstart = np.concatenate([[0], np.cumsum(fcount)[:-1]])
    total_v, total_f = int(vcount.sum()), int(fcount.sum())
    v = np.empty((total_v, 3))
    faces = np.empty((total_f, 3), np.int32)
    nrm = np.empty((total_v, 3), np.float32)
    uv = None if passes[0][6] is None else np.empty((total_v, 2), np.float32)
    while passes:
        sel, vc, fc, pv, pf, pn, puv = passes.pop(0)
        vi = np.repeat(vstart[sel], vc) + ramp(vc)
        fi = np.repeat(fstart[sel], fc) + ramp(fc)
        v[vi], nrm[vi], faces[fi] = pv, pn, pf
        if uv is not None:
            uv[vi] = puv
    return Meshes(v, faces, vcount, fcount, nrm, uv)


def similar(m: np.ndarray) -> np.ndarray:
    """Per 4x4 transform [N, 4, 4]: a rotation with uniform positive scale (and a
    translation), under which smoothing in the mesh's own space equals smoothing in world."""
    r = m[:, :3, :3]
    gram = np.einsum("nki,nkj->nij", r, r)
    s = np.trace(gram, axis1=1, axis2=2) / 3.0
    off = np.abs(gram - s[:, None, None] * np.eye(3)).max(axis=(1, 2))
    return np.isfinite(s) & (s > 0) & (off <= 1e-9 * s) & (np.linalg.det(r) > 0)


def rows_within(v: np.ndarray, limit: float) -> np.ndarray:
    """bool [V]: every coordinate of the row within ±limit (NaN is not); in chunks, no copy of all."""
    step = 1 << 18
    return (
        np.concatenate([np.abs(v[a : a + step]).max(axis=1) <= limit for a in range(0, len(v), step)])
        if len(v)
        else np.zeros(0, bool)
    )


def has_area(meshes: Meshes) -> np.ndarray:
    """Per mesh: whether any triangle has a non-zero area (relative to the mesh's size)."""
    v, vstart = meshes.vertices, meshes.vstart
    extent = (np.maximum.reduceat(v, vstart, axis=0) - np.minimum.reduceat(v, vstart, axis=0)).max(axis=1)
    area = np.zeros(len(meshes.fcount))
    owner = np.repeat(np.arange(len(meshes.fcount)), meshes.fcount)
    step = 1 << 16
    for a in range(0, len(meshes.faces), step):
        o = owner[a : a + step]
        f = meshes.faces[a : a + step] + vstart[o][:, None]
        cross = np.cross(v[f[:, 1]] - v[f[:, 0]], v[f[:, 2]] - v[f[:, 0]])
        area = np.maximum(area, _max_by(o, np.einsum("ij,ij->i", cross, cross), len(area)))
    return (extent > 0) & (area > (extent * 1e-12) ** 4)


def _max_by(owner: np.ndarray, values: np.ndarray, n: int) -> np.ndarray:
    """The largest value per owner (owners ascending), 0 where an owner has none."""
    out = np.zeros(n)
    starts = np.flatnonzero(np.r_[True, owner[1:] != owner[:-1]])
    out[owner[starts]] = np.maximum.reduceat(values, starts)
    return out


def instance(meshes: Meshes, mesh_of: np.ndarray, transforms: np.ndarray, consume: bool = False) -> Meshes:
    """The meshes placed once per instance (mesh index, 4x4 transform), in instance order:
    world vertices (float64) and normals by the inverse transpose, renormalised. `consume`:
    `meshes` is not used afterwards, so where each mesh is placed once, in order (CAD
    assemblies: one mesh per part), its arrays are transformed in place, not copied."""
    vcount, fcount = meshes.vcount[mesh_of], meshes.fcount[mesh_of]
    given = meshes.normals
    if given is None:
        raise ValueError("instance() places meshes with normals")
    once = consume and len(mesh_of) == len(meshes.vcount) and bool((mesh_of == np.arange(len(mesh_of))).all())
    vi = None if once else np.repeat(meshes.vstart[mesh_of], vcount) + ramp(vcount)
    r = transforms[:, :3, :3]
    with np.errstate(all="ignore"):
        normal_matrix = np.linalg.inv(r)  # n' = n @ inv(R) is (inv(R)^T n)^T
    total = int(vcount.sum())
    world = meshes.vertices if once else np.empty((total, 3))
    normals = given if once else np.empty((total, 3), np.float32)
    owner = np.repeat(np.arange(len(mesh_of)), vcount)
    step = 1 << 16

    def place(a: int) -> None:  # rows a..a+step: each chunk reads and writes its own
        rows = slice(a, a + step) if vi is None else vi[a : a + step]  # (vi is None when once)
        o, local = owner[a : a + step], meshes.vertices[rows]
        n = np.einsum("vj,vji->vi", given[rows].astype(np.float64), normal_matrix[o])
        world[a : a + step] = np.einsum("vj,vij->vi", local, r[o]) + transforms[o, :3, 3]
        length = np.linalg.norm(n, axis=1, keepdims=True)
        normals[a : a + step] = n / np.where(length > 0, length, 1.0)

    parallel(place, list(range(0, total, step)))
    if once:
        return Meshes(world, meshes.faces, vcount, fcount, normals, meshes.uvs)
    fi = np.repeat(meshes.fstart[mesh_of], fcount) + ramp(fcount)
    uvs = None if meshes.uvs is None else meshes.uvs[vi]
    return Meshes(world, meshes.faces[fi], vcount, fcount, normals, uvs)
