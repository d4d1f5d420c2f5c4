"""The measure tool (R): two clicks on the model give a distance and its dx, dy, dz in the
file's unit, drawn as a labelled line that stays on the model while the view moves.

A click is picked on the scene drawn directly (the renderer's STD pass, the parts not hidden):
the surface point under the cursor, unprojected in float64 as `rtta.pick` does, or the
nearest vertex of the parts there within SNAP_PX pixels that the view shows (not behind a
surface), so an edge's two corners give its exact length (where an exploded view moved the
parts: as shown, moved).
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import TYPE_CHECKING

import numpy as np
from imgui_bundle import imgui

if TYPE_CHECKING:
    from rtta.renderer.renderer import Renderer
    from rtta.scene.camera import Camera

SNAP_PX = 8.0
MAX_CANDIDATES = 64  # parts whose vertices a click looks at, nearest first
LINE = imgui.IM_COL32(255, 140, 30, 255)
LABEL_BG = imgui.IM_COL32(20, 20, 24, 200)
LABEL_TEXT = imgui.IM_COL32(255, 235, 200, 255)


@dataclass
class Measurement:
    """Two world points (float64) and the parts they lie on."""

    a: np.ndarray
    b: np.ndarray
    parts: tuple[str, str]

    @property
    def delta(self) -> np.ndarray:
        return self.b - self.a

    @property
    def distance(self) -> float:
        return float(np.linalg.norm(self.delta))


@dataclass
class Ruler:
    """The tool's state: on or off, the first point of a measurement, the measurements."""

    on: bool = False
    first: tuple[np.ndarray, str] | None = None
    done: list[Measurement] = field(default_factory=list)

    def add(self, point: np.ndarray, part: str) -> Measurement | None:
        """A clicked point: the first of a pair, or the second (then the measurement)."""
        if self.first is None:
            self.first = (np.asarray(point, np.float64), part)
            return None
        a, part_a = self.first
        self.first = None
        m = Measurement(a, np.asarray(point, np.float64), (part_a, part))
        self.done.append(m)
        return m

    def clear(self) -> None:
        self.first = None
        self.done.clear()


def decimals(radius: float) -> int:
    """Decimals that show a scene of this radius to about a thousandth of its size."""
    return int(np.clip(3 - np.floor(np.log10(max(radius, 1e-12))), 0, 6))


def describe(m: Measurement, unit: str, radius: float) -> tuple[str, str]:
    """('2.000 m', 'dx 0.000  dy 0.000  dz 2.000') for a measurement."""
    k, u = decimals(radius), f" {unit}" if unit else ""
    dx, dy, dz = m.delta
    return f"{m.distance:.{k}f}{u}", f"dx {dx:.{k}f}  dy {dy:.{k}f}  dz {dz:.{k}f}"


def point_at(renderer: Renderer, camera: Camera, viewport: tuple[int, int], px: int, py: int):
    """(world point, object id, snapped) under viewport pixel (px, py) (bottom-left origin),
    or None over the background with no vertex near."""
    W, H = viewport
    if not (0 <= px < W and 0 <= py < H):
        return None
    scene = renderer.scene
    target = renderer.std(camera, viewport)
    found = target.texels(np.array([[px, py, 0]]), ids=True)
    oid, depth = int(found["id"][0]), float(found["depth"][0])
    view, proj = renderer.matrices(camera, viewport)
    m = proj @ view
    snapped = _snap(renderer, camera, m, viewport, px, py, oid if depth < 1.0 else -1)
    if snapped is not None:
        return snapped
    if oid < 0 or depth >= 1.0:
        return None
    return _unproject(m, W, H, px + 0.5, py + 0.5, depth) + scene.origin, oid, False


def _unproject(m: np.ndarray, W: int, H: int, x: float, y: float, depth: float) -> np.ndarray:
    p = np.linalg.solve(m, np.array([x / W * 2.0 - 1.0, y / H * 2.0 - 1.0, depth * 2.0 - 1.0, 1.0]))
    return p[:3] / p[3]


