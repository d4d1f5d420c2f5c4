"""`rtta.pick`: what lies under a pixel of a view, in world coordinates, in one call."""

from __future__ import annotations

from collections.abc import Iterable, Sequence
from typing import NamedTuple

import numpy as np

from ..errors import RttaError
from ..scene.camera import Camera, Projection
from ..scene.framing import StandardView
from ..scene.model import Scene
from ..scene.preprocess import DEFAULT_SMOOTH_ANGLE
from .api import SceneLike, _prepare, _session
from .options import check_size, make_settings, orbit_camera
from .snapshot import resolve_names


class Pick(NamedTuple):
    """The surface under a pixel of a view, as `pick` gives it.

    Attributes
    ----------
    name : str
        The part's name (as `rtta info` lists it).
    point : numpy.ndarray
        The point hit, world coordinates, float64 [3].
    normal : numpy.ndarray
        The unit normal of the part's surface there, towards the camera, world coordinates.
    """

    name: str
    point: np.ndarray
    normal: np.ndarray


def pick(
    scene: SceneLike = None,
    *,
    x: int,
    y: int,
    camera: Camera | str | Sequence[float] | None = None,
    size: Sequence[int] = (1024, 768),
    projection: Projection = "perspective",
    view: StandardView | None = None,
    fov: float = 45.0,
    hidden: str | Iterable[str] = (),
    smooth_angle: float = DEFAULT_SMOOTH_ANGLE,
    smooth: bool = False,
) -> Pick | None:
    """The part, point and normal under pixel (x, y) of a view, as `snapshot` frames it.

    The view is drawn directly (as mode "std") in the process's headless context; the point
    is the pixel centre's ray at the drawn depth, unprojected in float64.

    Parameters
    ----------
    scene : str, Path, Scene or None
        A scene file, a loaded `Scene`, or None for the built-in demo.
    x, y : int
        The pixel, counted from the top-left one (as in the PNG `snapshot` gives).
    camera : Camera, str or sequence of float, optional
        As in `snapshot`: "AZ,EL,DIST", "AZ,EL" (fitted) or a `Camera`.
    size : sequence of int, default (1024, 768)
        The view's width and height in pixels.
    projection : {"perspective", "ortho"}, default "perspective"
        The projection, as in `snapshot`.
    view : {"front", "back", "left", "right", "top", "bottom", "iso"}, optional
        A standard view relative to the file's up axis, as in `snapshot`.
    fov : float, default 45
        Vertical field of view in degrees.
    hidden : str or iterable of str
        Objects left out (names, group names or globs); a pick sees through them.
    smooth_angle : float, default 30
        Normals made at load are smoothed across faces within this angle (degrees).
    smooth : bool, default False
        Smooth the file's own normals too.

    Returns
    -------
    Pick or None
        (name, point, normal) in world coordinates, the normal that of the part's triangle
        nearest the point, facing the camera; None where the pixel shows the background.

    Raises
    ------
    RttaError
        A pixel outside the view, an unreadable scene, an unknown name or a bad value.

    Examples
    --------
    >>> import rtta
    >>> hit = rtta.pick(None, x=160, y=120, size=(320, 240))  # the demo's middle pixel
    >>> hit is None or hit.point.shape == (3,)
    True
    """
    scene = _session.scene(scene, smooth_angle, smooth)
    W, H = check_size(size)
    if not (isinstance(x, (int, np.integer)) and isinstance(y, (int, np.integer)) and 0 <= x < W and 0 <= y < H):
        raise RttaError(f"pixel ({x}, {y}) lies outside the {W}x{H} view (x in 0..{W - 1}, y in 0..{H - 1})")
    hidden_ids = resolve_names(scene, [hidden] if isinstance(hidden, str) else list(hidden), "hidden")
    cam = orbit_camera(scene, camera, fov, projection=projection, view=view, aspect=W / H, hidden=hidden_ids)
    renderer = _prepare(scene, make_settings(), None, None, hidden_ids)
    row = H - 1 - int(y)  # GL rows count from the bottom
    try:
        found = renderer.std(cam, (W, H)).texels(np.array([[int(x), row, 0]]), ids=True)
    except ValueError as exc:
        raise RttaError(str(exc)) from None
    oid, depth = int(found["id"][0]), float(found["depth"][0])
    if oid < 0 or depth >= 1.0:
        return None
    view_m, proj = renderer.matrices(cam, (W, H))
    ndc = np.array([(x + 0.5) / W * 2.0 - 1.0, (row + 0.5) / H * 2.0 - 1.0, depth * 2.0 - 1.0, 1.0])
    p = np.linalg.solve(proj @ view_m, ndc)
    point = p[:3] / p[3] + scene.origin
    towards = cam.eye - point if cam.kind == "perspective" else cam.eye - cam.target
    return Pick(scene.names[oid], point, _normal(scene, oid, point, towards))


def _normal(scene: Scene, oid: int, point: np.ndarray, towards: np.ndarray) -> np.ndarray:
    """The unit normal of the object's triangle nearest `point`, turned to face `towards`."""
    first, count = (int(v) for v in scene.index_ranges[oid])
    tris = scene.positions[scene.indices[first : first + count].reshape(-1, 3)].astype(np.float64) + scene.origin
    import trimesh  # here, not at import: `import rtta` must not start cascadio's OpenCASCADE (rtta.cli.guard)

    near = trimesh.triangles.closest_point(tris, np.broadcast_to(point, (len(tris), 3)))
    a, b, c = tris[int(np.argmin(np.linalg.norm(near - point, axis=1)))]
    n = np.cross(b - a, c - a)
    n /= max(float(np.linalg.norm(n)), 1e-300)
    return -n if n @ towards < 0 else n
