"""The viewer's cutaway and exploded view: one section plane, along an axis or through a picked
surface point with its normal, flipped and toggled, its caps and scope; the explode factor and
scope (the flags of `rtta snapshot`: rtta.renderer.placing), as state the side panel edits
(`panel`) and the capture reads (`CutawayState.staging`). `reset` clears sections, explode,
lens and hide/isolate at once; the panel lists which of them are active."""

from __future__ import annotations

import time
from dataclasses import dataclass
from typing import TYPE_CHECKING, Literal, get_args

import numpy as np

from rtta.renderer.placing import Staging, make_staging
from rtta.scene.cutaway import CAPS, SECTION_SCOPES, Caps, SectionScope
from rtta.scene.explode import EXPLODE_MAX, EXPLODE_SCOPES, ExplodeScope

if TYPE_CHECKING:
    from rtta.scene.model import Scene

Axis = Literal["off", "x", "y", "z", "-x", "-y", "-z"]
AXES: tuple[Axis, ...] = get_args(Axis)
EXPLODE_ANIM_S = 0.8  # an animated explode opens or closes in this many seconds
_FLIPPED: dict[Axis, Axis] = {"off": "off", "x": "-x", "y": "-y", "z": "-z", "-x": "x", "-y": "y", "-z": "z"}


@dataclass
class CutawayState:
    """One section plane: along an axis (`axis`: remove what lies beyond `at` on x/y/z, or below
    it on -x...; `at` runs over the scene's bounds from 0 to 1) or, with `normal` set, the plane
    normal·p = `offset` (world; what lies on the normal's side is removed); `enabled` toggles it
    without losing it; `picking`: the next click in the composite places it on the surface
    there. Its caps and scope; explode and its scope."""

    axis: Axis = "off"
    at: float = 0.5
    caps: Caps = "solid"
    scope: SectionScope = "all"
    explode: float = 0.0
    explode_scope: ExplodeScope = "all"
    normal: tuple[float, float, float] | None = None
    offset: float = 0.0
    enabled: bool = True
    picking: bool = False
    show_quad: bool = True  # the plane drawn on the composite, with its handle
    dragging: bool = False  # the handle is being dragged
    explode_open: float = 1.0  # the factor an animated explode opens to (the slider's last non-zero)
    anim: tuple[float, float, float] | None = None  # an explode under way: (start, from, to)

    def key(self) -> tuple:
        """Changes whenever the capture must run again."""
        return (self.axis, self.at, self.caps, self.scope, self.explode, self.explode_scope) + (
            self.normal,
            self.offset,
            self.enabled,
        )

    @property
    def has_plane(self) -> bool:
        return self.normal is not None or self.axis != "off"

    def spec(self, scene: Scene) -> str | None:
        """The plane as `--section` takes it (world units), or None without one (or toggled off)."""
        if not self.enabled or not self.has_plane:
            return None
        if self.normal is not None:
            return ",".join(f"{float(v):.9g}" for v in (*self.normal, self.offset))
        lo, hi = scene.bounds
        k = "xyz".index(self.axis[-1])
        return f"{self.axis}={float(lo[k] + self.at * (hi[k] - lo[k])):.9g}"

    def animate_explode(self) -> None:
        """Open the explode to `explode_open` (closed now) or close it, over EXPLODE_ANIM_S."""
        to = 0.0 if self.explode > 0 and (self.anim is None or self.anim[2] > 0) else self.explode_open
        self.anim = (time.perf_counter(), self.explode, to)

    def tick(self, now: float | None = None) -> None:
        """Advance an animated explode (smoothstep in time) to `now`."""
        if self.anim is None:
            return
        t0, a, b = self.anim
        t = ((time.perf_counter() if now is None else now) - t0) / EXPLODE_ANIM_S
        if t >= 1.0:
            self.explode, self.anim = b, None
        else:
            t = max(t, 0.0)
            self.explode = float(a + (b - a) * t * t * (3 - 2 * t))

    def staging(self, scene: Scene) -> Staging:
        """The renderer's Staging of this state (an animated explode advanced to now)."""
        self.tick()
        spec = self.spec(scene)
        return make_staging([spec] if spec else [], self.caps, self.scope, self.explode, self.explode_scope)

    def flip(self) -> None:
        """Keep the other side of the plane (the same plane)."""
        if self.normal is not None:
            self.normal = (-self.normal[0], -self.normal[1], -self.normal[2])
            self.offset = -self.offset
        else:
            self.axis = _FLIPPED[self.axis]

    def set_plane(self, point, normal) -> None:
        """The plane through world `point` with `normal` (what lies on the normal's side goes)."""
        n = np.asarray(normal, np.float64)
        n = n / np.linalg.norm(n)
        self.normal = (float(n[0]), float(n[1]), float(n[2]))
        self.offset = float(np.dot(n, np.asarray(point, np.float64)))
        self.enabled, self.picking = True, False

    def plane(self, scene: Scene) -> tuple[np.ndarray, float] | None:
        """(unit normal, offset) of the plane in world coordinates, None without one."""
        if self.normal is not None:
            return np.asarray(self.normal, np.float64), self.offset
        if self.axis == "off":
            return None
        lo, hi = scene.bounds
        k = "xyz".index(self.axis[-1])
        sign = -1.0 if self.axis[0] == "-" else 1.0
        n = np.zeros(3)
        n[k] = sign
        return n, sign * float(lo[k] + self.at * (hi[k] - lo[k]))

    def move(self, scene: Scene, distance: float) -> None:
        """Move the plane `distance` world units along its normal (the removed side)."""
        if self.normal is not None:
            self.offset += float(distance)
            return
        if self.axis == "off":
            return
        lo, hi = scene.bounds
        k = "xyz".index(self.axis[-1])
        sign = -1.0 if self.axis[0] == "-" else 1.0
        self.at = float(np.clip(self.at + sign * distance / max(float(hi[k] - lo[k]), 1e-30), 0.0, 1.0))


