"""Orbit camera control: rotate about a target, pan, zoom towards the cursor, frame.

Pure numpy, no GL and no window: the viewer feeds it pixel deltas. Elevation is clamped
short of the poles, so the view never flips; near/far follow the scene's bounding sphere.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from rtta.scene.camera import DEFAULT_ORBIT, Camera, Projection, fit_distance, up_basis

DEGREES_PER_PIXEL = 0.3
MAX_ELEVATION = 89.0
ZOOM_PER_STEP = 0.88  # 12% closer per wheel notch (0.85 went from the whole model to a close-up in 5)


def _direction(az: float, el: float, up_axis: str = "y") -> tuple[np.ndarray, np.ndarray]:
    """Unit vector from the target to the eye, and the camera's up vector (as Camera.orbit)."""
    a, e = np.radians(az), np.radians(el)
    basis = up_basis(up_axis)
    d = np.array([np.sin(a) * np.cos(e), np.sin(e), np.cos(a) * np.cos(e)])
    up = np.array([-np.sin(a) * np.sin(e), np.cos(e), -np.cos(a) * np.sin(e)])
    return basis @ d, basis @ up


@dataclass
class Orbit:
    """Target (world, float64), azimuth/elevation in degrees, distance in world units."""

    target: np.ndarray
    az: float
    el: float
    dist: float
    scene_center: np.ndarray
    scene_radius: float
    fov_y: float = 45.0
    up_axis: str = "y"  # the scene's up: the orbit turns about it
    projection: Projection = "perspective"  # or 'ortho': the half height a perspective view shows at the target

    @classmethod
    def default(cls, center, radius: float, up_axis: str = "y") -> Orbit:
        az, el, dist = DEFAULT_ORBIT
        c = np.asarray(center, np.float64)
        return cls(
            target=c.copy(), az=az, el=el, dist=dist * radius, scene_center=c, scene_radius=radius, up_axis=up_axis
        )

    def camera(self) -> Camera:
        d, up = _direction(self.az, self.el, self.up_axis)
        cam = Camera(
            eye=self.target + d * self.dist, target=self.target.copy(), up=up, fov_y=self.fov_y, kind=self.projection
        )
        # near/far must hold the scene and the target, wherever the user wandered
        far_point = float(np.linalg.norm(self.target - self.scene_center)) + self.scene_radius
        return cam.fit_depth(self.target, max(far_point, self.dist * 1e-3))

    def _axes(self) -> tuple[np.ndarray, np.ndarray]:
        d, up = _direction(self.az, self.el, self.up_axis)
        right = np.cross(up, d)
        return right / np.linalg.norm(right), up

    def _units_per_pixel(self, height_px: int) -> float:
        return 2.0 * self.dist * np.tan(np.radians(self.fov_y) / 2.0) / max(1, height_px)

    def rotate(self, dx: float, dy: float) -> None:
        """Drag by (dx, dy) pixels (y down): left/right turns about the up axis, up/down tilts."""
        self.az = (self.az - dx * DEGREES_PER_PIXEL) % 360.0
        self.el = float(np.clip(self.el + dy * DEGREES_PER_PIXEL, -MAX_ELEVATION, MAX_ELEVATION))

    def pan(self, dx: float, dy: float, height_px: int) -> None:
        """Move the target so the scene follows the cursor (y down)."""
        right, up = self._axes()
        k = self._units_per_pixel(height_px)
        self.target = self.target - right * dx * k + up * dy * k

    def zoom(self, steps: float, cursor_ndc: tuple[float, float] = (0.0, 0.0), aspect: float = 1.0) -> None:
        """Zoom by `steps` wheel notches (positive: closer) towards the point under the cursor
        on the plane through the target, which stays put on screen."""
        f = ZOOM_PER_STEP ** float(steps)
        new_dist = float(np.clip(self.dist * f, self.scene_radius * 1e-4, self.scene_radius * 1e3))
        f = new_dist / self.dist
        right, up = self._axes()
        half = self.dist * np.tan(np.radians(self.fov_y) / 2.0)
        p = self.target + (cursor_ndc[0] * aspect * right + cursor_ndc[1] * up) * half
        self.target = p + (self.target - p) * f
        self.dist = new_dist

    def frame(self, center=None, radius: float | None = None, aspect: float = 1.0, corners=None) -> None:
        """Fit in view, keeping the direction, with a margin on all four sides whatever the
        aspect (width / height): the points `corners` (world [k, 3], e.g. the 8 corners of
        each visible object's box), about the centre of their bounds; else a sphere (default: the whole scene)."""
        if corners is not None and len(corners):
            pts = np.asarray(corners, np.float64).reshape(-1, 3)
            c = (pts.min(axis=0) + pts.max(axis=0)) / 2.0
        else:
            c = self.scene_center if center is None else np.asarray(center, np.float64)
            r = self.scene_radius if radius is None else max(float(radius), self.scene_radius * 1e-4)
            pts = c + np.concatenate([np.eye(3), -np.eye(3)]) * r  # the sphere's extreme points
            corners = None
        d, up = _direction(self.az, self.el, self.up_axis)
        self.target = c.copy()
        dist = fit_distance(pts, c, d, up, self.fov_y, max(float(aspect), 1e-3), projection=self.projection)
        if corners is None:  # a sphere: its silhouette, not only the six points, must fit
            half = np.arctan(np.tan(np.radians(self.fov_y) / 2.0) * min(1.0, max(float(aspect), 1e-3)) * 0.9)
            dist = max(dist, r / np.sin(half))
        self.dist = float(np.clip(dist, self.scene_radius * 1e-4, self.scene_radius * 1e3))

    def orbit_around(self, point) -> None:
        """Orbit about `point` from where the eye is now (the view turns to face it)."""
        d, _ = _direction(self.az, self.el, self.up_axis)
        eye = self.target + d * self.dist
        v = eye - np.asarray(point, np.float64)
        dist = float(np.linalg.norm(v))
        if dist < self.scene_radius * 1e-6:
            return
        v = up_basis(self.up_axis).T @ (v / dist)  # back into the orbit's Y-up frame
        self.el = float(np.clip(np.degrees(np.arcsin(np.clip(v[1], -1, 1))), -MAX_ELEVATION, MAX_ELEVATION))
        self.az = float(np.degrees(np.arctan2(v[0], v[2])) % 360.0)
        self.target = np.asarray(point, np.float64).copy()
        self.dist = dist
