"""Load a scene file into a batched Scene: the file checked (a regular file, a known suffix,
not empty, within the size limit), then read by its format's reader in the one table of
rtta.scene.readers. Expected failures raise RttaError naming the file and the problem.
"""

from __future__ import annotations

import gc
import time
import warnings
from pathlib import Path

import numpy as np

from ..errors import RttaError
from . import cache as scene_cache
from . import readers
from .files import MAX_FILE_BYTES, regular_file
from .model import Scene
from .preprocess import DEFAULT_SMOOTH_ANGLE


def load_scene(
    path: str | Path, smooth_angle: float = DEFAULT_SMOOTH_ANGLE, smooth: bool = False, *, cache: bool = True
) -> Scene:
    """Read a scene file.

    Parameters
    ----------
    path : str or Path
        The file; see the module docstring for the rules.
    smooth_angle : float
        Normals are smoothed across edges below this angle (degrees) where the file has none.
    smooth : bool
        Recompute normals by `smooth_angle` even where the file has its own.
    cache : bool
        Use the scene cache on disk (rtta.scene.cache): a file loaded before with the same
        options, unchanged since, is read back from it; a file read is stored there.

    Returns
    -------
    Scene
        The batched scene; vertices are indexed.
    """
    path = Path(path)
    options = {"smooth_angle": float(smooth_angle), "smooth": bool(smooth)}
    started = time.time_ns()
    enabled = gc.isenabled()
    gc.disable()  # the document's 10^5-10^6 objects would be traversed again and again by
    try:  # automatic collections while the load allocates; trimesh's cycles are
        scene = scene_cache.load(path, options) if cache else None  # collected explicitly (mesh._read)
        if scene is not None:
            readers.reader_of(path)  # its format's library still installed: the answer a read would give
        else:
            scene = _load(path, smooth_angle, smooth)
            if cache:
                scene_cache.store(path, options, scene, started)
        return scene
    finally:
        if enabled:
            gc.enable()


def _load(path: Path, smooth_angle: float, smooth: bool) -> Scene:
    size = regular_file(path, "scene file")
    suffix = path.suffix.lower()
    if suffix not in readers.SUFFIXES:
        raise RttaError(
            f"unsupported file type '{suffix[:16] or '(none)'}'; supported: {', '.join(readers.SUFFIXES)}", path
        )
    if size == 0:
        raise RttaError("file is empty", path)
    if size > MAX_FILE_BYTES:
        raise RttaError(f"file is larger than the {MAX_FILE_BYTES >> 30} GiB limit", path)
    with warnings.catch_warnings(), np.errstate(all="ignore"):
        warnings.simplefilter("ignore")
        return readers.load(path, smooth_angle, smooth)


def load_scene_or_demo(path: str | None, **options) -> Scene:
    """The scene at `path`, or the built-in demo assembly when no path is given."""
    from .generators.demo import demo_path

    return load_scene(path or str(demo_path()), **options)