NO_SURFACE = "section: no surface there"
HANDLE_PX = 9.0  # the handle's radius on screen (a press within it drags the plane)
QUAD_FILL, QUAD_EDGE, HANDLE = 0x28E0A040, 0xC0E0A040, 0xF040C0F0  # ABGR: translucent amber, cyan


def quad(scene: Scene, c: CutawayState) -> tuple[np.ndarray, np.ndarray, np.ndarray] | None:
    """(corners [4, 3], centre, normal) in world of the plane as a square sized to the scene's
    bounds (centred where the bounds' centre projects on it), None without a shown plane."""
    found = c.plane(scene) if c.enabled else None
    if found is None:
        return None
    n, d = found
    lo, hi = (np.asarray(b, np.float64) for b in scene.bounds)
    mid = (lo + hi) / 2
    centre = mid - (float(n @ mid) - d) * n
    u = np.cross(n, [1.0, 0.0, 0.0] if abs(n[0]) < 0.9 else [0.0, 1.0, 0.0])
    u /= np.linalg.norm(u)
    v = np.cross(n, u)
    r = 0.5 * float(np.linalg.norm(hi - lo)) or 1.0
    corners = np.array([centre + r * (a * u + b * v) for a, b in ((-1, -1), (1, -1), (1, 1), (-1, 1))])
    return corners, centre, n


def _screen(app, points) -> tuple[np.ndarray, bool]:
    """World points -> window points (top-left origin) in the composite; all in front?"""
    x0, y0, W, H = app.layout.composite
    view, proj = app.renderer.matrices(app.orbit.camera(), (max(W, 1), max(H, 1)))
    clip = np.c_[np.asarray(points, np.float64) - app.renderer.scene.origin, np.ones(len(points))] @ (proj @ view).T
    front = bool((clip[:, 3] > 1e-12).all())
    ndc = clip[:, :2] / np.where(clip[:, 3:4] > 1e-12, clip[:, 3:4], 1.0)
    return np.c_[x0 + (ndc[:, 0] + 1) / 2 * W, y0 + H - (ndc[:, 1] + 1) / 2 * H], front


