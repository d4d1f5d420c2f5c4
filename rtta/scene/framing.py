"""Where the camera stands: standard views relative to the file's up axis, `--camera AZ,EL[,DIST]`,
and cameras fitted to the visible parts (both fields of view, a margin, perspective or ortho).

Directions are orbit angles (Camera.orbit): azimuth about the up axis from the front, elevation
from the ground plane, so 'front' looks from -Y in a Z-up (CAD, BIM) file and from +Z in a
Y-up (glTF) one, and 'top' looks down the file's up axis.
"""

from __future__ import annotations

from collections.abc import Iterable, Sequence
from dataclasses import dataclass
from typing import Literal, get_args

import numpy as np

from ..errors import RttaError
from .camera import DEFAULT_ORBIT, PROJECTIONS, Camera, Projection, fit_distance, parse_orbit
from .model import Scene

StandardView = Literal["front", "back", "left", "right", "top", "bottom", "iso"]
STANDARD_VIEWS: dict[str, tuple[float, float]] = {
    "front": (0.0, 0.0),
    "back": (180.0, 0.0),
    "left": (-90.0, 0.0),
    "right": (90.0, 0.0),
    "top": (0.0, 90.0),
    "bottom": (0.0, -90.0),
    "iso": (45.0, float(np.degrees(np.arctan(1.0 / np.sqrt(2.0))))),  # along a cube's diagonal
}
assert tuple(STANDARD_VIEWS) == get_args(StandardView)
FIT_MARGIN = 0.05  # of the width and the height, left free on each side of a fitted view


def parse_camera(text: str | Sequence[float], option: str = "--camera") -> tuple[float, float, float | None]:
    """'AZ,EL,DIST' or 'AZ,EL' (or 2 or 3 numbers) -> (az, el, dist or None: fit the distance)."""
    given = text if isinstance(text, str) else ",".join(str(v) for v in text)
    fields = given.split(",")
    if len(fields) == 2:
        try:
            az, el = (float(v) for v in fields)
        except ValueError:
            az = el = float("nan")
        if not (np.isfinite([az, el]).all() and max(abs(az), abs(el)) <= 1e6):
            raise RttaError(f"{option} '{given}': AZ and EL must be finite degrees (|value| up to 1e6)")
        return az, el, None
    try:
        return parse_orbit(given, option)
    except RttaError as exc:
        if len(fields) == 3:
            raise
        raise RttaError(f"{option} expects AZ,EL,DIST or AZ,EL (the distance fitted), got '{given}'") from exc


@dataclass(frozen=True)
class Orbit:
    """A camera as a saved view holds it: orbit angles (degrees) and distance (world units)
    about a world target, the vertical field of view and the projection. `camera` rebuilds
    the same Camera bit for bit (a saved view renders what its snapshot rendered)."""

    az: float
    el: float
    distance: float
    target: tuple[float, float, float]
    fov: float = 45.0
    projection: Projection = "perspective"

    def camera(self, scene: Scene, hidden: Iterable[int] = ()) -> Camera:
        """The Camera about `scene` (its up axis), its depth range fitted to the parts not hidden."""
        cam = Camera.orbit(
            np.asarray(self.target, np.float64),
            1.0,
            self.az,
            self.el,
            self.distance,
            fov_y=self.fov,
            up_axis=scene.up_axis,
            projection=self.projection,
        )
        return cam.fit_depth(*shown_sphere(scene, hidden))


def shown_sphere(scene: Scene, hidden: Iterable[int] = ()) -> tuple[np.ndarray, float]:
    """Centre and radius of the bounds of the parts not hidden (of all, when all are)."""
    lo, hi = _shown_bounds(scene, _shown(scene, hidden))
    return (lo + hi) / 2.0, max(float(np.linalg.norm(hi - lo)) / 2.0, scene.radius * 1e-6)


def scene_orbit(
    scene: Scene,
    camera: str | Sequence[float] | None = None,
    fov: float = 45.0,
    *,
    projection: Projection = "perspective",
    view: StandardView | None = None,
    aspect: float = 4 / 3,
    hidden: Iterable[int] = (),
) -> Orbit:
    """The orbit of `camera` (AZ,EL,DIST about the scene's centre, DIST in scene radii; AZ,EL;
    None: the default direction) or of a standard `view`; without a distance it frames the
    parts not `hidden` (fitted_orbit)."""
    if projection not in PROJECTIONS:
        raise RttaError(f"--projection must be one of {', '.join(PROJECTIONS)}, got '{projection}'")
    if view is not None and view not in STANDARD_VIEWS:
        raise RttaError(f"--view must be one of {', '.join(STANDARD_VIEWS)}, got '{view}'")
    az, el, dist = DEFAULT_ORBIT[0], DEFAULT_ORBIT[1], None
    if camera is not None:
        az, el, dist = parse_camera(camera)
    if view is not None:
        if camera is not None:
            raise RttaError(f"--view {view} and --camera both give the direction: use one of them")
        az, el = STANDARD_VIEWS[view]
    if dist is not None:
        target = tuple(float(v) for v in scene.center)
        return Orbit(az, el, dist * scene.radius, target, fov, projection)  # type: ignore[arg-type]
    return fitted_orbit(scene, az, el, fov, projection=projection, aspect=aspect, hidden=hidden)


def fitted_orbit(
    scene: Scene,
    az: float,
    el: float,
    fov: float = 45.0,
    *,
    projection: Projection = "perspective",
    aspect: float = 4 / 3,
    hidden: Iterable[int] = (),
    margin: float = FIT_MARGIN,
) -> Orbit:
    """An orbit from direction (az, el) about the bounds of the parts not `hidden` (all when
    every part is hidden) at the distance where their boxes fill the view but for `margin`
    on each side, in the vertical and the horizontal field of view."""
    shown = _shown(scene, hidden)
    lo, hi = _shown_bounds(scene, shown)
    target = (lo + hi) / 2.0
    corners = scene.box_corners()[shown].reshape(-1, 3) + scene.origin
    unit = Camera.orbit(target, 1.0, az, el, 1.0, fov_y=fov, up_axis=scene.up_axis)
    dist = fit_distance(corners, target, unit.eye - target, unit.up, fov, aspect, margin, projection)
    return Orbit(az, el, dist, tuple(float(v) for v in target), fov, projection)  # type: ignore[arg-type]


def _shown(scene: Scene, hidden: Iterable[int]) -> np.ndarray:
    shown = np.ones(scene.count, bool)
    shown[[i for i in hidden if 0 <= i < scene.count]] = False
    return shown if shown.any() else np.ones(scene.count, bool)


def _shown_bounds(scene: Scene, shown: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    return scene.aabb_min[shown].min(axis=0), scene.aabb_max[shown].max(axis=0)
