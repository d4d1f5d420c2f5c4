"""Load glTF/GLB/OBJ/STL/PLY/3MF/OFF through trimesh into a batched Scene.

Every scene-graph node with triangle geometry is one object (instances are separate
objects). Expected failures raise RttaError naming the file and the problem.
"""

from __future__ import annotations

import gc
import warnings
from pathlib import Path

import numpy as np

from ..errors import RttaError
from . import readers
from .files import MAX_FILE_BYTES, regular_file
from .model import SUPPORTED, Scene, from_batch
from .preprocess import DEFAULT_SMOOTH_ANGLE
from .readers.mesh import _parts, _read, _texture_notes


def load_scene(path: str | Path, smooth_angle: float = DEFAULT_SMOOTH_ANGLE, smooth: bool = False) -> Scene:
    """Read a scene file; see the module docstring for the rules. Vertices are indexed;
    normals are smoothed by `smooth_angle` degrees where the file has none, or everywhere
    with `smooth`."""
    enabled = gc.isenabled()
    gc.disable()  # the document's 10^5-10^6 objects would be traversed again and again by
    try:  # automatic collections while the load allocates; trimesh's cycles are
        return _load(Path(path), smooth_angle, smooth)  # collected explicitly (_read)
    finally:
        if enabled:
            gc.enable()


def _load(path: Path, smooth_angle: float, smooth: bool) -> Scene:
    size = regular_file(path, "scene file")
    suffix = path.suffix.lower()
    if suffix not in SUPPORTED + readers.SUFFIXES:
        raise RttaError(
            f"unsupported file type '{suffix[:16] or '(none)'}'; supported: {', '.join(SUPPORTED + readers.SUFFIXES)}",
            path,
        )
    if size == 0:
        raise RttaError("file is empty", path)
    if size > MAX_FILE_BYTES:
        raise RttaError(f"file is larger than the {MAX_FILE_BYTES >> 30} GiB limit", path)
    with warnings.catch_warnings(), np.errstate(all="ignore"):
        warnings.simplefilter("ignore")
        if suffix in readers.SUFFIXES:
            scene = readers.load(path, 180.0 if smooth else smooth_angle)
            scene.inputs = [str(path.resolve())]
            return scene
        notes, inputs, read = _read(path, suffix, smooth)
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


def load_scene_or_demo(path: str | None, **options) -> Scene:
    """The scene at `path`, or the built-in demo assembly when no path is given."""
    from .generators.demo import demo_path

    return load_scene(path or str(demo_path()), **options)
