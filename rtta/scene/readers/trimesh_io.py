"""trimesh as rtta's loaders call it: a scene read with rtta's resolver (its errors one
RttaError line), and a mesh's base colour from its material or visual."""

from __future__ import annotations

import logging
from pathlib import Path
from typing import TYPE_CHECKING

import numpy as np

from ...errors import RttaError, reason

if TYPE_CHECKING:
    import trimesh


def trimesh_load(source, file_type: str, path: Path, resolver) -> trimesh.Scene:
    """trimesh's scene of `source` (OBJ: one geometry per object, materials not merged)."""
    import trimesh

    logging.getLogger("trimesh").setLevel(logging.ERROR)
    try:
        options = {"split_objects": True, "group_material": False} if file_type == "obj" else {}
        loaded = trimesh.load(source, file_type=file_type, force="scene", process=False, resolver=resolver, **options)
    except Exception as exc:  # trimesh raises many types for corrupt files (MemoryError, RecursionError too)
        raise RttaError(f"cannot read {path.suffix[1:].upper()} file ({reason(exc)})", path) from None
    return as_scene(loaded, path)


def as_scene(loaded, path: Path) -> trimesh.Scene:
    """`loaded` as the trimesh.Scene that ``force="scene"`` makes.

    Parameters
    ----------
    loaded : object
        What ``trimesh.load(..., force="scene")`` returned.
    path : Path
        The file read, for the message.

    Returns
    -------
    trimesh.Scene
        `loaded` itself; an RttaError if it is not a scene.
    """
    import trimesh

    if not isinstance(loaded, trimesh.Scene):
        raise RttaError(f"cannot read {path.suffix[1:].upper()} file (trimesh made no scene of it)", path)
    return loaded


def base_color(mesh) -> list[float] | None:
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
