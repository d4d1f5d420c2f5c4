"""Image comparisons shared by the reliability runs and the tests: silhouette masks and the
depth tolerance of the core's sprites/atlas-vs-STD equalities."""

from __future__ import annotations

import numpy as np

DEPTH_TOL = 1e-5
SNAP_PX = 2.0 / 256.0  # two steps of the rasterizer's sub-pixel grid (8 bits on llvmpipe)
CREASE = 2e-4  # window depth is affine over a planar triangle: larger 2nd differences are contours


def near_edges(ids: np.ndarray) -> np.ndarray:
    """Pixels within one pixel (8-neighbourhood) of a change of id: silhouettes."""
    pad = np.pad(ids, 1, mode="edge")
    h, w = ids.shape
    edge = np.zeros(ids.shape, bool)
    for dy in (-1, 0, 1):
        for dx in (-1, 0, 1):
            edge |= pad[1 + dy : 1 + dy + h, 1 + dx : 1 + dx + w] != ids
    return edge


def near_silhouettes(ids: np.ndarray, *depths: np.ndarray) -> np.ndarray:
    """Pixels within one pixel of an id change or of a depth crease/discontinuity in any image."""
    crease = np.zeros(ids.shape, bool)
    for d in depths:
        d = d.astype(np.float64)
        pad = np.pad(d, 1, mode="edge")
        second_x = np.abs(pad[1:-1, 2:] + pad[1:-1, :-2] - 2 * d)
        second_y = np.abs(pad[2:, 1:-1] + pad[:-2, 1:-1] - 2 * d)
        crease |= (second_x > CREASE) | (second_y > CREASE)
    return near_edges(ids) | near_edges(crease.astype(np.int8))


def depth_tolerance(*depths: np.ndarray) -> np.ndarray:
    """1e-5, plus the local depth slope (the larger of the images') times two sub-pixel steps:
    on grazing triangles and self-occlusion edges a displaced vertex may snap to the
    neighbouring sub-pixel position (float32 rounding of T)."""
    slope = np.zeros(depths[0].shape)
    for depth in depths:
        d = depth.astype(np.float64)
        for axis in (0, 1):
            if d.shape[axis] >= 2:
                slope = np.maximum(slope, np.abs(np.gradient(d, axis=axis)))
    return DEPTH_TOL + np.minimum(slope, 1.0) * SNAP_PX


def depth_mismatch(depth: np.ndarray, reference: np.ndarray, where: np.ndarray, ids: np.ndarray) -> tuple[int, int]:
    """(pixels over tolerance off depth creases, pixels over tolerance on creases) within
    `where`. The core allows none of the first and at most crease_limit() of the second."""
    over = ((np.abs(depth - reference) - depth_tolerance(reference, depth)) > 0) & where
    if not over.any():
        return 0, 0
    creases = near_silhouettes(ids, reference, depth)
    return int((over & ~creases).sum()), int((over & creases).sum())


def crease_limit(where: np.ndarray) -> int:
    """Crease pixels allowed to differ: 0.1% of the compared pixels, at least 2."""
    return max(2, int(0.001 * where.sum()))
