"""What paints over or cuts the scene in the viewer: the projector and the lens the panel
describes, and the lens following the mouse."""

from __future__ import annotations

from typing import TYPE_CHECKING

import numpy as np

from rtta.ldi.lens import Lens, default_placement
from rtta.passes.projector import Projector, default_image

if TYPE_CHECKING:
    from rtta.renderer.renderer import Renderer

    from .orbit import Orbit
    from .state import ViewerState
    from .views import Layout


class Painting:
    """The projector and the lens (a part of `viewer.app.Viewer`)."""

    state: ViewerState
    renderer: Renderer
    orbit: Orbit
    layout: Layout
    _projector_image: np.ndarray | None
    _lens_cache: Lens | None

    def _projector(self, camera):
        """The Projector the panel describes (None when off); the image is made once."""
        p, scene = self.state.projector, self.renderer.scene
        if not p.on:
            return None
        if self._projector_image is None:
            self._projector_image = default_image()
        kw = {"image": self._projector_image, "fov_y": p.fov, "strength": p.strength, "shadows": p.shadows}
        if p.attached:
            return Projector.at_camera(camera, scene.center, scene.radius, **kw)
        return Projector.orbit(scene.center, scene.radius, p.az, p.el, p.dist, up_axis=scene.up_axis, **kw)

    def _lens(self):
        """The Lens the panel describes (None when off); its geometry is made once per shape."""
        p, scene = self.state.lens, self.renderer.scene
        if not p.on:
            return None
        if self._lens_cache is None or self._lens_cache.key != p.shape:
            self._lens_cache = Lens.shape(p.shape, scene.center, 1.0)
        center = p.center if p.center is not None else default_placement(scene, self.state.highlighted)[0]
        self._lens_cache.center = np.asarray(center, float)
        self._lens_cache.radius = max(p.radius, 1e-3) * scene.radius
        return self._lens_cache

    def move_lens(self, x: float, y: float) -> None:
        """Put the lens under window point (x, y), at its present depth (on the plane through
        its centre facing the camera)."""
        p, scene, lens = self.state.lens, self.renderer.scene, self._lens()
        cx, cy, cw, ch = self.layout.composite
        if lens is None or cw < 1 or ch < 1:
            return
        camera = self.orbit.camera()
        view, proj = self.renderer.matrices(camera, (cw, ch))
        inv = np.linalg.inv(proj @ view)
        ndc = (2.0 * (x - cx) / cw - 1.0, 1.0 - 2.0 * (y - cy) / ch)
        near, far = (inv @ np.array([*ndc, z, 1.0]) for z in (-1.0, 1.0))
        near, far = near[:3] / near[3], far[:3] / far[3]
        current = lens.center - scene.origin
        forward = np.asarray(camera.target, float) - np.asarray(camera.eye, float)
        ray = far - near
        denom = float(ray @ forward)
        if abs(denom) < 1e-12:
            return
        k = float((current - near) @ forward) / denom
        hit = near + k * ray + scene.origin
        if np.isfinite(hit).all():
            p.center = tuple(float(v) for v in hit)
