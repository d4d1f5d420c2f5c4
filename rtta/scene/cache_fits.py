"""Whether a scene cache entry's arrays and metadata make a whole Scene (rtta.scene.cache):
an entry whose CRC-32 is whole may still deceive (written by another program, or damaged and
its checksum made again), and a Scene handed back must never be damaged: no index past the
vertices, no object id past the objects, no NaN where the renderer computes."""

from __future__ import annotations

import numpy as np

DTYPES = {  # the Scene's arrays (and texture_0, texture_1 ... uint8): nothing else is read
    "positions": "float32",
    "normals": "float32",
    "object_ids": "uint32",
    "indices": "uint32",
    "index_ranges": "int64",
    "colors": "float32",
    "aabb_min": "float64",
    "aabb_max": "float64",
    "origin": "float64",
    "uvs": "float32",
    "texture_ids": "int32",
}
ARRAYS = tuple(DTYPES)[:9]  # those every scene has


def fits(a: dict, meta: dict, textures: list) -> bool:
    """Whether an entry's arrays and metadata make a whole scene: the shapes of its counts,
    indices below the vertex count, object ids below the object count, index ranges within
    the indices, texture ids of its textures or -1, finite numbers (colours in [0, 1], boxes
    not inside out), lists of strings where a scene has them."""
    names, paths, warnings = meta["names"], meta["paths"], meta["warnings"]
    if any(name not in a for name in ARRAYS) or set(a) - set(DTYPES) or not isinstance(names, list):
        return False
    n, v = len(names), len(a["positions"])
    shapes = {"positions": (v, 3), "normals": (v, 3), "object_ids": (v,), "index_ranges": (n, 2), "colors": (n, 4)}
    shapes.update(aabb_min=(n, 3), aabb_max=(n, 3), origin=(3,), uvs=(v, 2), texture_ids=(n,))
    if any(name in a and a[name].shape != shape for name, shape in shapes.items()):
        return False
    indices, ranges, ids = a["indices"], a["index_ranges"], a.get("texture_ids")
    return not (
        n == 0
        or indices.ndim != 1
        or len(indices) % 3
        or not isinstance(warnings, list)
        or not all(isinstance(s, str) for s in [*names, *warnings, meta["unit"]])
        or meta["up_axis"] not in ("y", "z")
        or (paths is not None and not paths_fit(paths, n))
        or (len(indices) and int(indices.max()) >= v)
        or (v and int(a["object_ids"].max()) >= n)
        or ranges.min() < 0
        or (ranges[:, 0] > len(indices)).any()
        or (ranges[:, 1] > len(indices) - ranges[:, 0]).any()  # first + count could overflow int64
        or any(t.ndim != 3 or t.shape[2] != 4 or not t.size for t in textures)
        or (ids is not None and (int(ids.min()) < -1 or int(ids.max()) >= len(textures)))
        or not all(
            _finite(a[name]) for name in ("positions", "normals", "aabb_min", "aabb_max", "origin", "uvs") if name in a
        )
        or not (a["colors"].min() >= 0 and a["colors"].max() <= 1)
        or not (a["aabb_min"] <= a["aabb_max"]).all()
    )


def paths_fit(paths, n: int) -> bool:
    return (
        isinstance(paths, list)
        and len(paths) == n
        and all(isinstance(p, list) and all(isinstance(s, str) for s in p) for p in paths)
    )


def _finite(x: np.ndarray) -> bool:
    """No NaN or infinity in `x` (its minimum and maximum: two passes, no [V, 3] mask)."""
    return not x.size or bool(np.isfinite(x.min()) and np.isfinite(x.max()))
