"""Fast navigation: while the camera moves, the parts smallest on screen are left out of the
capture so that a frame keeps to a time budget; the first frame after the camera stops
captures every part again, so a view at rest is always exact.

This is the "guaranteed frame rate" of large-model viewers (Navisworks drops the smallest
objects while navigating and fills them in when the view rests). On a CPU renderer the
capture of a large assembly is bound by its triangles (BENCHMARKS.md, issue 22), and a frame
costs about what it draws: leaving out the smallest 20% of a 10,000-part assembly's parts
made a viewer frame 18% faster. Parts are ranked by the area of their B_viewport in the last
records (the camera moves little between two frames); the focus is never left out.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from ..atlas.parameterize import Records

MIN_OBJECTS = 500          # smaller scenes are never thinned: their frames are bound by pixels, not parts
FULL = 0.98                # a share kept at or above this leaves nothing out


@dataclass
class FrameBudget:
    """The share of the visible triangles drawn while the camera moves, steered towards
    `target_ms` a frame: after each such frame, `keep` moves by the square root of target over
    measured time (at most 0.6x to 1.3x a frame, so one slow frame does not empty the view),
    never below `min_keep` and never above 1."""

    target_ms: float = 100.0
    keep: float = 1.0
    min_keep: float = 0.1

    def update(self, frame_ms: float) -> None:
        if not (math.isfinite(frame_ms) and frame_ms > 0 and math.isfinite(self.target_ms) and self.target_ms > 0):
            return
        step = min(1.3, max(0.6, math.sqrt(self.target_ms / frame_ms)))
        self.keep = float(min(1.0, max(self.min_keep, self.keep * step)))


def left_out(records: Records, triangles: np.ndarray, keep: float, protect: np.ndarray | None = None
             ) -> np.ndarray | None:
    """bool [n]: the objects to leave out of a frame drawn while moving, or None for none.
    Of the objects visible in `records` (the last capture), the largest on screen are kept
    until they hold `keep` of the visible triangles (`triangles` [n] per object); the rest,
    the smallest, are left out. `protect` [n] bool (the focus) are always kept and count
    towards the share. Objects not visible in `records` (culled, hidden) are never left out:
    they cost nothing while outside the view."""
    n = len(records.visible)
    if keep >= FULL or n < MIN_OBJECTS:
        return None
    visible = np.asarray(records.visible, bool)
    r = records.viewport_rect.astype(np.float64)
    area = np.where(visible, (r[:, 2] - r[:, 0]) * (r[:, 3] - r[:, 1]), -1.0)
    if protect is not None:
        area[np.asarray(protect, bool) & visible] = np.inf
    order = np.argsort(-area, kind="stable")
    tri = np.where(visible, np.asarray(triangles, np.float64), 0.0)[order]
    budget = max(0.0, keep) * tri.sum()
    kept = np.cumsum(tri) - tri <= budget          # every object that starts within the budget
    kept |= area[order] == np.inf
    out = np.zeros(n, bool)
    out[order[~kept]] = True
    out &= visible
    return out if out.any() else None
