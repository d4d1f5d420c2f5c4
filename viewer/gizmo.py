"""The view cube in the composite's top-right corner: it turns with the camera, shows which
side of the model faces the viewer (relative to the file's up axis: TOP looks down it) and the
world axes, and a click on a face, an edge or a corner turns the view there (animated).

Geometry is in the orbit's frame (Y up, the file's up axis mapped onto it, as viewer.orbit):
the view from direction d looks along -d. Each visible face is a 3 x 3 grid: its centre cell
is the face's view, its border cells the views from an edge or a corner.
"""

from __future__ import annotations

import time
from dataclasses import dataclass
from typing import Literal

import numpy as np
from imgui_bundle import imgui

from rtta.scene.camera import up_basis
from rtta.scene.framing import STANDARD_VIEWS

from .orbit import Orbit, _direction
from .views import Rect

HALF = 36.0  # the cube's half size on screen (pixels)
MARGIN = 14.0  # from the composite's corner
INNER = 0.6  # the centre cell's half size, in face units (border cells: edges and corners)
TURN_S = 0.3  # how long a turn to a view takes
FACES = {  # orbit-frame normal -> the standard view seen from that side
    (0, 0, 1): "front",
    (0, 0, -1): "back",
    (1, 0, 0): "right",
    (-1, 0, 0): "left",
    (0, 1, 0): "top",
    (0, -1, 0): "bottom",
}
FACE_FILL = imgui.IM_COL32(205, 210, 220, 235)
CELL_HOVER = imgui.IM_COL32(255, 200, 80, 255)
EDGE = imgui.IM_COL32(70, 75, 85, 255)
LABEL = imgui.IM_COL32(30, 32, 38, 255)
AXIS_COLORS = (imgui.IM_COL32(220, 60, 60, 255), imgui.IM_COL32(60, 170, 60, 255), imgui.IM_COL32(60, 100, 230, 255))
Part = Literal["cube", "projection"]


def view_angles(direction) -> tuple[float, float]:
    """(az, el) in degrees of the view from orbit-frame `direction` (towards the eye): the
    standard view's angles for a face, else those of the direction itself."""
    d = np.asarray(direction, np.float64)
    sx, sy, sz = (int(v) for v in np.sign(d))
    key = (sx, sy, sz)
    if abs(sx) + abs(sy) + abs(sz) == 1 and key in FACES:
        return STANDARD_VIEWS[FACES[key]]
    d = d / np.linalg.norm(d)
    return float(np.degrees(np.arctan2(d[0], d[2])) % 360.0), float(np.degrees(np.arcsin(np.clip(d[1], -1, 1))))


def centre(rect: Rect) -> np.ndarray:
    """The cube's centre on screen for a composite rectangle."""
    x, y, w, _ = rect
    r = HALF * np.sqrt(3.0)
    return np.array([x + w - MARGIN - r, y + MARGIN + r])


