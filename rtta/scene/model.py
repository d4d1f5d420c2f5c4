"""Scenes: every scene-graph node with geometry is one object; all objects are batched into
ONE vertex/index buffer carrying a per-vertex object id. Positions are stored in float32
relative to `origin` (the bounds centre, float64): a scene far from the world origin keeps
full precision on the GPU.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from ..errors import RttaError, member, printable
from .bounds import BOUNDS, Bounds, BoundsName
from .closure import closed_objects
from .meshes_check import checked_colors, checked_parts

# Corner i of a box has bit 0 -> x max, bit 1 -> y max, bit 2 -> z max.
BOX_EDGES = np.array(
    [(0, 1), (2, 3), (4, 5), (6, 7), (0, 2), (1, 3), (4, 6), (5, 7), (0, 4), (1, 5), (2, 6), (3, 7)], dtype=np.intp
)
_BITS = np.array([[(i >> k) & 1 for k in range(3)] for i in range(8)], dtype=bool)
# scene extent below which a GPU may draw nothing (scripts/probe_tiny.py: llvmpipe draws a box
# down to 1e-36 units and nothing at 1e-38, where float32 underflows; an NVIDIA H200 draws it
# whole at 1e-15, 4% of it at 1e-20 and nothing at 1e-25, its clipping losing w that small)
TINY_SCENE = 1e-15


@dataclass
class Scene:
    """A batched scene: ONE vertex and index buffer with an object id per vertex.

    Attributes
    ----------
    names : list of str
        Object names, indexed by object id (unique, numbered in file order).
    positions, normals : numpy.ndarray
        float32 [V, 3]; positions relative to `origin` (float32 precision far from the origin).
    object_ids, indices, index_ranges : numpy.ndarray
        uint32 [V] per vertex; uint32 [3F] triangles; int64 [N, 2] (first, count) per object.
    colors, aabb_min, aabb_max : numpy.ndarray
        float32 [N, 4] base colours; float64 [N, 3] world bounds (B_world).
    paths, unit, up_axis
        Each object's groups in the file's tree (root first, or None); the length unit ('' =
        unstated); the file's up axis, 'y' or 'z'.
    warnings, inputs : list of str
        Problems worked around while loading; the files read (outputs never replace them).
    """

    names: list[str]
    positions: np.ndarray  # float32 [V, 3], relative to origin
    normals: np.ndarray  # float32 [V, 3]
    object_ids: np.ndarray  # uint32 [V]
    indices: np.ndarray  # uint32 [F*3]
    index_ranges: np.ndarray  # int64 [N, 2]: (first, count) into indices
    colors: np.ndarray  # float32 [N, 4]
    aabb_min: np.ndarray  # float64 [N, 3], world (B_world)
    aabb_max: np.ndarray  # float64 [N, 3]
    origin: np.ndarray  # float64 [3]
    source: str = "<memory>"
    warnings: list[str] = field(default_factory=list)  # problems loading worked around
    inputs: list[str] = field(default_factory=list)  # the files it was read from (outputs never replace them)
    uvs: np.ndarray | None = None  # float32 [V, 2] when the scene has textures
    textures: list[np.ndarray] = field(default_factory=list)  # uint8 [h, w, 4], row 0 = v 0, each once
    texture_ids: np.ndarray | None = None  # int32 [N]: index into textures, -1 = material colour only
    paths: list[tuple[str, ...]] | None = None  # per object: its groups in the file's tree, root first
    unit: str = ""  # length unit of the coordinates ('m', 'mm', 'in'...; '' = unstated)
    up_axis: str = "y"  # the file's up axis: 'y' (glTF) or 'z' (CAD, BIM)
    _corners: dict = field(default_factory=dict, repr=False)

    @property
    def count(self) -> int:
        return len(self.names)

    @property
    def textured(self) -> bool:
        """Whether any object has a base-colour texture (else the material atlas is skipped)."""
        return bool(self.textures) and self.uvs is not None

    @property
    def vertex_count(self) -> int:
        return int(self.positions.shape[0])

    def _reduced(self) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray, np.ndarray, float]:
        """(lo, hi, low, high, centre, radius) of the box arrays, once per arrays (frames ask often)."""
        made, lo, hi = self._corners.get("bounds"), self.aabb_min, self.aabb_max
        if made is None or made[0] is not lo or made[1] is not hi:
            low, high = lo.min(axis=0), hi.max(axis=0)
            r = float(np.linalg.norm(high - low) / 2.0)
            r = r if r > 0 else max(1e-6, float(np.abs(low).max()) * 1e-7)
            made = self._corners["bounds"] = (lo, hi, low, high, (low + high) / 2.0, r)
        return made

    @property
    def bounds(self) -> tuple[np.ndarray, np.ndarray]:
        """The scene's box (lo, hi)."""
        made = self._reduced()
        return made[2].copy(), made[3].copy()

    center = property(lambda self: self._reduced()[4].copy(), doc="The centre of `bounds`.")
    radius = property(lambda self: self._reduced()[5], doc="Bounding-sphere radius about `center` (never zero).")

    def box_corners(self, kind: BoundsName | Bounds = "aabb") -> np.ndarray:
        """B_world as 8 corners per object, relative to origin: float64 [N, 8, 3] for 'aabb'
        (the paper's axis-aligned boxes); [2, N, 8, 3] for 'obb': the AABBs and the
        principal-axes boxes, whose projections parameterization intersects (both enclose
        the object, so the intersection does too, and it is never larger than the AABB's)."""
        bounds = member(Bounds, kind)
        if bounds is None:
            raise ValueError(f"unknown bounds '{kind}' (choose from {', '.join(BOUNDS)})")
        if Bounds.AABB not in self._corners:  # stored planar [3, 8, N]: parameterize projects rows
            lo = (self.aabb_min - self.origin).T[:, None, :]
            hi = (self.aabb_max - self.origin).T[:, None, :]
            planar = np.where(_BITS.T[:, :, None], hi, lo)
            planar.flags.writeable = False  # fixed, so parameterize checks their alignment once
            self._corners[Bounds.AABB] = planar.transpose(2, 1, 0)
        if bounds is Bounds.OBB and Bounds.OBB not in self._corners:
            obb = oriented_corners(self.positions, self.object_ids, self.count)
            planar = np.stack([self._corners[Bounds.AABB].transpose(2, 1, 0), obb.transpose(2, 1, 0)])
            self._corners[Bounds.OBB] = planar.transpose(0, 3, 2, 1)
        return self._corners[bounds]

    @property
    def closed(self) -> np.ndarray:
        """bool [N]: the objects that are closed surfaces facing outward (scene.closure), whose
        back faces the scene passes cull; computed once, on first use."""
        if "closed" not in self._corners:
            centers = (self.aabb_min + self.aabb_max) / 2 - self.origin
            self._corners["closed"] = closed_objects(self.positions, self.indices, self.index_ranges, centers)
            keep = self._corners.get("keep_closed")  # kept beside the scene's cache entry (rtta.scene.cache)
            if keep is not None:
                keep(self._corners["closed"])
        return self._corners["closed"]

    def index_runs(self, mask: np.ndarray) -> np.ndarray:
        """[(first index, index count)] of the runs of consecutive objects in `mask` (bool [N]):
        objects lie in the index buffer in id order, so k left out make at most k + 1 runs."""
        keep = np.flatnonzero(np.asarray(mask, bool) & (self.index_ranges[:, 1] > 0))
        if not len(keep):
            return np.zeros((0, 2), np.int64)
        first, count = self.index_ranges[keep, 0], self.index_ranges[keep, 1]
        begin = np.flatnonzero(np.r_[True, first[1:] != first[:-1] + count[:-1]])  # not continuing a run
        end = np.r_[begin[1:], len(keep)] - 1
        return np.stack([first[begin], first[end] + count[end] - first[begin]], axis=1)

    def index(self, name: str) -> int:
        return self.names.index(name)

    def path_of(self, oid: int) -> tuple[str, ...]:
        """The object's groups in the file's tree, root first (empty for a flat file)."""
        return tuple(self.paths[oid]) if self.paths is not None else ()

    @property
    def groups(self) -> dict[str, list[int]]:
        """Every group of the tree as 'a/b/c' -> the ids of all objects below it, in tree order."""
        key = ("groups", id(self.paths))
        if key not in self._corners:
            out: dict[str, list[int]] = {}
            for oid in range(self.count):
                path = self.path_of(oid)
                for k in range(1, len(path) + 1):
                    out.setdefault("/".join(path[:k]), []).append(oid)
            self._corners[key] = out
        return self._corners[key]