def handle(app) -> tuple[np.ndarray, np.ndarray] | None:
    """(the handle's window point, window pixels per world unit along the normal), or None."""
    c: CutawayState = app.state.cutaway
    found = quad(app.renderer.scene, c) if c.show_quad else None
    if found is None:
        return None
    _, centre, n = found
    step = 0.01 * float(app.renderer.scene.radius) or 1e-3
    xy, front = _screen(app, [centre, centre + step * n])
    if not front:
        return None
    return xy[0], (xy[1] - xy[0]) / step


def draw(dl, app) -> None:
    """The plane as a translucent quad over the composite, its handle and normal."""
    from imgui_bundle import imgui

    c: CutawayState = app.state.cutaway
    found = quad(app.renderer.scene, c) if c.show_quad else None
    if found is None or app.layout.composite[2] <= 0:
        return
    corners, centre, n = found
    xy, front = _screen(app, np.r_[corners, [centre, centre + 0.25 * float(app.renderer.scene.radius) * n]])
    if not front:
        return
    p = [imgui.ImVec2(float(a), float(b)) for a, b in xy]
    x0, y0, W, H = app.layout.composite
    dl.push_clip_rect(imgui.ImVec2(x0, y0), imgui.ImVec2(x0 + W, y0 + H), False)  # not over the atlas
    dl.add_quad_filled(p[0], p[1], p[2], p[3], QUAD_FILL)
    dl.add_quad(p[0], p[1], p[2], p[3], QUAD_EDGE, 1.5)
    dl.add_line(p[4], p[5], HANDLE, 2.0)
    dl.add_circle_filled(p[4], HANDLE_PX if not c.dragging else HANDLE_PX + 2, HANDLE)
    dl.pop_clip_rect()


def grab(app, x: float, y: float) -> bool:
    """A press at window point (x, y) on the handle starts a drag of the plane."""
    found = handle(app)
    c: CutawayState = app.state.cutaway
    c.dragging = found is not None and float(np.hypot(x - found[0][0], y - found[0][1])) <= HANDLE_PX + 2
    return c.dragging


def drag(app, dx: float, dy: float) -> None:
    """Move the plane along its normal by the mouse motion along the normal's screen direction."""
    found = handle(app)
    if found is None:
        return
    per_unit = found[1]
    length2 = float(per_unit @ per_unit)
    if length2 < 1e-12:  # the normal points at the camera: up moves it away
        distance = -dy * float(app.renderer.scene.radius) / max(app.layout.composite[3], 1)
    else:
        distance = float(np.array([dx, dy]) @ per_unit) / length2
    app.state.cutaway.move(app.renderer.scene, distance)


def surface_plane(app, x: float, y: float) -> tuple[np.ndarray, np.ndarray] | None:
    """(world point, unit normal towards the camera) of the surface under window point (x, y),
    from the std pass's depth there and at two neighbouring pixels; None over the background."""
    cx, cy, cw, ch = app.layout.composite
    px, py = int(x - cx), int(cy + ch - 1 - y)
    W, H = app.viewport
    if not (0 <= px < W - 1 and 0 <= py < H - 1):
        return None
    r, camera = app.renderer, app.orbit.camera()
    target = r.std(camera, app.viewport)
    texels = np.array([[px, py, 0], [px + 1, py, 0], [px, py + 1, 0]])
    found = target.texels(texels, ids=True)
    ids, depth = np.asarray(found["id"]), np.asarray(found["depth"], np.float64)
    if ids[0] < 0 or depth[0] >= 1.0:
        return None
    view, proj = r.matrices(camera, app.viewport)
    inv = np.linalg.inv(proj @ view)
    ndc = np.c_[(texels[:, 0] + 0.5) / W * 2 - 1, (texels[:, 1] + 0.5) / H * 2 - 1, depth * 2 - 1, np.ones(3)]
    p = ndc @ inv.T
    p = p[:, :3] / p[:, 3:4] + r.scene.origin
    n = np.cross(p[1] - p[0], p[2] - p[0])
    same = (ids == ids[0]) & (depth < 1.0)
    if not same.all() or not np.isfinite(n).all() or np.linalg.norm(n) == 0:  # an edge: face the camera
        n = np.asarray(camera.eye, np.float64) - np.asarray(camera.target, np.float64)
    n = n / np.linalg.norm(n)
    if np.dot(n, np.asarray(camera.eye, np.float64) - p[0]) < 0:
        n = -n
    return p[0], n


