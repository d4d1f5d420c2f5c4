"""Fast navigation: while the camera moves, the parts smallest on screen are left out of the
capture so that a frame keeps to a time budget; the first frame after the camera stops
captures every part again, so a view at rest is always exact.

This is the "guaranteed frame rate" of large-model viewers (Navisworks drops the smallest
objects while navigating and fills them in when the view rests). On a CPU renderer the
capture of a large assembly is bound by its triangles (docs/performance/scale.md), and a frame
costs about what it draws: leaving out the smallest 20% of a 10,000-part assembly's parts
made a viewer frame 18% faster. Parts are ranked by the area of their B_viewport in the
frame's own projection (atlas.parameterize's `thin`, before packing); the focus is never left out.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

MIN_OBJECTS = 500  # smaller scenes are never thinned: their frames are bound by pixels, not parts
FULL = 0.98  # a share kept at or above this leaves nothing out
# Frame times scatter from frame to frame (±8-15% on llvmpipe), and a budget steered to sit
# at its target in the mean of log(ms) gives a mean frame time above it: fewer frames per
# second than asked (9.5-9.9 instead of 10 in a simulation of the 10,000-part assembly's
# frames). It aims a little under the target instead; RESPONSE < 1 damps one noisy frame.
AIM = 0.95
RESPONSE = 0.75


@dataclass
class FrameBudget:
    """The share of the visible triangles drawn while the camera moves, steered towards
    `target_ms` a frame: after each such frame, `keep` moves by (AIM * target / measured) **
    RESPONSE (at most 0.6x to 1.3x a frame, so one slow frame does not empty the view), never
    below `min_keep` and never above 1."""

    target_ms: float = 100.0
    keep: float = 1.0
    min_keep: float = 0.1

    def update(self, frame_ms: float) -> None:
        if not (math.isfinite(frame_ms) and frame_ms > 0 and math.isfinite(self.target_ms) and self.target_ms > 0):
            return
        step = min(1.3, max(0.6, (AIM * self.target_ms / frame_ms) ** RESPONSE))
        self.keep = float(min(1.0, max(self.min_keep, self.keep * step)))


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
