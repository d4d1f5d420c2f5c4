"""Load glTF/GLB/OBJ/STL/PLY/3MF/OFF through trimesh into a batched Scene.

Every scene-graph node with triangle geometry is one object (instances are separate
objects). Expected failures raise RttaError naming the file and the problem.
"""

from __future__ import annotations

import io
import logging
import re
import warnings
from pathlib import Path

import numpy as np

from ..errors import RttaError
from . import formats
from .files import MAX_FILE_BYTES, MAX_OBJECTS, SafeResolver, regular_file
from .gltf import prepare
from .model import SUPPORTED, Scene, from_meshes
from .precheck import check_size, precheck
from .preprocess import DEFAULT_SMOOTH_ANGLE, preprocess_objects
from .textures import TextureTable

MAX_COORDINATE = 1e15    # float64 keeps ~0.1 units of precision there; float32 offsets stay finite


def load_scene(path: str | Path, smooth_angle: float = DEFAULT_SMOOTH_ANGLE, smooth: bool = False) -> Scene:
    """Read a scene file; see the module docstring for the rules. Vertices are indexed;
    normals are smoothed by `smooth_angle` degrees where the file has none, or everywhere
    with `smooth`."""
    path = Path(path)
    size = regular_file(path, "scene file")
    suffix = path.suffix.lower()
    if suffix not in SUPPORTED + formats.SUFFIXES:
        raise RttaError(f"unsupported file type '{suffix[:16] or '(none)'}'; "
                        f"supported: {', '.join(SUPPORTED + formats.SUFFIXES)}", path)
    if size == 0:
        raise RttaError("file is empty", path)
    if size > MAX_FILE_BYTES:
        raise RttaError(f"file is larger than the {MAX_FILE_BYTES >> 30} GiB limit", path)
    with warnings.catch_warnings(), np.errstate(all="ignore"):
        warnings.simplefilter("ignore")
        if suffix in formats.SUFFIXES:
            scene = formats.load(path, 180.0 if smooth else smooth_angle)
            scene.inputs = [str(path.resolve())]
            return scene
        notes, inputs, items = _read(path, suffix)
        parts, colors, dropped, materials = _parts(items, path, smooth_angle, smooth)
        notes += materials.pop("notes")
        paths = materials.pop("paths")
    if dropped:
        notes.append(f"{len(dropped)} object(s) with only degenerate (zero-area) triangles left out: "
                     + ", ".join(dropped[:5]) + (" ..." if len(dropped) > 5 else ""))
    scene = from_meshes(parts, colors, source=str(path), **materials)
    scene.paths = paths if any(paths) else None
    scene.warnings = notes + scene.warnings + _texture_notes(scene)
    scene.inputs = [str(p) for p in dict.fromkeys([path.resolve(), *inputs])]
    return scene


def _read(path: Path, suffix: str) -> tuple[list[str], list[Path], list[tuple]]:
    """(warnings, files read besides `path`, [(name, trimesh geometry, 4x4 world transform,
    path in the file's tree)]) in file order. glTF's graph is walked by rtta.scene.gltf; the
    other formats' by trimesh."""
    if suffix in (".gltf", ".glb"):
        prepared = prepare(path)
        loaded = _trimesh_load(io.BytesIO(prepared.data), "glb", path, None)
        items = [(i.name, loaded.geometry.get(i.geometry), i.matrix, i.path) for i in prepared.instances]
        return prepared.warnings, prepared.inputs, items
    notes = precheck(path)
    resolver = SafeResolver(path)
    source, names = path, None
    if suffix == ".obj":
        data, names = obj_objects(path)
        if len(names) > MAX_OBJECTS:
            raise RttaError(f"OBJ file has {len(names):,} objects ('o' statements; at most {MAX_OBJECTS:,})", path)
        source = io.BytesIO(data)
    loaded = _trimesh_load(source, suffix[1:], path, resolver)
    items = []
    order = {name: i for i, name in enumerate(loaded.geometry)}
    nodes = list(loaded.graph.nodes_geometry)
    trees = formats.graph_paths(loaded, nodes) or [()] * len(nodes)
    for node, tree in zip(nodes, trees, strict=True):
        transform, geom_name = loaded.graph[node]
        name, key = str(node), order.get(geom_name, len(order))
        if names is not None and re.fullmatch(r"rtta\.o\.\d+", name) and int(name[7:]) < len(names):
            name, key = names[int(name[7:])], int(name[7:])
        items.append((key, name, loaded.geometry.get(geom_name), np.asarray(transform, np.float64), tree))
    items.sort(key=lambda item: item[0])                  # file order
    return notes + resolver.warnings, resolver.inputs, [item[1:] for item in items]