def place_at(app, x: float, y: float) -> bool:
    """The click of `picking`: the plane through the surface point there, its normal towards the
    camera (what lies in front of the surface is cut away). False over the background."""
    found = surface_plane(app, x, y)
    c: CutawayState = app.state.cutaway
    c.picking = False
    if found is None:
        app.say(NO_SURFACE, error=True)
        return False
    if app.message == NO_SURFACE:  # a miss before: no longer so
        app.say("")
    c.set_plane(*found)
    return True


def active(app) -> list[str]:
    """What `reset` would clear: the section, explode, the lens, hidden parts."""
    s = app.state
    out = []
    if s.cutaway.has_plane and s.cutaway.enabled:
        out.append("section")
    if s.cutaway.explode > 0:
        out.append(f"explode {s.cutaway.explode:.2f}")
    if s.lens.on:
        out.append("lens")
    if s.hidden:
        out.append(f"{len(s.hidden)} hidden")
    return out


def reset(app) -> None:
    """Sections, explode, lens and hide/isolate back to none, at one click."""
    s = app.state
    c = s.cutaway
    c.axis, c.normal, c.enabled, c.picking, c.explode, c.anim = "off", None, True, False, 0.0, None
    s.lens.on = False
    if s.hidden:
        s.show_all()


def panel(app) -> None:
    """The side panel's cutaway section (a function of the app, as viewer.panels' sections)."""
    from imgui_bundle import imgui

    c: CutawayState = app.state.cutaway
    if not imgui.collapsing_header("cutaway and explode"):
        return
    on = active(app)
    imgui.text_disabled("active: " + (", ".join(on) if on else "none"))
    if on:
        imgui.same_line()
        if imgui.small_button("reset all"):
            reset(app)
    items = list(AXES) + ([] if c.normal is None else ["on a surface"])
    changed, i = imgui.combo("section plane", AXES.index(c.axis) if c.normal is None else len(AXES), items)
    if changed and i < len(AXES):
        c.axis, c.normal, c.enabled = AXES[i], None, True
    if imgui.small_button("on a surface (then click it)" if not c.picking else "click a surface..."):
        c.picking = not c.picking
    if c.has_plane:
        imgui.same_line()
        if imgui.small_button("flip (X)"):
            c.flip()
        _, c.enabled = imgui.checkbox("on", c.enabled)
        imgui.same_line()
        _, c.show_quad = imgui.checkbox("show the plane (drag its handle)", c.show_quad)
        if c.normal is None:
            _, c.at = imgui.slider_float("at (of the bounds)", c.at, 0.0, 1.0)
        else:
            radius = float(app.renderer.scene.radius)
            _, c.offset = imgui.drag_float("offset", c.offset, radius / 200.0)
        changed, i = imgui.combo("caps", CAPS.index(c.caps), list(CAPS))
        if changed:
            c.caps = CAPS[i]
        changed, i = imgui.combo("section scope", SECTION_SCOPES.index(c.scope), list(SECTION_SCOPES))
        if changed:
            c.scope = SECTION_SCOPES[i]
        imgui.text_disabled(c.spec(app.renderer.scene) or "(off)")
    changed, c.explode = imgui.slider_float("explode", c.explode, 0.0, EXPLODE_MAX)
    if changed:
        c.anim = None  # the slider takes it from an animation
        c.explode_open = c.explode if c.explode > 0 else c.explode_open
    changed, i = imgui.combo("explode scope", EXPLODE_SCOPES.index(c.explode_scope), list(EXPLODE_SCOPES))
    if changed:
        c.explode_scope = EXPLODE_SCOPES[i]
    if imgui.small_button("animate the explode (E)"):
        c.animate_explode()