def unique_names(raw: list[str]) -> list[str]:
    """Names as given, with `_2`, `_3`, ... appended to repeats (instances, duplicates)."""
    seen: dict[str, int] = {}
    out = []
    taken = set(raw)
    for name in raw:
        name = name or "object"
        if name not in seen:
            seen[name] = 1
            out.append(name)
            continue
        k = seen[name]
        while True:
            k += 1
            candidate = f"{name}_{k}"
            if candidate not in taken:
                break
        seen[name] = k
        taken.add(candidate)
        out.append(candidate)
    return out


PALETTE = np.array(
    [
        [0.80, 0.36, 0.30],
        [0.30, 0.56, 0.80],
        [0.45, 0.72, 0.38],
        [0.86, 0.70, 0.30],
        [0.62, 0.45, 0.78],
        [0.35, 0.75, 0.72],
        [0.85, 0.50, 0.65],
        [0.60, 0.60, 0.62],
    ],
    dtype=np.float32,
)


def from_meshes(
    parts: list[tuple[str, np.ndarray, np.ndarray, np.ndarray | None]],
    colors: list | None = None,
    source: str = "<memory>",
    *,
    uvs: list[np.ndarray | None] | None = None,
    texture_ids: list[int] | None = None,
    textures: list[np.ndarray] | None = None,
) -> Scene:
    """Batch meshes of your own into a `Scene`, one object per part.

    Parameters
    ----------
    parts : list of tuple
        (name, vertices float64 [V, 3] in world units, faces int [F, 3], normals [V, 3] or None).
    colors : list, optional
        An RGBA colour per part (default: a palette).
    source : str, default "<memory>"
        The name errors and warnings give.
    uvs, texture_ids, textures : list, optional
        Texture coordinates per part, an index into `textures` per part (-1: none), RGBA images.

    Returns
    -------
    Scene
    """
    parts = checked_parts(parts, source)
    colors = checked_colors(colors, len(parts), source)
    textured = bool(textures) and uvs is not None and texture_ids is not None
    batch = Batch(
        vertices=np.concatenate([p[1] for p in parts]),
        faces=np.concatenate([p[2] for p in parts]),
        vcount=np.array([len(p[1]) for p in parts], np.int64),
        fcount=np.array([len(p[2]) for p in parts], np.int64),
        normals=np.concatenate(
            [_vertex_normals(v, f) if n is None else np.asarray(n, np.float32) for _, v, f, n in parts]
        ),
        uvs=np.concatenate(
            [
                np.zeros((len(p[1]), 2), np.float32) if uv is None else np.asarray(uv, np.float32)
                for p, uv in zip(parts, uvs, strict=True)
            ]
        )
        if textured and uvs is not None  # (textured says so too)
        else None,
    )
    return from_batch(
        [p[0] for p in parts],
        batch,
        colors,
        source,
        texture_ids=texture_ids if textured else None,
        textures=textures if textured else None,
    )