def obj_objects(path: Path) -> tuple[bytes, list[str]]:
    """The OBJ's bytes with each `o NAME` line made `o rtta.o.K` (trimesh merges objects of the
    same name, and an unnamed one into its neighbour), and the names in file order, decoded
    as UTF-8 or else Windows-1252."""
    data = path.read_bytes()
    names: list[str] = []

    def rename(match: re.Match) -> bytes:
        raw = (match.group(2) or b"").strip()
        try:
            names.append(raw.decode("utf-8"))
        except UnicodeDecodeError:
            names.append(raw.decode("cp1252", errors="replace"))
        return match.group(1) + f"o rtta.o.{len(names) - 1}".encode()

    return re.sub(rb"(^|\n)[ \t]*o(?:[ \t]+([^\r\n]*)|(?=[\r\n]|$))", rename, data), names


def _texture_notes(scene: Scene) -> list[str]:
    """A warning when textures are too large for the material atlas and get halved."""
    if not scene.textured:
        return []
    from .material_atlas import oversized_note

    users: list[list[str]] = [[] for _ in scene.textures]
    for name, tid in zip(scene.names, scene.texture_ids, strict=True):
        if tid >= 0:
            users[tid].append(name)
    note = oversized_note(scene.textures, users)
    return [note] if note else []


def _trimesh_load(source, file_type: str, path: Path, resolver):
    import trimesh

    logging.getLogger("trimesh").setLevel(logging.ERROR)
    try:
        options = {"split_objects": True, "group_material": False} if file_type == "obj" else {}
        return trimesh.load(source, file_type=file_type, force="scene", process=False, resolver=resolver, **options)
    except (MemoryError, RecursionError) as exc:
        raise RttaError(f"cannot read {path.suffix[1:].upper()} file ({type(exc).__name__})", path) from None
    except Exception as exc:  # trimesh raises many types for corrupt files
        reason = str(exc).strip().splitlines()[0] if str(exc).strip() else type(exc).__name__
        raise RttaError(f"cannot read {path.suffix[1:].upper()} file ({reason[:160]})", path) from None


def _parts(items: list[tuple], path: Path, smooth_angle: float, smooth: bool) -> tuple[list, list, list, dict]:
    """(name, world vertices, faces, normals) per object, their colours, the names of
    objects left out because every triangle is degenerate, and the from_meshes texture
    arguments (uvs, texture_ids, textures). What depends on the geometry alone is done once
    per geometry, and preprocessing once for all objects (rtta.scene.preprocess)."""
    textures = TextureTable()
    geometry: dict[int, tuple | None] = {}
    names, raw, colors, texture_ids, trees = [], [], [], [], []
    vertices = triangles = 0
    for node, mesh, transform, tree in items:
        if id(mesh) not in geometry:
            geometry[id(mesh)] = _geometry(mesh, node, path, textures, smooth)
        geo = geometry[id(mesh)]
        if geo is None:
            continue
        v, f, n, uv, texture, color = geo
        m = np.asarray(transform, np.float64)
        world = v @ m[:3, :3].T + m[:3, 3] if np.isfinite(m).all() else np.full(1, np.nan)
        if not np.isfinite(world).all():
            raise RttaError(f"object '{node}' has a transform that makes coordinates non-finite", path)
        if np.abs(world).max() > MAX_COORDINATE:
            raise RttaError(f"object '{node}' has coordinates up to {np.abs(world).max():.3g}, beyond "
                            f"the ±{MAX_COORDINATE:.0e} this program handles", path)
        if np.linalg.det(m[:3, :3]) < 0:
            f = f[:, ::-1]                   # a mirroring transform turns the winding: keep faces front-facing
        vertices, triangles = vertices + len(v), triangles + len(f)
        check_size(vertices, triangles, path)
        names.append(str(node))
        raw.append((world, f, None if n is None else _transform_normals(n, m), uv))
        colors.append(color)
        texture_ids.append(texture)
        trees.append(tuple(tree))
    area = _has_area(raw)
    dropped = [name for name, ok in zip(names, area, strict=True) if not ok]
    keep = np.flatnonzero(area)
    if not keep.size and dropped:
        raise RttaError("every triangle of the scene is degenerate (zero area)", path)
    if not keep.size:
        raise RttaError("scene has no objects with triangle geometry", path)
    done = preprocess_objects([raw[i] for i in keep], smooth_angle, smooth)
    parts = [(names[i], *d[:3]) for i, d in zip(keep, done, strict=True)]
    return parts, [colors[i] for i in keep], dropped, {
        "uvs": [d[3] for d in done], "texture_ids": [texture_ids[i] for i in keep], "textures": textures.images,
        "notes": textures.notes, "paths": [trees[i] for i in keep]}


