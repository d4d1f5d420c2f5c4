"""The mesh formats (glTF/GLB/OBJ/STL/PLY/3MF/OFF), read by rtta's own readers or
through trimesh, gathered into one batch: every scene-graph node with triangle geometry is
one object (instances are separate objects). Expected failures raise RttaError naming the
file and the problem.
"""

from __future__ import annotations

import gc
import io
from dataclasses import replace
from pathlib import Path

import numpy as np

from ...errors import RttaError
from .. import batch
from ..files import PARTS_HINT, SafeResolver, max_objects
from ..model import Scene, from_batch
from ..precheck import BYTES_PER_TRIANGLE, BYTES_PER_VERTEX, check_size, memory_limit, precheck
from ..textures import TextureTable
from . import graph_paths, hidden, obj_read
from .gltf import prepare
from .gltf_read import Decoded
from .obj import material_colors, obj_objects, object_number
from .trimesh_io import base_color, trimesh_load

F32_MAX = float(np.finfo(np.float32).max)
MAX_COORDINATE = 1e15  # float64 keeps ~0.1 units of precision there; float32 offsets stay finite
BEYOND = f"coordinates up to {{:.3g}}, beyond the ±{MAX_COORDINATE:.0e} this program handles"


def load(path: Path, smooth_angle: float, smooth: bool) -> Scene:
    """The Scene of a mesh file: normals smoothed by `smooth_angle` degrees where the file
    has none, or everywhere with `smooth` (then the file's normals are dropped)."""
    notes, inputs, read = _read(path, path.suffix.lower(), smooth)
    placed, names, colors, texture_ids, textures, dropped, paths = _parts(read, path, smooth_angle)
    notes += read[0].textures.notes
    if dropped:
        notes.append(
            f"{len(dropped)} object(s) with only degenerate (zero-area) triangles left out: "
            + ", ".join(dropped[:5])
            + (" ..." if len(dropped) > 5 else "")
        )
    scene = from_batch(
        names, placed, colors, source=str(path), texture_ids=texture_ids, textures=textures, consume=True
    )
    del placed
    scene.paths = paths
    scene.warnings = notes + scene.warnings + _texture_notes(scene)
    scene.inputs = [str(p) for p in dict.fromkeys([path.resolve(), *inputs])]
    return scene


def _read(path: Path, suffix: str, smooth: bool) -> tuple[list[str], list[Path], tuple]:
    """(warnings, files read besides `path`, (gathered meshes, their concatenation, node
    names, node transforms, node paths or None)); trimesh's own objects are freed before
    this returns (their cycles collected), so they never sit in memory beside the batch."""
    notes, inputs, items = _items(path, suffix)
    textures, records = TextureTable(), _Records(smooth)
    items = [(name, records.of(mesh, textures), matrix, tree) for name, mesh, matrix, tree in items]
    items = [item for item in items if item[1] is not None and len(item[1].faces) > 0]
    for name, record, _, _ in items:
        _check_shapes(record, str(name), path)
    if not items:
        raise RttaError("scene has no objects with triangle geometry", path)
    names = [str(item[0]) for item in items]
    transforms = np.array([np.asarray(item[2], np.float64) for item in items]).reshape(-1, 4, 4)
    paths = [tuple(item[3]) for item in items]
    gathered = _Gathered(items, transforms, textures)
    trimeshes = records.trimesh
    del items, records  # the per-geometry arrays go as they are concatenated
    meshes = gathered.concatenated()
    if trimeshes:
        gc.collect()
    return notes, inputs, (gathered, meshes, names, transforms, paths if any(paths) else None)


def _check_shapes(record: Decoded, name: str, path: Path) -> None:
    """Vertices [n, 3] and triangles [m, 3]: a reader given a damaged file (an OBJ cut in the
    middle of a 'v' line) can hand back rows of another width."""
    v, f = record.vertices, record.faces
    if v.ndim != 2 or v.shape[1] != 3:
        width = v.shape[1] if v.ndim == 2 else 1
        raise RttaError(
            f"object '{name}' has vertices of {width} coordinate(s) instead of 3 (is the file truncated or damaged?)",
            path,
        )
    if f.ndim != 2 or f.shape[1] != 3:
        raise RttaError(
            f"object '{name}' has faces that are not triangles of 3 vertex indices (is the file truncated or damaged?)",
            path,
        )