@dataclass
class Batch:
    """Objects concatenated: world vertices float64 [V, 3], faces [F, 3] indexing into
    their own object's vertices, per object vertex and face counts, normals float32 [V, 3],
    uvs float32 [V, 2] or None (rtta.scene.batch.Meshes has these fields too)."""

    vertices: np.ndarray
    faces: np.ndarray
    vcount: np.ndarray
    fcount: np.ndarray
    normals: np.ndarray
    uvs: np.ndarray | None = None


def from_batch(
    names: list[str],
    batch,
    colors: list | None = None,
    source: str = "<memory>",
    *,
    texture_ids: list[int] | None = None,
    textures: list[np.ndarray] | None = None,
    consume: bool = False,
) -> Scene:
    """The Scene of objects given as one batch (a Batch, or anything with its fields), in
    whole-array passes: no loop per object. `consume`: the batch is not used afterwards, so
    int32 faces become the indices in place (a copy fewer at the load's peak)."""
    n = len(names)
    if n == 0:
        raise RttaError("scene has no objects with geometry", source)
    vcount = np.asarray(batch.vcount, np.int64)
    fcount = np.asarray(batch.fcount, np.int64)
    vstart = np.concatenate([[0], np.cumsum(vcount)[:-1]])
    fstart = np.concatenate([[0], np.cumsum(fcount)[:-1]])
    v = np.asarray(batch.vertices, np.float64)
    lo = np.minimum.reduceat(v, vstart, axis=0)
    hi = np.maximum.reduceat(v, vstart, axis=0)
    origin = (lo.min(axis=0) + hi.max(axis=0)) / 2.0
    faces = np.asarray(batch.faces)
    reuse = consume and faces.dtype == np.int32 and faces.flags.c_contiguous and (len(faces) == 0 or faces.min() >= 0)
    indices = (faces.view(np.uint32) if reuse else faces.astype(np.uint32)).reshape(-1, 3)
    indices += np.repeat(vstart.astype(np.uint32), fcount)[:, None]
    positions = np.empty(v.shape, np.float32)
    for a in range(0, len(v), 1 << 18):  # no float64 copy of every vertex
        positions[a : a + (1 << 18)] = v[a : a + (1 << 18)] - origin
    cols = np.empty((n, 4), np.float32)
    cols[:] = np.hstack([PALETTE[np.arange(n) % len(PALETTE)], np.ones((n, 1), np.float32)])
    for i, c in enumerate(colors or []):
        if c is not None:
            cols[i] = c
    raw = list(names)
    names = unique_names(raw)
    renamed = [f"{printable(a)} -> {printable(b)}" for a, b in zip(raw, names, strict=True) if a and a != b]
    scene = Scene(
        names=names,
        positions=positions,
        normals=np.asarray(batch.normals, np.float32),
        object_ids=np.repeat(np.arange(n, dtype=np.uint32), vcount),
        indices=indices.reshape(-1),
        index_ranges=np.stack([3 * fstart, 3 * fcount], axis=1).astype(np.int64),
        colors=cols,
        aabb_min=lo,
        aabb_max=hi,
        origin=origin,
        source=source,
        warnings=_collapsed(names, lo, hi, origin),
    )
    if renamed:
        scene.warnings.insert(
            0,
            f"{len(renamed)} object name(s) repeated, numbered in file order to keep names "
            "unique: " + ", ".join(renamed[:5]) + (" ..." if len(renamed) > 5 else ""),
        )
    if textures and batch.uvs is not None and texture_ids is not None and any(t >= 0 for t in texture_ids):
        scene.textures = list(textures)
        scene.texture_ids = np.asarray(texture_ids, np.int32)
        scene.uvs = np.asarray(batch.uvs, np.float32)
    return scene