def _geometry(mesh, node, path: Path, textures: TextureTable, smooth: bool) -> tuple | None:
    """(vertices, faces, file normals or None, uv, texture, colour) of a trimesh geometry,
    checked; None for what is not a triangle mesh."""
    import trimesh

    if not isinstance(mesh, trimesh.Trimesh) or len(mesh.faces) == 0:
        return None
    v = np.asarray(mesh.vertices, np.float64)
    if not np.isfinite(v).all():
        raise RttaError(f"object '{node}' has NaN or infinite vertex coordinates", path)
    f = np.asarray(mesh.faces, np.int64)
    if f.min() < 0 or f.max() >= len(v):
        raise RttaError(f"object '{node}' has face indices out of range", path)
    n = None if smooth or not _file_has_normals(mesh) else _file_normals(mesh)
    uv, texture = textures.of(mesh)
    return v, f, n, uv, texture, _color(mesh)


def _transform_normals(n: np.ndarray, m: np.ndarray) -> np.ndarray | None:
    """Normals by the inverse transpose of the transform, unit length; None if it is singular."""
    try:
        normal_matrix = np.linalg.inv(m[:3, :3]).T
    except np.linalg.LinAlgError:
        return None
    out = n @ normal_matrix.T
    length = np.linalg.norm(out, axis=1, keepdims=True)
    return (out / np.where(length > 0, length, 1.0)).astype(np.float32)


def _has_area(parts: list[tuple]) -> np.ndarray:
    """Per object: whether any triangle has a non-zero area (relative to its size); all
    objects at once."""
    if not parts:
        return np.zeros(0, bool)
    v = np.concatenate([p[0] for p in parts])
    starts = np.cumsum([0] + [len(p[0]) for p in parts[:-1]])
    f = np.concatenate([p[1] + s for p, s in zip(parts, starts, strict=True)])
    fstarts = np.cumsum([0] + [len(p[1]) for p in parts[:-1]])
    cross = np.linalg.norm(np.cross(v[f[:, 1]] - v[f[:, 0]], v[f[:, 2]] - v[f[:, 0]]), axis=1)
    largest = np.maximum.reduceat(cross, fstarts)
    extent = (np.maximum.reduceat(v, starts) - np.minimum.reduceat(v, starts)).max(axis=1)
    return (extent > 0) & (largest > (extent * 1e-12) ** 2)


def _file_has_normals(mesh) -> bool:
    """Whether the file gave vertex normals (trimesh computes them lazily otherwise)."""
    cache = getattr(getattr(mesh, "_cache", None), "cache", None)
    return cache is None or "vertex_normals" in cache


def _file_normals(mesh) -> np.ndarray | None:
    """The file's vertex normals (float64), or None if unusable."""
    try:
        n = np.asarray(mesh.vertex_normals, np.float64)
    except Exception:
        return None
    return n if n.shape == mesh.vertices.shape and np.isfinite(n).all() else None


def _color(mesh) -> list[float] | None:
    """Base colour from the material or visual, RGBA in [0, 1]; None for the palette."""
    visual = mesh.visual
    material = getattr(visual, "material", None)
    factor = getattr(material, "baseColorFactor", None)
    if factor is not None:
        c = np.asarray(factor, np.float64).reshape(-1)
        return list((c / 255.0 if c.max() > 1 else c)[:4]) + [1.0] * (4 - min(4, c.size))
    main = getattr(material, "main_color", None)
    if main is None and getattr(visual, "kind", None) in ("face", "vertex"):
        main = getattr(visual, "main_color", None)
    if main is not None:
        c = np.asarray(main, np.float64).reshape(-1)[:4] / 255.0
        return list(c) + [1.0] * (4 - c.size)
    return None


def load_scene_or_demo(path: str | None, **options) -> Scene:
    """The scene at `path`, or the built-in demo assembly when no path is given."""
    from .demo import demo_path

    return load_scene(path or str(demo_path()), **options)
