"""What `from_meshes` is given, checked before it is batched: a caller's mistake (a flat
vertex list, a face past its part's vertices, an RGB colour or 0-255 values, NaN) is one
`RttaError` naming the part, not a numpy broadcast error or a picture with holes."""

from __future__ import annotations

import numpy as np

from ..errors import RttaError, printable


def checked_parts(parts, source: str) -> list[tuple[str, np.ndarray, np.ndarray, np.ndarray | None]]:
    """Each part as (name, vertices float64 [V, 3], faces int64 [F, 3], normals float32 [V, 3] or None)."""
    if not parts:
        raise RttaError("scene has no objects with geometry", source)
    out = []
    for i, part in enumerate(parts):
        if not isinstance(part, (tuple, list)) or len(part) != 4:
            raise RttaError(f"part {i}: expected (name, vertices, faces, normals or None)", source)
        name, v, f, n = part
        what = f"part {i} ({printable(str(name))})"
        v = _array(v, np.float64, what, "vertices", source)
        f = _array(f, np.int64, what, "faces", source)
        if not np.isfinite(v).all():
            raise RttaError(f"{what}: vertices are not all finite numbers", source)
        if len(f) and (f.min() < 0 or f.max() >= len(v)):
            raise RttaError(f"{what}: a face indexes a vertex the part does not have ({len(v)} vertices)", source)
        if n is not None:
            n = _array(n, np.float32, what, "normals", source)
            if len(n) != len(v):
                raise RttaError(f"{what}: {len(n)} normals for {len(v)} vertices", source)
        out.append((name, v, f, n))
    return out


def _array(a, dtype, what: str, field: str, source: str) -> np.ndarray:
    try:
        arr = np.asarray(a, dtype)
    except (TypeError, ValueError, OverflowError):
        raise RttaError(f"{what}: {field} are not numbers", source) from None
    if arr.ndim == 1 and arr.size % 3 == 0:  # flat [x0, y0, z0, x1, ...], as before
        arr = arr.reshape(-1, 3)
    if arr.ndim != 2 or arr.shape[1] != 3:
        raise RttaError(f"{what}: {field} must have shape [N, 3], got {list(arr.shape)}", source)
    return arr


def checked_colors(colors, n: int, source: str) -> list[np.ndarray | None] | None:
    """Colours as RGBA float in [0, 1]: RGB gets alpha 1; None keeps the palette's."""
    if colors is None:
        return None
    colors = list(colors)
    if len(colors) > n:
        raise RttaError(f"{len(colors)} colours for {n} parts", source)
    out: list[np.ndarray | None] = []
    for i, c in enumerate(colors):
        if c is None:
            out.append(None)
            continue
        try:
            rgba = np.asarray(c, np.float64).reshape(-1)
        except (TypeError, ValueError):
            raise RttaError(f"colour of part {i} is not a list of numbers", source) from None
        if len(rgba) == 3:
            rgba = np.append(rgba, 1.0)
        if len(rgba) != 4 or not np.isfinite(rgba).all() or rgba.min() < 0 or rgba.max() > 1:
            raise RttaError(f"colour of part {i} must be RGB or RGBA with values in [0, 1], got {list(rgba)}", source)
        out.append(rgba.astype(np.float32))
    return out