def _project(m: np.ndarray, W: int, H: int, points: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Window pixels (x, y, bottom-left origin) and a mask of the points in front of the camera."""
    clip = np.c_[points, np.ones(len(points))] @ m.T
    front = clip[:, 3] > 1e-12
    w = np.where(front, clip[:, 3], 1.0)
    xy = (clip[:, :2] / w[:, None] + 1.0) / 2.0 * np.array([W, H])
    return xy, front


def _snap(renderer: Renderer, camera: Camera, m: np.ndarray, viewport, px: int, py: int, oid: int):
    """The nearest shown vertex within SNAP_PX of the pixel, of the part hit or of the parts
    whose screen box is there; None when there is none."""
    scene, (W, H) = renderer.scene, viewport
    staging = renderer.staging  # an exploded view moves the parts; a section removes some whole
    hidden, corners = staging.staged(renderer.hidden_mask(), scene.box_corners("aabb"))  # relative to the origin
    xy, front = _project(m, W, H, corners.reshape(-1, 3))
    xy, front = xy.reshape(-1, 8, 2), front.reshape(-1, 8).all(axis=1)
    lo, hi = xy.min(axis=1) - SNAP_PX, xy.max(axis=1) + SNAP_PX
    near = front & (lo[:, 0] <= px) & (px <= hi[:, 0]) & (lo[:, 1] <= py) & (py <= hi[:, 1])
    if hidden is not None:
        near &= ~hidden
    ids = [oid] if oid >= 0 else []
    ids += [int(i) for i in np.flatnonzero(near) if i != oid][: MAX_CANDIDATES - len(ids)]
    if not ids:
        return None
    eye = np.asarray(camera.eye, np.float64) - scene.origin
    forward = np.asarray(camera.target, np.float64) - np.asarray(camera.eye, np.float64)
    forward /= np.linalg.norm(forward)
    best = None
    for o in ids:
        first, count = (int(v) for v in scene.index_ranges[o])
        verts = np.unique(scene.indices[first : first + count])
        pts = scene.positions[verts].astype(np.float64)
        if staging.offsets is not None:
            pts += staging.offsets[o]
        vxy, ok = _project(m, W, H, pts)
        dist = np.hypot(vxy[:, 0] - (px + 0.5), vxy[:, 1] - (py + 0.5))
        ok &= (dist <= SNAP_PX) & (vxy[:, 0] >= 0) & (vxy[:, 0] < W) & (vxy[:, 1] >= 0) & (vxy[:, 1] < H)
        for k in np.flatnonzero(ok)[np.argsort(dist[ok])][:8]:
            if best is not None and dist[k] >= best[0]:
                break
            if _shown(renderer, m, viewport, vxy[k], pts[k], eye, forward):
                best = (float(dist[k]), pts[k] + scene.origin, o)
                break
    return None if best is None else (best[1], best[2], True)


def _shown(renderer: Renderer, m: np.ndarray, viewport, xy: np.ndarray, p: np.ndarray, eye, forward) -> bool:
    """Whether vertex `p` (relative to the origin) is in view: no surface drawn in front of it."""
    W, H = viewport
    x, y = min(int(xy[0]), W - 1), min(int(xy[1]), H - 1)
    depth = float(renderer.single_target.texels(np.array([[x, y, 0]]), ids=False)["depth"][0])
    if depth >= 1.0:
        return True  # the background: a silhouette corner
    surface = _unproject(m, W, H, x + 0.5, y + 0.5, depth)
    t_surface, t_vertex = float((surface - eye) @ forward), float((p - eye) @ forward)
    return t_surface >= t_vertex - 2e-3 * max(t_vertex, 1e-9) - 1e-6 * renderer.scene.radius


def draw(dl, ruler: Ruler, m: np.ndarray, rect, origin: np.ndarray, unit: str, radius: float) -> None:
    """The measurements and a first point as lines and labels on draw list `dl`; `m` is the
    composite's projection @ view (of points relative to the scene's `origin`), `rect` the
    composite's window rectangle."""
    x0, y0, W, H = rect

    def screen(p):
        xy, ok = _project(m, W, H, (np.asarray(p, np.float64) - origin)[None])
        return (imgui.ImVec2(float(x0 + xy[0, 0]), float(y0 + H - xy[0, 1])), bool(ok[0]))

    for k, meas in enumerate(ruler.done):
        (a, ok_a), (b, ok_b) = screen(meas.a), screen(meas.b)
        if not (ok_a and ok_b):
            continue
        dl.add_line(a, b, LINE, 2.0)
        for p in (a, b):
            dl.add_circle_filled(p, 3.5, LINE)
        length, delta = describe(meas, unit, radius)
        text = f"#{k + 1}  {length}\n{delta}"
        size = imgui.calc_text_size(text)
        mid = imgui.ImVec2((a.x + b.x) / 2 + 6, (a.y + b.y) / 2 + 6)
        dl.add_rect_filled(mid, imgui.ImVec2(mid.x + size.x + 8, mid.y + size.y + 4), LABEL_BG, 3.0)
        dl.add_text(imgui.ImVec2(mid.x + 4, mid.y + 2), LABEL_TEXT, text)
    if ruler.first is not None:
        p, ok = screen(ruler.first[0])
        if ok:
            dl.add_circle_filled(p, 4.0, LINE)
