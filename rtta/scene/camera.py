"""Perspective or orthographic camera with orbit parameters; matrices in float64, relative to
the scene origin.

An orthographic view's half height is `Camera.height`; an orbit sets it to the orbit distance
times tan(fov / 2), the half height a perspective view of that orbit shows at its target, so
switching the projection keeps the scale there. Its eye only bounds the depth range: fitting
the depth places it a little outside the scene's bounding sphere, whatever the orbit distance.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, replace
from typing import Literal, get_args

import numpy as np

from ..errors import RttaError

DEFAULT_ORBIT = (35.0, 25.0, 2.2)
NEAR_RATIO = 1e-3  # near >= far * NEAR_RATIO: float32 depth keeps ~1e-4 relative precision at far
MAX_FAR_NEAR = 1e4  # beyond this, window depth loses the surfaces' order (`rtta bench report`, section 4)


def parse_orbit(text: str, option: str = "--camera", given: str | None = None) -> tuple[float, float, float]:
    """'AZ,EL,DIST' -> floats; DIST in units of the scene's bounding-sphere radius. Errors
    name `option` and quote `given` (default: `text`), the value as the user wrote it."""
    given = text if given is None else given
    try:
        az, el, dist = (float(x) for x in text.split(","))
    except ValueError:
        raise RttaError(f"{option} expects AZ,EL,DIST (three numbers), got '{given}'") from None
    if not orbit_in_range(az, el, dist):
        raise RttaError(
            f"{option} '{given}': AZ and EL must be finite degrees (|value| up to 1e6) and DIST "
            "between 1e-6 and 1e6 scene radii"
        )
    return az, el, dist


def orbit_in_range(az: float, el: float, dist: float) -> bool:
    """Whether an orbit is one `--camera` takes: finite angles up to 1e6 degrees and DIST
    between 1e-6 and 1e6 scene radii."""
    return bool(np.isfinite([az, el, dist]).all()) and 1e-6 <= dist <= 1e6 and max(abs(az), abs(el)) <= 1e6


UP_AXES = ("y", "z")
Projection = Literal["perspective", "ortho"]
PROJECTIONS: tuple[str, ...] = get_args(Projection)
_I3, _I4 = np.identity(3), np.identity(4)  # copied: np.identity is three Python calls
ORTHO_EYE = 2.0  # an orthographic eye stands this many radii before the bounding sphere's centre


def up_basis(up: str = "y") -> np.ndarray:
    """Rotation from the orbit's Y-up frame to the world: identity for 'y'; for 'z' (CAD,
    BIM) Y-up (x, y, z) becomes (x, -z, y), so the orbit's up is +Z and azimuth 0 looks
    from -Y, the CAD front view."""
    if up not in UP_AXES:
        raise ValueError(f"up axis must be one of {', '.join(UP_AXES)}, got {up!r}")
    return _I3.copy() if up == "y" else np.array([[1.0, 0.0, 0.0], [0.0, 0.0, -1.0], [0.0, 1.0, 0.0]])


def fit_distance(
    corners,
    target,
    direction,
    up,
    fov_y: float,
    aspect: float,
    margin: float = 0.05,
    projection: Projection = "perspective",
) -> float:
    """Distance from `target` along `direction` (unit, towards the eye) at which every corner
    (world points [k, 3]) projects inside the view with `margin` (a fraction of the width and
    of the height) left free on each side, in BOTH the vertical and the horizontal field of view.
    For 'ortho' the distance whose half height (distance * tan(fov / 2), Camera.orbit) frames them."""
    d = np.asarray(direction, np.float64)
    u = np.asarray(up, np.float64)
    r = np.cross(u, d)
    r /= np.linalg.norm(r)
    u = np.cross(d, r)
    p = np.asarray(corners, np.float64).reshape(-1, 3) - np.asarray(target, np.float64)
    x, y, z = p @ r, p @ u, p @ d
    keep = 1.0 - 2.0 * margin
    tan_y = np.tan(np.radians(fov_y) / 2.0) * keep
    tan_x = tan_y * aspect
    extent = float(np.abs(p).max()) if p.size else 0.0
    if projection == "ortho":
        half = max(float(np.abs(x).max(initial=0.0)) / aspect, float(np.abs(y).max(initial=0.0))) / keep
        return float(max(half / np.tan(np.radians(fov_y) / 2.0), extent * 1e-3, 1e-9))
    need = z + np.maximum(np.abs(x) / tan_x, np.abs(y) / tan_y)
    return float(max(need.max() if p.size else 0.0, (z.max() if p.size else 0.0) + extent * 1e-3, 1e-9))


def _length(v: np.ndarray) -> float:
    """|v| of a 3-vector, as np.linalg.norm works it out (sqrt of v.v; NaN stays NaN) in one
    call instead of six (a frame asks for a few)."""
    return math.sqrt(float(v @ v))


def _cross(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """a x b for two 3-vectors (np.cross takes 30 µs on them, a frame's view matrix two)."""
    return np.array([a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]])


