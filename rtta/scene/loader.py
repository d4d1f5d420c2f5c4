"""Load glTF/GLB/OBJ/STL/PLY/3MF/OFF through trimesh into a batched Scene.

Every scene-graph node with triangle geometry is one object (instances are separate
objects). Expected failures raise RttaError naming the file and the problem.
"""

from __future__ import annotations

import logging
import warnings
from pathlib import Path

import numpy as np

from ..errors import RttaError
from . import formats
from .model import SUPPORTED, Scene, from_meshes
from .precheck import check_size, precheck
from .preprocess import DEFAULT_SMOOTH_ANGLE, index_vertices, smooth_normals
from .textures import TextureTable

MAX_FILE_BYTES = 2 * 1024**3
MAX_COORDINATE = 1e15    # float64 keeps ~0.1 units of precision there; float32 offsets stay finite


def load_scene(path: str | Path, smooth_angle: float = DEFAULT_SMOOTH_ANGLE, smooth: bool = False) -> Scene:
    """Read a scene file; see the module docstring for the rules. Vertices are indexed;
    normals are smoothed by `smooth_angle` degrees where the file has none, or everywhere
    with `smooth`."""
    path = Path(path)
    if not path.exists():
        raise RttaError("no such file", path)
    if path.is_dir():
        raise RttaError("is a directory, expected a scene file", path)
    suffix = path.suffix.lower()
    if suffix not in SUPPORTED + formats.SUFFIXES:
        raise RttaError(f"unsupported file type '{suffix or '(none)'}'; "
                        f"supported: {', '.join(SUPPORTED + formats.SUFFIXES)}", path)
    size = path.stat().st_size
    if size == 0:
        raise RttaError("file is empty", path)
    if size > MAX_FILE_BYTES:
        raise RttaError(f"file is larger than the {MAX_FILE_BYTES >> 30} GiB limit", path)
    with warnings.catch_warnings(), np.errstate(all="ignore"):
        warnings.simplefilter("ignore")
        if suffix in formats.SUFFIXES:
            return formats.load(path, 180.0 if smooth else smooth_angle)
        notes = precheck(path)
        loaded = _trimesh_load(path, suffix)
        parts, colors, dropped, materials = _parts(loaded, path, smooth_angle, smooth)
    if dropped:
        notes.append(f"{len(dropped)} object(s) with only degenerate (zero-area) triangles left out: "
                     + ", ".join(dropped[:5]) + (" ..." if len(dropped) > 5 else ""))
    scene = from_meshes(parts, colors, source=str(path), **materials)
    scene.paths = formats.graph_paths(loaded, [p[0] for p in parts])
    scene.warnings = notes + scene.warnings + _texture_notes(scene)
    return scene


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


def _trimesh_load(path: Path, suffix: str):
    import trimesh

    logging.getLogger("trimesh").setLevel(logging.ERROR)
    try:
        options = {"split_objects": True, "group_material": False} if suffix == ".obj" else {}
        return trimesh.load(str(path), file_type=suffix[1:], force="scene", process=False, **options)
    except Exception as exc:  # trimesh raises many types for corrupt files
        reason = str(exc).strip().splitlines()[0] if str(exc).strip() else type(exc).__name__
        raise RttaError(f"cannot read {suffix[1:].upper()} file ({reason[:160]})", path) from None


def _parts(loaded, path: Path, smooth_angle: float, smooth: bool) -> tuple[list, list, list, dict]:
    """(name, world vertices, faces, normals) per object, their colours, the names of
    objects left out because every triangle is degenerate, and the from_meshes texture
    arguments (uvs, texture_ids, textures)."""
    import trimesh

    parts, colors, dropped = [], [], []
    textures = TextureTable()
    uvs, texture_ids = [], []
    vertices = triangles = 0
    graph = loaded.graph
    for node in graph.nodes_geometry:
        transform, geom_name = graph[node]
        mesh = loaded.geometry.get(geom_name)
        if not isinstance(mesh, trimesh.Trimesh) or len(mesh.faces) == 0:
            continue
        v = np.asarray(mesh.vertices, np.float64)
        if not np.isfinite(v).all():
            raise RttaError(f"object '{node}' has NaN or infinite vertex coordinates", path)
        f = np.asarray(mesh.faces, np.int64)
        if f.min() < 0 or f.max() >= len(v):
            raise RttaError(f"object '{node}' has face indices out of range", path)
        m = np.asarray(transform, np.float64)
        world = v @ m[:3, :3].T + m[:3, 3]
        normals = None if smooth or not _file_has_normals(mesh) else _world_normals(mesh, m)
        if not np.isfinite(world).all():
            raise RttaError(f"object '{node}' has a transform that makes coordinates non-finite", path)
        if np.abs(world).max() > MAX_COORDINATE:
            raise RttaError(f"object '{node}' has coordinates up to {np.abs(world).max():.3g}, beyond "
                            f"the ±{MAX_COORDINATE:.0e} this program handles", path)
        vertices, triangles = vertices + len(v), triangles + len(f)
        check_size(vertices, triangles, path)
        if not _has_area(world, f):
            dropped.append(str(node))
            continue
        uv, texture = textures.of(mesh)
        if normals is None:
            world, f, normals, uv = smooth_normals(world, f, uv, smooth_angle)
        else:
            world, f, normals, uv = index_vertices(world, f, normals, uv)
        parts.append((str(node), world, f, normals))
        colors.append(_color(mesh))
        uvs.append(uv)
        texture_ids.append(texture)
    if not parts and dropped:
        raise RttaError("every triangle of the scene is degenerate (zero area)", path)
    if not parts:
        raise RttaError("scene has no objects with triangle geometry", path)
    return parts, colors, dropped, {"uvs": uvs, "texture_ids": texture_ids, "textures": textures.images}


def _file_has_normals(mesh) -> bool:
    """Whether the file gave vertex normals (trimesh computes them lazily otherwise)."""
    cache = getattr(getattr(mesh, "_cache", None), "cache", None)
    return cache is None or "vertex_normals" in cache


def _has_area(v: np.ndarray, f: np.ndarray) -> bool:
    """Whether any triangle has a non-zero area (relative to the object's size)."""
    cross = np.cross(v[f[:, 1]] - v[f[:, 0]], v[f[:, 2]] - v[f[:, 0]])
    extent = float(np.ptp(v, axis=0).max()) if len(v) else 0.0
    return bool(extent > 0 and (np.linalg.norm(cross, axis=1) > (extent * 1e-12) ** 2).any())


def _world_normals(mesh, m: np.ndarray) -> np.ndarray | None:
    """File normals (or trimesh's computed ones) by the inverse transpose; None if unusable."""
    try:
        n = np.asarray(mesh.vertex_normals, np.float64)
    except Exception:
        return None
    if n.shape != mesh.vertices.shape or not np.isfinite(n).all():
        return None
    try:
        normal_matrix = np.linalg.inv(m[:3, :3]).T
    except np.linalg.LinAlgError:
        return None
    n = n @ normal_matrix.T
    length = np.linalg.norm(n, axis=1, keepdims=True)
    return (n / np.where(length > 0, length, 1.0)).astype(np.float32)


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