class _Records:
    """Every geometry as a Decoded record, whichever reader gave it, made once per geometry
    (its instances share the record): glTF's direct reader gives them (their file normals
    dropped when `smooth`); a trimesh mesh is converted with its file normals (none when
    `smooth`), uvs and texture, and base colour (one list per material); anything without
    triangles (paths, point clouds) is None."""

    def __init__(self, smooth: bool) -> None:
        self.smooth = smooth
        self.trimesh = False  # a trimesh mesh was converted: its cycles want collecting
        self._made: dict[int, Decoded | None] = {}
        self._color_of: dict = {}

    def of(self, mesh, textures: TextureTable) -> Decoded | None:
        if mesh is None:
            return None
        if id(mesh) not in self._made:
            self._made[id(mesh)] = self._record(mesh, textures)
        return self._made[id(mesh)]

    def _record(self, mesh, textures: TextureTable) -> Decoded | None:
        if isinstance(mesh, Decoded):  # read directly: trimesh need not even be imported
            usable = mesh.normals is not None and not self.smooth and _usable_normals(mesh.normals)
            return mesh if mesh.normals is None or usable else replace(mesh, normals=None)
        import trimesh

        self.trimesh = True
        if not isinstance(mesh, trimesh.Trimesh) or len(mesh.faces) == 0:
            return None
        uv, texture = textures.of(mesh)
        material = getattr(mesh.visual, "material", None)
        key = (
            id(material)
            if material is not None and getattr(mesh.visual, "kind", None) not in ("face", "vertex")
            else None
        )
        color = self._color_of[key] if key in self._color_of else base_color(mesh)
        if key is not None:
            self._color_of[key] = color
        faces = np.asarray(mesh.faces).astype(np.int32, copy=False)  # an index past 2^31 wraps negative: out of range
        return Decoded(
            np.asarray(mesh.vertices, np.float64),
            faces,
            None if self.smooth else _file_normals(mesh),
            color,
            uv,
            texture,
        )


def _items(path: Path, suffix: str) -> tuple[list[str], list[Path], list[tuple]]:
    """(warnings, files read besides `path`, [(name, trimesh geometry, 4x4 world transform,
    path in the file's tree)]) in file order. glTF's graph is walked by rtta.scene.readers.gltf; the
    other formats' by trimesh."""
    if suffix in (".gltf", ".glb"):
        prepared = prepare(path)
        geometry = prepared.decoded()
        if geometry is None:
            geometry = trimesh_load(io.BytesIO(prepared.for_trimesh()), "glb", path, None).geometry
        items = [(i.name, geometry.get(i.geometry), i.matrix, i.path) for i in prepared.instances]
        return prepared.warnings, prepared.inputs, items
    notes = precheck(path)
    resolver = SafeResolver(path)
    source, names = path, None
    if suffix == ".obj":
        data, names = obj_objects(path)
        limit = max_objects(path)
        if len(names) > limit:
            raise RttaError(
                f"OBJ file has {len(names):,} objects ('o' statements, or 'g' groups where there are "
                f"fewer than two; at most {limit:,} for a file of its size; {PARTS_HINT})",
                path,
            )
        decoded = obj_read.decode(data, names)
        materials = SafeResolver(path)  # the skeleton's reads: kept only when its colours are
        if decoded is not None and obj_read.has_materials(data):
            decoded = material_colors(decoded, data, path, materials)
        if decoded is not None:  # a plain file: its geometry without trimesh (whose split is quadratic)
            return (
                notes + materials.warnings,
                materials.inputs,
                [(names[k], geometry, np.eye(4), ()) for k, geometry in decoded],
            )
        source = io.BytesIO(data)
    loaded = trimesh_load(source, suffix[1:], path, resolver)
    items = []
    order = {name: i for i, name in enumerate(loaded.geometry)}
    nodes = list(loaded.graph.nodes_geometry)
    trees = graph_paths(loaded, nodes) or [()] * len(nodes)
    for node, tree in zip(nodes, trees, strict=True):
        transform, geom_name = loaded.graph[node]
        name, key = str(node), order.get(geom_name, len(order))
        k = object_number(name) if names is not None else None
        if names is not None and k is not None and k < len(names):
            name, key = names[k], k
        items.append((key, name, loaded.geometry.get(geom_name), np.asarray(transform, np.float64), tree))
    items.sort(key=lambda item: item[0])  # file order
    flat = hidden.singular(np.array([item[3] for item in items]).reshape(-1, 4, 4))  # a zero scale hides (3MF)
    gone = list(dict.fromkeys(item[1] for item, f in zip(items, flat, strict=True) if f))
    hidden.note_hidden(gone, int((~flat).sum()), path, resolver.warnings)
    return notes + resolver.warnings, resolver.inputs, [item[1:] for item, f in zip(items, flat, strict=True) if not f]


