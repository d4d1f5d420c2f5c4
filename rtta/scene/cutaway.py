"""Section planes and what they cut: the value types of cutaways, parsed in one place.

A `SectionPlane(normal, d)` removes the points p with normal·p > d (world coordinates, the
file's units as `rtta info` prints its bounds). `parse_section` reads the CLI's SPEC:
`x=V`, `y=V`, `z=V` (remove what lies beyond V on that axis), `-x=V`, `-y=V`, `-z=V` (remove
what lies below V) or `nx,ny,nz,d`; `x=P%` places the plane P% of the way across the scene's
bounds on that axis, and `x` alone halfway (a plane `at` a fraction, placed on a scene by
`SectionPlane.on`, as the viewer's slider is: one spec cuts every scene of a dataset alike).
`Cutaway` holds up to MAX_SECTIONS planes, the cap style and the scope; `cut_flags` and
`removed` give what each object gets from it.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Literal, get_args

import numpy as np

from ..errors import RttaError

Caps = Literal["solid", "hatch", "off"]
SectionScope = Literal["all", "context"]
CAPS: tuple[Caps, ...] = get_args(Caps)
SECTION_SCOPES: tuple[SectionScope, ...] = get_args(SectionScope)
MAX_SECTIONS = 6
_AXES = {"x": (1.0, 0.0, 0.0), "y": (0.0, 1.0, 0.0), "z": (0.0, 0.0, 1.0)}
LIMIT = 1e15  # |d| and |normal| components above this are refused (float32 and NaN safety)


@dataclass(frozen=True)
class SectionPlane:
    """The half-space n·p > d removed (n normalized; world coordinates).

    Parameters
    ----------
    normal : tuple of float
        (nx, ny, nz), any non-zero length; stored unit length.
    d : float
        Offset in world units (scaled with the normal); with `at`, none yet.
    at : float, optional
        An axis plane's place as a fraction of the scene's bounds on its axis (0: the low
        side, 1: the high side), `d` to be worked out for a scene (`on`).
    """

    normal: tuple[float, float, float]
    d: float
    at: float | None = None

    def __post_init__(self) -> None:
        n = np.asarray(self.normal, np.float64)
        length = float(np.linalg.norm(n)) if n.shape == (3,) else 0.0
        if not (math.isfinite(length) and length > 0 and math.isfinite(self.d)):
            raise RttaError(f"--section: a plane needs a non-zero finite normal and a finite offset, got {self}")
        object.__setattr__(self, "normal", tuple(float(v) for v in n / length))
        object.__setattr__(self, "d", float(self.d) / length)

    def on(self, bounds) -> SectionPlane:
        """This plane placed on a scene whose box is `bounds` (lo, hi): itself unless it is `at`
        a fraction of the box."""
        if self.at is None:
            return self
        lo, hi = (np.asarray(b, np.float64) for b in bounds)
        k = int(np.argmax(np.abs(self.normal)))
        where = float(lo[k] + self.at * (hi[k] - lo[k]))
        return SectionPlane(self.normal, where * self.normal[k])

    def removes(self, points: np.ndarray) -> np.ndarray:
        """bool [...]: which of the world points [..., 3] this plane removes."""
        return np.asarray(points, np.float64) @ np.asarray(self.normal) > self._placed().d

    def relative(self, origin: np.ndarray) -> tuple[float, float, float, float]:
        """(n, d') for coordinates relative to `origin`: n·(p + origin) > d ⇔ n·p > d - n·origin."""
        return (*self.normal, self._placed().d - float(np.dot(self.normal, origin)))

    def _placed(self) -> SectionPlane:
        if self.at is not None:
            raise ValueError(f"{self} lies at a fraction of a scene's bounds: place it with on(scene.bounds)")
        return self


def parse_section(spec: str) -> SectionPlane:
    """A SectionPlane from `x=V`, `-x=V` (likewise y, z) or `nx,ny,nz,d`.

    Raises
    ------
    RttaError
        For anything else (the message quotes the SPEC and the accepted forms).
    """
    text = str(spec).strip().lower().replace(" ", "")
    bad = RttaError(f"--section expects x=V, x=P% or x (halfway), -x likewise (y, z too) or nx,ny,nz,d, got '{spec}'")
    axis, eq, value = text.partition("=")
    try:
        if eq or "," not in text:
            sign = -1.0 if axis[:1] == "-" else 1.0
            normal = _AXES.get(axis[1:] if axis[:1] in "-+" else axis)
            percent = not eq or value.endswith("%")
            v = float(value.removesuffix("%")) if eq else 50.0
            if normal is None or not math.isfinite(v) or abs(v) > LIMIT:
                raise bad
            signed = (sign * normal[0], sign * normal[1], sign * normal[2])
            return SectionPlane(signed, 0.0, v / 100.0) if percent else SectionPlane(signed, sign * v)
        parts = [float(p) for p in text.split(",")]
    except ValueError:
        raise bad from None
    if len(parts) != 4 or not all(math.isfinite(p) and abs(p) <= LIMIT for p in parts) or not any(parts[:3]):
        raise bad
    return SectionPlane((parts[0], parts[1], parts[2]), parts[3])


@dataclass(frozen=True)
class Cutaway:
    """What is cut and how: the planes, the caps on closed parts, the scope.

    Parameters
    ----------
    planes : tuple of SectionPlane
        Up to MAX_SECTIONS; a point is removed when any plane removes it.
    caps : {'solid', 'hatch', 'off'}
        The cut faces of closed parts: filled in the part's darker colour, hatched, or open.
    scope : {'all', 'context'}
        'context': the focus parts stay whole, only the others are cut.
    """

    planes: tuple[SectionPlane, ...] = ()
    caps: Caps = "solid"
    scope: SectionScope = "all"

    def __post_init__(self) -> None:
        object.__setattr__(self, "planes", tuple(self.planes))
        if len(self.planes) > MAX_SECTIONS:
            raise RttaError(f"--section: at most {MAX_SECTIONS} planes, got {len(self.planes)}")
        if self.caps not in CAPS:
            raise RttaError(f"--caps must be one of {', '.join(CAPS)}, got '{self.caps}'")
        if self.scope not in SECTION_SCOPES:
            raise RttaError(f"--section-scope must be one of {', '.join(SECTION_SCOPES)}, got '{self.scope}'")

    def __bool__(self) -> bool:
        return bool(self.planes)

    def cut(self, count: int, focus=()) -> np.ndarray:
        """bool [count]: the objects the planes cut (all, or all but the focus with scope 'context')."""
        out = np.full(count, bool(self.planes))
        if self.scope == "context":
            out[[o for o in focus if 0 <= o < count]] = False
        return out

    def sides(self, scene, offsets: np.ndarray | None, cut: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """(removed, crossed), bool [n] each, of the `cut` objects of `scene` moved by `offsets`
        (float [n, 3] world, or None): removed, one plane removes it whole (every vertex beyond
        it: not packed or drawn); crossed, not removed but some vertex lies beyond a plane (the
        others lie wholly on the kept side: drawn as they are, without a cut or a cap)."""
        n = scene.count
        out, crossed = np.zeros(n, bool), np.zeros(n, bool)
        if not self.planes or not cut.any() or not scene.vertex_count:
            return out, crossed
        counts = np.bincount(scene.object_ids, minlength=n)
        starts = np.minimum(np.concatenate([[0], np.cumsum(counts)[:-1]]), scene.vertex_count - 1)
        shift = np.asarray(scene.origin, np.float64) + (0.0 if offsets is None else np.asarray(offsets, np.float64))
        bounds = scene.bounds  # planes at a fraction of them (x=P%) placed on this scene
        for plane in (p.on(bounds) for p in self.planes):
            normal = np.asarray(plane.normal)
            dist = scene.positions @ normal.astype(np.float32)
            least = np.minimum.reduceat(dist, starts).astype(np.float64) + shift @ normal
            most = np.maximum.reduceat(dist, starts).astype(np.float64) + shift @ normal
            out |= (counts > 0) & (least > plane.d)
            crossed |= (counts > 0) & (most > plane.d - 1e-6 * scene.radius)  # float32 slack: cut when in doubt
        return out & cut, crossed & cut & ~out