def _collapsed(names: list[str], lo: np.ndarray, hi: np.ndarray, origin: np.ndarray) -> list[str]:
    """A warning for objects smaller than a few float32 steps at their distance from the
    scene origin: their GPU positions collapse, so they draw as specks or not at all."""
    far = np.maximum(np.abs(lo - origin), np.abs(hi - origin)).max(axis=1)
    step = np.spacing(far.astype(np.float32)).astype(np.float64)
    small = np.flatnonzero((hi - lo).max(axis=1) < 16 * step)
    notes = []
    if small.size:
        listed = ", ".join(printable(names[i]) for i in small[:5]) + (" ..." if small.size > 5 else "")
        notes.append(
            f"{small.size} object(s) smaller than 16 float32 steps at their distance from the scene "
            f"centre draw collapsed: {listed}"
        )
    extent = float(np.linalg.norm(hi.max(axis=0) - lo.min(axis=0)))
    if extent < TINY_SCENE:
        notes.append(
            f"the scene is only {extent:.3g} units across: below {TINY_SCENE:g} units GPUs lose it in "
            "clipping or float32 underflow, so views may be blank; scale the model up"
        )
    elif extent < 100 * float(np.spacing(np.abs(origin).max())):
        notes.append(
            f"the scene is only {extent:.3g} units across at {np.abs(origin).max():.3g} units from the "
            "world origin: cameras cannot be placed that finely there, so views may be blank or "
            "off-centre; move the model nearer the origin"
        )
    return notes


def _vertex_normals(v: np.ndarray, f: np.ndarray) -> np.ndarray:
    """Area-weighted vertex normals (for parts that come without any)."""
    v = np.asarray(v, np.float64)
    f = np.asarray(f, np.int64)
    fn = np.cross(v[f[:, 1]] - v[f[:, 0]], v[f[:, 2]] - v[f[:, 0]])
    out = np.zeros_like(v)
    for k in range(3):
        np.add.at(out, f[:, k], fn)
    length = np.linalg.norm(out, axis=1, keepdims=True)
    return (out / np.where(length > 0, length, 1.0)).astype(np.float32)


def oriented_corners(positions: np.ndarray, object_ids: np.ndarray, n: int) -> np.ndarray:
    """Principal-axes bounding box of each object's vertices (which lie contiguously, in
    object order), as 8 corners in the BOX_EDGES order: float64 [n, 8, 3]."""
    p = positions.astype(np.float64)
    counts = np.bincount(object_ids, minlength=n)
    starts = np.concatenate([[0], np.cumsum(counts)[:-1]])
    mean = np.add.reduceat(p, starts, axis=0) / counts[:, None]
    q = p - mean[object_ids]
    i, j = [0, 0, 0, 1, 1, 2], [0, 1, 2, 1, 2, 2]
    m = np.add.reduceat(q[:, i] * q[:, j], starts, axis=0)
    cov = m[:, [0, 1, 2, 1, 3, 4, 2, 4, 5]].reshape(n, 3, 3)
    axes = np.linalg.eigh(cov)[1]  # columns: principal axes
    local = np.einsum("vi,vij->vj", q, axes[object_ids])
    lo = np.minimum.reduceat(local, starts, axis=0)
    hi = np.maximum.reduceat(local, starts, axis=0)
    pad = 1e-9 * np.maximum(np.abs(hi - lo).max(axis=1, keepdims=True), 1e-30)
    box = np.where(_BITS[None], (hi + pad)[:, None], (lo - pad)[:, None])  # [n, 8, 3] local
    return mean[:, None, :] + np.einsum("nkj,nij->nki", box, axes)
