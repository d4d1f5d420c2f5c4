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

from ..atlas.thinning import FULL, MIN_OBJECTS, KeepShare, left_out

__all__ = ["AIM", "FULL", "MIN_OBJECTS", "RESPONSE", "FrameBudget", "KeepShare", "left_out"]

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