@dataclass
class Camera:
    """A camera: where it stands, what it looks at, its field of view and depth range.

    `Camera.orbit` places one on an orbit around the scene (azimuth, elevation, distance in
    bounding radii) with near and far fitted to the bounding sphere; `view` and `projection`
    give the float64 matrices, relative to the scene origin.

    Parameters
    ----------
    eye, target, up : numpy.ndarray
        World-space float64 [3]: the eye, the point looked at, the up direction.
    fov_y : float, default 45
        Vertical field of view in degrees.
    near, far : float
        The depth range in world units.
    kind : {"perspective", "ortho"}, default "perspective"
        The projection.
    height : float, optional
        An orthographic view's half height in world units (None: |eye - target| *
        tan(fov_y / 2), what a perspective view shows at the target).

    Examples
    --------
    >>> import rtta
    >>> camera = rtta.Camera.orbit([0.0, 0.0, 0.0], 1.0, 35, 25, 2.2)
    >>> camera.projection(4 / 3).shape
    (4, 4)
    """

    eye: np.ndarray
    target: np.ndarray
    up: np.ndarray
    fov_y: float = 45.0
    near: float = 0.1
    far: float = 100.0
    kind: Projection = "perspective"
    height: float | None = None

    @classmethod
    def orbit(
        cls,
        center,
        radius: float,
        az: float,
        el: float,
        dist: float,
        fov_y: float = 45.0,
        up_axis: str = "y",
        projection: Projection = "perspective",
    ) -> Camera:
        """Azimuth about the up axis (+Y, or +Z for up_axis 'z') starting at +Z (-Y),
        elevation up from the ground plane; dist in radii. 'ortho': the half height that a
        perspective view at dist shows at the centre (module docstring)."""
        if projection not in PROJECTIONS:
            raise RttaError(f"projection must be one of {', '.join(PROJECTIONS)}, got {projection!r}")
        if not (math.isfinite(az) and math.isfinite(el)):
            raise RttaError(f"orbit angles must be finite degrees, got azimuth {az} and elevation {el}")
        a, e = math.radians(az), math.radians(el)  # (scalars: math, not numpy's ufuncs, a frame makes one)
        sa, ca, se, ce = math.sin(a), math.cos(a), math.sin(e), math.cos(e)
        basis = up_basis(up_axis)
        direction = basis @ np.array([sa * ce, se, ca * ce])
        up = basis @ np.array([-sa * se, ce, -ca * se])  # never degenerate
        center = np.asarray(center, np.float64)
        cam = cls(eye=center + direction * (dist * radius), target=center, up=up, fov_y=fov_y, kind=projection)
        return cam.fit_depth(center, radius)

    def half_height(self) -> float:
        """An orthographic view's half height in world units (`height`, or as a perspective
        view shows it at the target)."""
        if self.height is not None:
            return float(self.height)
        return float(np.linalg.norm(self.target - self.eye) * np.tan(np.radians(self.fov_y) / 2.0))

    def fit_depth(self, center, radius: float) -> Camera:
        """Near/far tight around the bounding sphere so depth keeps its precision. Inside the
        sphere the near plane stays at far * NEAR_RATIO: closer geometry is clipped rather
        than letting distant surfaces z-fight. An orthographic camera keeps its half height
        and moves its eye along the view axis to ORTHO_EYE radii before the centre: nothing
        is clipped however close the orbit, and float32 view depths stay precise however far."""
        if self.kind == "ortho":
            self.height = self.half_height()
            forward = self.target - self.eye
            forward = forward / np.linalg.norm(forward)
            ahead = float((np.asarray(center, np.float64) - self.eye) @ forward)
            shift = forward * (ahead - ORTHO_EYE * radius)
            self.eye = self.eye + shift
            self.near, self.far = (ORTHO_EYE - 1.01) * radius, (ORTHO_EYE + 1.01) * radius
            return self
        d = _length(np.asarray(center, np.float64) - self.eye)
        far = (d + radius) * 1.01
        near = max(d - radius * 1.01, far * NEAR_RATIO)
        self.near, self.far = near, far
        return self

    def depth_limited(self) -> tuple[Camera, str | None]:
        """This camera, or a copy whose near plane is raised to far / MAX_FAR_NEAR, with a
        message saying so: a wider depth range would draw z-fighting garbage."""
        if self.kind == "ortho" and self.far > self.near:
            return self, None  # window depth is linear in view depth: no range loses the order
        if self.near > 0 and self.far > self.near and self.far / self.near <= MAX_FAR_NEAR:
            return self, None
        far = self.far if self.far > 0 else 1.0
        near = far / MAX_FAR_NEAR
        msg = (
            f"far/near {self.far:g}/{self.near:g} exceeds {MAX_FAR_NEAR:g}: near plane raised to {near:g} "
            "(closer geometry is clipped)"
        )
        return replace(self, near=near, far=far), msg

    def view(self, origin) -> np.ndarray:
        """World-to-eye matrix for positions given relative to `origin`."""
        eye = self.eye - np.asarray(origin, np.float64)
        f = self.target - self.eye
        n = _length(f)
        if not math.isfinite(n) or n == 0:
            raise RttaError("camera eye and target coincide")
        f = f / n
        s = _cross(f, np.asarray(self.up, np.float64))
        if _length(s) < 1e-12:
            s = _cross(f, np.array([1.0, 0.0, 0.0] if abs(f[0]) < 0.9 else [0.0, 0.0, 1.0]))
        s /= _length(s)
        u = _cross(s, f)
        m = _I4.copy()
        m[0, :3], m[1, :3], m[2, :3] = s, u, -f
        m[:3, 3] = -m[:3, :3] @ eye
        return m

    def projection(self, aspect: float) -> np.ndarray:
        """OpenGL perspective or orthographic matrix (clip z in [-w, w])."""
        if not (0.0 < self.fov_y < 180.0):
            raise RttaError(f"field of view must be in (0, 180) degrees, got {self.fov_y}")
        n, f = self.near, self.far
        if self.kind == "ortho":
            h = self.half_height()
            if not (np.isfinite(h) and h > 0):
                raise RttaError(f"an orthographic view needs a positive half height, got {h:g}")
            p = np.identity(4)
            p[0, 0], p[1, 1] = 1.0 / (h * aspect), 1.0 / h
            p[2, 2], p[2, 3] = -2.0 / (f - n), -(f + n) / (f - n)
            return p
        t = 1.0 / np.tan(np.radians(self.fov_y) / 2.0)
        p = np.zeros((4, 4))
        p[0, 0] = t / aspect
        p[1, 1] = t
        p[2, 2] = -(f + n) / (f - n)
        p[2, 3] = -2.0 * f * n / (f - n)
        p[3, 2] = -1.0
        return p