def _texture_notes(scene: Scene) -> list[str]:
    """A warning when textures are too large for the material atlas and get halved."""
    if not scene.textured or scene.texture_ids is None:
        return []
    from ..material_atlas import oversized_note

    users: list[list[str]] = [[] for _ in scene.textures]
    for name, tid in zip(scene.names, scene.texture_ids, strict=True):
        if tid >= 0:
            users[tid].append(name)
    note = oversized_note(scene.textures, users)
    return [note] if note else []


def _parts(read: tuple, path: Path, smooth_angle: float) -> tuple:
    """The scene's objects as one batch (batch.Meshes in world coordinates, one mesh per
    kept node), their names, colours and texture ids, the texture images, and the names of
    objects left out because every triangle is degenerate. Each distinct mesh is read and
    preprocessed once for all its instances, in whole-scene passes (batch.py)."""
    gathered, meshes, names, transforms, paths = read
    mesh_of = np.asarray(gathered.mesh_of, np.int64)
    _check(meshes, mesh_of, transforms, names, path)
    meshes = batch.preprocess(meshes, np.asarray(gathered.smoothed, bool), smooth_angle)
    area = batch.has_area(meshes)[mesh_of]
    placing = np.where(gathered.baked[:, None, None], np.eye(4), transforms)
    flat = np.flatnonzero(~area)
    if len(flat):  # an object spread beyond the range is flat relative to its size: say the range
        _check_world(batch.instance(meshes, mesh_of[flat], placing[flat]), [names[i] for i in flat], path)
    if not area.any():
        raise RttaError("every triangle of the scene is degenerate (zero area)", path)
    keep = np.flatnonzero(area)
    placed = batch.instance(meshes, mesh_of[keep], placing[keep], consume=True)
    del meshes
    with np.errstate(all="ignore"):
        mirrored = ~gathered.baked[keep] & (np.linalg.det(transforms[keep, :3, :3]) < 0)
    if mirrored.any():  # instances under a mirror: turn the winding back (see _Gathered)
        rows = np.repeat(mirrored, placed.fcount)
        placed.faces[rows] = placed.faces[rows][:, ::-1]
    kept = [names[i] for i in keep]
    _check_world(placed, kept, path)
    colors = [gathered.colors[mesh_of[i]] for i in keep]
    texture_ids = [gathered.texture_ids[mesh_of[i]] for i in keep]
    kept_paths = None if paths is None else [paths[i] for i in keep]
    return (
        placed,
        kept,
        colors,
        texture_ids,
        gathered.textures.images,
        [names[i] for i in np.flatnonzero(~area)],
        kept_paths,
    )


class _Gathered:
    """The distinct meshes of the nodes (Decoded records), read once each: vertices, faces,
    file normals (or smoothing), uvs, texture, colour. A node whose mesh must be smoothed in
    world space (a shear, a mirror or a non-uniform scale, and no file normals) or whose
    transform is singular gets a copy of the mesh in world coordinates of its own (`baked`)."""

    def __init__(self, items: list[tuple], transforms: np.ndarray, textures: TextureTable) -> None:
        self.textures = textures
        self.colors: list = []
        self.texture_ids: list[int] = []
        self.smoothed: list[bool] = []
        self.mesh_of: list[int] = []
        self._arrays: list[tuple] = []
        with np.errstate(all="ignore"):
            det = np.linalg.det(transforms[:, :3, :3])
        usable = np.isfinite(transforms[:, :3, :]).all(axis=(1, 2)) & np.isfinite(det) & (det != 0)
        similar = batch.similar(transforms) & usable
        self.baked = np.zeros(len(items), bool)
        seen: dict = {}
        for i, (_, mesh, _, _) in enumerate(items):  # the items hold every mesh, so ids stay unique
            bake = usable[i] and mesh.normals is None and not similar[i]
            key = (id(mesh), i) if bake else id(mesh)
            if key not in seen:
                seen[key] = len(self._arrays)
                self._add(mesh, transforms[i] if bake else None)
            self.baked[i] = bake
            self.mesh_of.append(seen[key])

    def _add(self, mesh: Decoded, transform) -> None:
        v, f = mesh.vertices, mesh.faces
        if transform is not None:
            v = v @ transform[:3, :3].T + transform[:3, 3]
            if np.linalg.det(transform[:3, :3]) < 0:
                f = f[:, ::-1]  # a mirroring transform turns the winding: keep faces front-facing
        self._arrays.append((v, f, mesh.normals, mesh.uv))
        self.smoothed.append(mesh.normals is None)
        self.texture_ids.append(mesh.texture)
        self.colors.append(mesh.color)

    def concatenated(self) -> batch.Meshes:
        """The meshes as one batch.Meshes (zero normals where smoothed, zero uvs where none)."""
        arrays, self._arrays = self._arrays, []
        vcount = np.array([len(a[0]) for a in arrays], np.int64)
        normals = [np.zeros((len(a[0]), 3), np.float32) if a[2] is None else a[2] for a in arrays]
        textured = any(a[3] is not None for a in arrays)
        uvs = [np.zeros((len(a[0]), 2), np.float32) if a[3] is None else a[3] for a in arrays] if textured else None
        return batch.Meshes(
            np.concatenate([a[0] for a in arrays]),
            np.concatenate([a[1] for a in arrays]),
            vcount,
            np.array([len(a[1]) for a in arrays], np.int64),
            np.concatenate(normals),
            None if uvs is None else np.concatenate(uvs),
        )


