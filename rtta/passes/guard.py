"""The region guard: the capture at an extreme zoom keeps every region whole.

An object that meets the viewport's edge is clipped to its region by four planes
(records.glsl, `region_clip_distances`). Zoomed in far enough, its triangles reach clip
coordinates of a million viewport NDC units or more (an orthographic view of a part 1e-5
scene radii high), and float32 clipping against those planes misses them by a few pixels:
the capture lost the top rows of such regions (2.5 rows at 1920x1080, 1e-5 radii; nothing
at 1e-4). Where the scene can reach that far (`clip_reach`, in pixels), the planes stand `region_guard`
NDC further out, a few hundred times the error, and the fragment shader keeps the region's
own texels alone (`region_holds`: the planes' test made exactly, per fragment). Frames that
are not zoomed in so far draw as before, without the discard.
"""

from __future__ import annotations

import math

import numpy as np

from ..scene.camera import near_distance

GUARD_AT = 2.0**23  # reach in pixels (NDC reach x viewport side): float32's error nears a quarter pixel
GUARD_SHARE = 2.0**-19  # the guard per unit of reach, ~200x the error measured (module docstring)
MAX_GUARD = 2.0**40  # (an infinite reach: the planes as far as float32 keeps them apart)


def clip_reach(view: np.ndarray, proj: np.ndarray, center, radius: float) -> tuple[float, float]:
    """The largest |x / w| and |y / w| (viewport NDC) that a sphere reaches in front of the
    near plane: how far beyond the viewport a scene of that bounding sphere can be drawn.

    Parameters
    ----------
    view, proj : numpy.ndarray
        The 4x4 view and projection matrices (the sphere's centre in the view's frame).
    center : array_like
        The sphere's centre [3].
    radius : float
        Its radius.

    Examples
    --------
    >>> import numpy as np
    >>> ortho = np.diag([1e5, 2e5, -1.0, 1.0])
    >>> clip_reach(np.eye(4), ortho, [0.0, 0.0, -1.0], 1.0)
    (100000.0, 200000.0)
    """
    return _reach(view, proj, np.append(np.asarray(center, np.float64), 1.0), float(radius))


def _reach(view: np.ndarray, proj: np.ndarray, center4: np.ndarray, radius: float) -> tuple[float, float]:
    """clip_reach with the centre homogeneous (a frame's few calls: once per capture)."""
    x, y, z, _ = (view @ center4).tolist()
    p = proj.tolist()
    lateral = math.hypot(x, y) + radius
    if not (p[3][2] == 0.0 and p[3][3] == 1.0):  # perspective (camera.is_ortho): over the closest depth
        closest = max(-z - radius, near_distance(proj))
        lateral = lateral / closest if closest > 0 else math.inf
    return lateral * abs(p[0][0]), lateral * abs(p[1][1])


def region_guard(reach: tuple[float, float], viewport: tuple[int, int]) -> float:
    """How far (viewport NDC) the region planes stand out for a scene of `reach` (clip_reach,
    x and y) drawn at `viewport` (W, H); 0.0: at the regions themselves, no guard needed."""
    pixels = max(reach[0] * viewport[0], reach[1] * viewport[1])  # (NaN: no guard)
    if not pixels > GUARD_AT:
        return 0.0
    return min(max(reach) * GUARD_SHARE, MAX_GUARD)


class RegionGuard:
    """A capture pass's guard for each frame (`of`), the scene's bounding sphere (its parts'
    offsets included: an exploded view) worked out once per scene and placement."""

    def __init__(self) -> None:
        self._sphere: tuple[object, object, np.ndarray, float] | None = None

    def of(self, gpu, view: np.ndarray, proj: np.ndarray, viewport: tuple[int, int]) -> float:
        """region_guard for drawing `gpu`'s scene (a GpuScene) with `view` and `proj`."""
        scene, placement = gpu.scene, gpu.placement
        serial = None if placement is None else placement.serial
        if self._sphere is None or self._sphere[0] is not scene or self._sphere[1] != serial:
            spread = 0.0
            if placement is not None and placement.offsets is not None and len(placement.offsets):
                spread = float(np.sqrt((np.asarray(placement.offsets, np.float64) ** 2).sum(axis=1).max()))
            center4 = np.append(scene.center - scene.origin, 1.0)
            self._sphere = (scene, serial, center4, float(scene.radius) + spread)
        _, _, center4, radius = self._sphere
        return region_guard(_reach(view, proj, center4, radius), viewport)