def view_depth(window, proj: np.ndarray):
    """Window depth [0, 1] -> distance before the eye along the view axis, for a GL
    perspective or orthographic `proj` (ndc z = (P22 z + P23) / (P32 z + P33) at view z)."""
    ndc = np.asarray(window, np.float64) * 2.0 - 1.0
    p = np.asarray(proj, np.float64)
    with np.errstate(divide="ignore", invalid="ignore"):
        return -(p[2, 3] - ndc * p[3, 3]) / (ndc * p[3, 2] - p[2, 2])


def near_distance(proj: np.ndarray) -> float:
    """`view_depth(0.0, proj)` (the near plane's distance) in scalar arithmetic: no numpy call,
    for the ones made every frame."""
    num, den = float(proj[2, 3]) + float(proj[3, 3]), float(proj[3, 2]) + float(proj[2, 2])
    if den == 0.0:
        return math.copysign(math.inf, num) if num else math.nan
    return num / den


def is_ortho(proj: np.ndarray) -> bool:
    """Whether a GL projection matrix is orthographic (its w row is (0, 0, 0, 1))."""
    return bool(proj[3, 2] == 0.0 and proj[3, 3] == 1.0)


def ortho_near(proj: np.ndarray) -> float | None:
    """near / (far - near) of an orthographic `proj` (window depth + this, times far - near, is
    the view distance); None for a perspective one."""
    if not is_ortho(proj):
        return None
    near, far = view_depth(0.0, proj), view_depth(1.0, proj)
    return float(near / (far - near))


def outline_eye(view: np.ndarray, proj: np.ndarray, radius: float) -> np.ndarray:
    """Where objects' outlines are seen from (scene origin at 0, as `view` expects): the eye,
    or in an orthographic view a point far back along the view axis (the outline of a box seen
    along parallel rays is its outline from infinitely far). `view` is rigid (Camera.view): its
    inverse is the transposed rotation, and the eye -R^T t."""
    rotation = view[:3, :3]
    eye = -(rotation.T @ view[:3, 3])
    return eye + rotation[2] * (1e4 * max(radius, 1e-9) if is_ortho(proj) else 0.0)
