"""Atlas regions mapped back to the viewport through T^-1 (nearest texel), in numpy.

Used by export, tests and benchmarks to compare the atlas with STD and RTT renders.
"""

from __future__ import annotations

import numpy as np

from ..atlas.parameterize import Records

EMPTY = {"color": 0, "normal": 0.0, "id": -1, "depth": 1.0}


def to_atlas(records: Records, oid: int, x, y) -> tuple[np.ndarray, np.ndarray]:
    """The transform T: atlas texel column/row (nearest) of viewport pixels x, y of one object."""
    x0, y0 = records.viewport_rect[oid, :2]
    ax, ay = records.atlas_rect[oid, :2] + records.border
    s = records.scale[oid]
    tx = np.floor(ax + s * (np.asarray(x) + 0.5 - x0)).astype(np.int64)
    ty = np.floor(ay + s * (np.asarray(y) + 0.5 - y0)).astype(np.int64)
    return tx, ty


def region_texels(records: Records, oid: int) -> tuple[np.ndarray, np.ndarray]:
    """Atlas texel column/row for every viewport pixel of the object's inner B_viewport."""
    x0, y0, x1, y1 = records.viewport_rect[oid]
    return to_atlas(records, oid, np.arange(x0, x1), np.arange(y0, y1))


def map_back(atlas: dict[str, np.ndarray], records: Records, oid: int) -> dict[str, np.ndarray]:
    """One object's atlas images as full-viewport arrays [H, W(, C)]; empty outside its region."""
    W, H = records.viewport
    out = {k: np.full((H, W, *v.shape[3:]), EMPTY[k], v.dtype) for k, v in atlas.items()}
    if not records.visible[oid]:
        return out
    x0, y0, x1, y1 = records.viewport_rect[oid]
    tx, ty = region_texels(records, oid)
    layer = records.layer[oid]
    for k, v in atlas.items():
        out[k][y0:y1, x0:x1] = v[layer][ty[:, None], tx[None, :]]
    return out


def front_most(atlas: dict[str, np.ndarray], records: Records) -> dict[str, np.ndarray]:
    """Per viewport pixel, the nearest of all objects' mapped-back depths and its id."""
    W, H = records.viewport
    depth = np.ones((H, W), np.float32)
    ids = np.full((H, W), -1, np.int32)
    for oid in np.flatnonzero(records.visible):
        m = map_back({"depth": atlas["depth"], "id": atlas["id"]}, records, int(oid))
        closer = (m["id"] >= 0) & (m["depth"] < depth)
        depth[closer] = m["depth"][closer]
        ids[closer] = m["id"][closer]
    return {"depth": depth, "id": ids}