def _check(meshes: batch.Meshes, mesh_of: np.ndarray, transforms: np.ndarray, names: list[str], path: Path) -> None:
    """The first node (in graph order) with non-finite vertices, face indices out of range
    or a non-finite transform raises; then the memory limit, counted as the nodes add up."""
    # |v| within float32's range (not NaN or infinite either): preprocessing works in float32
    finite = np.logical_and.reduceat(batch.rows_within(meshes.vertices, F32_MAX), meshes.vstart)
    low = np.minimum.reduceat(meshes.faces.min(axis=1), meshes.fstart)
    high = np.maximum.reduceat(meshes.faces.max(axis=1), meshes.fstart)
    in_range = (low >= 0) & (high < meshes.vcount)
    transform_ok = np.isfinite(transforms[:, :3, :]).all(axis=(1, 2))
    bad = ~finite[mesh_of] | ~in_range[mesh_of] | ~transform_ok
    if bad.any():
        i = int(np.flatnonzero(bad)[0])
        if not finite[mesh_of[i]]:
            v = meshes.vertices[meshes.vstart[mesh_of[i]] :][: meshes.vcount[mesh_of[i]]]
            raise RttaError(
                f"object '{names[i]}' has NaN or infinite vertex coordinates"
                if not np.isfinite(v).all()
                else f"object '{names[i]}' has " + BEYOND.format(np.abs(v).max()),
                path,
            )
        if not in_range[mesh_of[i]]:
            raise RttaError(f"object '{names[i]}' has face indices out of range", path)
        raise RttaError(f"object '{names[i]}' has a transform that makes coordinates non-finite", path)
    vertices = np.cumsum(meshes.vcount[mesh_of])
    triangles = np.cumsum(meshes.fcount[mesh_of])
    need = vertices * BYTES_PER_VERTEX + triangles * BYTES_PER_TRIANGLE
    over = np.flatnonzero(need > memory_limit())
    i = int(over[0]) if len(over) else len(names) - 1
    check_size(int(vertices[i]), int(triangles[i]), path)


def _check_world(placed: batch.Meshes, names: list[str], path: Path) -> None:
    """World coordinates are finite and within ±MAX_COORDINATE (first offending object)."""
    bad = ~batch.rows_within(placed.vertices, MAX_COORDINATE)
    if not bad.any():
        return
    i = int(np.searchsorted(placed.vstart, np.flatnonzero(bad)[0], side="right") - 1)
    peak = np.abs(placed.vertices[placed.vstart[i] : placed.vstart[i] + placed.vcount[i]]).max()
    if not np.isfinite(peak):
        raise RttaError(f"object '{names[i]}' has a transform that makes coordinates non-finite", path)
    raise RttaError(f"object '{names[i]}' has " + BEYOND.format(peak), path)


def _file_normals(mesh) -> np.ndarray | None:
    """The file's vertex normals (float32), or None when it has none or they are unusable."""
    if not _file_has_normals(mesh):
        return None
    try:
        n = np.asarray(mesh.vertex_normals, np.float64)
    except Exception:
        return None
    if n.shape != mesh.vertices.shape or not _usable_normals(n):
        return None
    return n.astype(np.float32)


def _usable_normals(n: np.ndarray) -> bool:
    """Finite, and none of zero length (which no renormalising can make a direction: the
    shaders' normalize() would give NaN); else the normals are made as for a file without."""
    return bool(np.isfinite(n).all() and (np.abs(n).max(axis=1, initial=0.0) > 0).all())


def _file_has_normals(mesh) -> bool:
    """Whether the file gave vertex normals (trimesh computes them lazily otherwise)."""
    cache = getattr(getattr(mesh, "_cache", None), "cache", None)
    return cache is None or "vertex_normals" in cache
