"""Fast navigation's thinning (rtta.renderer.navigation): which parts a frame drawn while the
camera moves leaves out, on the CPU (`left_out`, called by atlas.parameterize) or on the GPU
(`KeepShare`, read by rtta.passes.atlas_gpu: parameterize.comp's stages 7 and 8)."""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

FULL = 0.98  # a share kept at or above this leaves nothing out
MIN_OBJECTS = 500  # smaller scenes are never thinned: their frames are bound by pixels, not parts


@dataclass(eq=False)
class KeepShare:
    """Keep the visible parts largest on screen until they hold `keep` of the visible
    triangles; leave out the rest. A `Thinning` (called with the frame's visibility and
    B_viewport, as atlas.parameterize calls it) that the GPU path also reads as it is: there
    the parts are ranked by classes of a quarter octave of area (parameterize.comp), here one
    by one.

    Parameters
    ----------
    keep : float
        The share of the visible triangles kept, in (0, 1].
    triangles : numpy.ndarray
        Triangles per object [n].
    protect : numpy.ndarray, optional
        bool [n]: never left out (the focus); they count towards the share.
    key : hashable, optional
        Equal keys promise equal `triangles` and `protect` (the GPU uploads them once).

    Attributes
    ----------
    left : int
        Parts the last call left out (the CPU path; the GPU's count is read a frame late).
    """

    keep: float
    triangles: np.ndarray
    protect: np.ndarray | None = None
    key: object = None
    left: int = field(default=0, init=False)

    def __call__(self, visible: np.ndarray, viewport_rect: np.ndarray) -> np.ndarray | None:
        out = left_out(visible, viewport_rect, self.triangles, self.keep, self.protect)
        self.left = 0 if out is None else int(out.sum())
        return out

    def weights(self) -> np.ndarray:
        """uint32 [n]: triangles (at most 2^31 - 1), the top bit set where protected."""
        w = np.minimum(np.asarray(self.triangles, np.int64), 2**31 - 1).astype(np.uint32)
        if self.protect is not None:
            w[np.asarray(self.protect, bool)] |= np.uint32(2**31)
        return w


def left_out(
    visible: np.ndarray,
    viewport_rect: np.ndarray,
    triangles: np.ndarray,
    keep: float,
    protect: np.ndarray | None = None,
) -> np.ndarray | None:
    """bool [n]: the objects to leave out of a frame drawn while moving, or None for none.
    Of the `visible` objects (bool [n], after culling, as atlas.parameterize's `thin` gets
    them, with their inner B_viewport [n, 4] in pixels), the largest on screen are kept until
    they hold `keep` of the visible triangles (`triangles` [n] per object); the rest, the
    smallest, are left out. `protect` [n] bool (the focus) are always kept and count towards
    the share. Objects not visible (culled, hidden) are never left out: they cost nothing
    while outside the view. Ranked on the frame's own projection, the same parts are left out
    frame after frame while the view changes little (ranked on the last frame's records, the
    parts left out had no B_viewport there: they came back on every other frame)."""
    n = len(visible)
    if keep >= FULL or n < MIN_OBJECTS:
        return None
    visible = np.asarray(visible, bool)
    r = np.asarray(viewport_rect, np.float64)
    area = np.where(visible, (r[:, 2] - r[:, 0]) * (r[:, 3] - r[:, 1]), -1.0)
    if protect is not None:
        area[np.asarray(protect, bool) & visible] = np.inf
    order = np.argsort(-area, kind="stable")
    tri = np.where(visible, np.asarray(triangles, np.float64), 0.0)[order]
    budget = max(0.0, keep) * tri.sum()
    kept = np.cumsum(tri) - tri <= budget  # every object that starts within the budget
    kept |= area[order] == np.inf
    out = np.zeros(n, bool)
    out[order[~kept]] = True
    out &= visible
    return out if out.any() else None