def _screen_axes(orbit: Orbit) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Right, up and towards-the-eye in the orbit frame (the cube turns as the scene does)."""
    d, up = _direction(orbit.az, orbit.el)  # orbit frame: Y up
    right = np.cross(up, d)
    return right / np.linalg.norm(right), up, d


def cells(rect: Rect, orbit: Orbit) -> list[tuple[float, tuple[int, int, int], np.ndarray]]:
    """(depth, orbit-frame direction of the view, screen quad [4, 2]) of every cell of the faces
    that face the viewer, farthest first (the order to draw them in)."""
    right, up, toward = _screen_axes(orbit)
    c = centre(rect)
    out = []
    bands = ((-1.0, -INNER), (-INNER, INNER), (INNER, 1.0))
    for normal in FACES:
        n = np.array(normal, np.float64)
        if n @ toward <= 1e-3:
            continue
        u = np.roll(n, 1) if n[1] == 0 else np.array([1.0, 0.0, 0.0])
        v = np.cross(n, u)
        for i, (u0, u1) in zip((-1, 0, 1), bands, strict=True):
            for j, (v0, v1) in zip((-1, 0, 1), bands, strict=True):
                corners = [n + a * u + b * v for a, b in ((u0, v0), (u1, v0), (u1, v1), (u0, v1))]
                quad = np.array([[c[0] + HALF * (p @ right), c[1] - HALF * (p @ up)] for p in corners])
                direction = tuple(int(k) for k in n + i * u + j * v)
                out.append((float(n @ toward), direction, quad))
    out.sort(key=lambda cell: cell[0])
    return out


def _inside(quad: np.ndarray, x: float, y: float) -> bool:
    """Point in a convex quad (either winding)."""
    edges = np.roll(quad, -1, axis=0) - quad
    rel = np.array([x, y]) - quad
    cross = edges[:, 0] * rel[:, 1] - edges[:, 1] * rel[:, 0]
    return bool((cross >= 0).all() or (cross <= 0).all())


def projection_rect(rect: Rect) -> tuple[float, float, float, float]:
    """The perspective/ortho switch under the cube (x0, y0, x1, y1)."""
    c = centre(rect)
    r = HALF * np.sqrt(3.0)
    return (c[0] - 34, c[1] + r + 4, c[0] + 34, c[1] + r + 22)


def hit(rect: Rect, orbit: Orbit, x: float, y: float) -> tuple[Part, tuple[int, int, int] | None] | None:
    """What a click at window point (x, y) lands on: ('cube', the view's direction), the
    ('projection', None) switch, or None (elsewhere)."""
    x0, y0, x1, y1 = projection_rect(rect)
    if x0 <= x < x1 and y0 <= y < y1:
        return "projection", None
    for _, direction, quad in reversed(cells(rect, orbit)):  # the nearest face first
        if _inside(quad, x, y):
            return "cube", direction
    return None


def draw(dl, rect: Rect, orbit: Orbit, up_axis: str, mouse: tuple[float, float]) -> None:
    """The cube, its labels, the world axes and the projection switch, on draw list `dl`."""
    if rect[2] < 8 * HALF or rect[3] < 6 * HALF:
        return  # no room
    found = hit(rect, orbit, *mouse)
    hover = found[1] if found and found[0] == "cube" else None
    right, up, toward = _screen_axes(orbit)
    for _, direction, quad in cells(rect, orbit):
        pts = [imgui.ImVec2(float(px), float(py)) for px, py in quad]
        dl.add_quad_filled(*pts, CELL_HOVER if direction == hover else FACE_FILL)
        dl.add_quad(*pts, EDGE, 1.0)
    c = centre(rect)
    for normal, name in FACES.items():
        n = np.array(normal, np.float64)
        if n @ toward > 0.35:
            p = c + HALF * np.array([n @ right, -(n @ up)])
            label = name.upper()
            size = imgui.calc_text_size(label)
            k = min(1.0, 1.6 * HALF * float(n @ toward) / max(size.x, 1.0))  # the label fits its face
            at = imgui.ImVec2(float(p[0] - k * size.x / 2), float(p[1] - k * size.y / 2))
            dl.add_text(imgui.get_font(), imgui.get_font_size() * k, at, LABEL, label)
    # the world axes (X red, Y green, Z blue) from the cube's lower-left
    origin = c + np.array([-HALF * 2.1, HALF * 1.4])
    world = up_basis(up_axis).T  # world axis k in the orbit frame: column k
    for k, col in enumerate(AXIS_COLORS):
        a = world[:, k]
        tip = origin + 22.0 * np.array([a @ right, -(a @ up)])
        dl.add_line(imgui.ImVec2(*origin), imgui.ImVec2(*tip), col, 2.0)
        dl.add_text(imgui.ImVec2(float(tip[0] + 2), float(tip[1] - 7)), col, "XYZ"[k])
    x0, y0, x1, y1 = projection_rect(rect)
    over = x0 <= mouse[0] < x1 and y0 <= mouse[1] < y1
    dl.add_rect_filled(imgui.ImVec2(x0, y0), imgui.ImVec2(x1, y1), CELL_HOVER if over else FACE_FILL, 3.0)
    label = orbit.projection
    size = imgui.calc_text_size(label)
    dl.add_text(imgui.ImVec2((x0 + x1 - size.x) / 2, (y0 + y1 - size.y) / 2), LABEL, label)


@dataclass
class Turn:
    """The camera turning to (az, el) over TURN_S seconds (smoothstep; the shorter way round)."""

    az0: float
    el0: float
    az1: float
    el1: float
    t0: float

    @classmethod
    def to(cls, orbit: Orbit, az: float, el: float) -> Turn:
        return cls(orbit.az, orbit.el, float(az), float(el), time.perf_counter())

    def step(self, orbit: Orbit, now: float | None = None) -> bool:
        """Move `orbit` to where the turn is at `now`; True once it has arrived."""
        k = ((time.perf_counter() if now is None else now) - self.t0) / TURN_S
        k = 1.0 if k >= 1.0 - 1e-9 else max(0.0, k)  # (t0 + TURN_S) - t0 can fall an ulp short
        s = k * k * (3.0 - 2.0 * k)
        d_az = (self.az1 - self.az0 + 180.0) % 360.0 - 180.0
        orbit.az = (self.az0 + s * d_az) % 360.0 if k < 1.0 else self.az1 % 360.0
        orbit.el = self.el0 + s * (self.el1 - self.el0)
        return k >= 1.0
