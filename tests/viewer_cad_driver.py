"""Drives the real viewer window through the CAD basics (issue 45), for tests/test_viewer_cad.py.

Run as `python tests/viewer_cad_driver.py OUT_DIR` with DISPLAY set (Xvfb), from an empty
current folder, with XDG_PICTURES_DIR set: the first view (solid until a highlight), the view
cube, the measure tool on a generated box, a double-click on a focus part seen through the
context, saved views, screenshots, a tap on the panel, the splitter, the projection and the
wheel. Events go through the pyglet window's own dispatch, as in tests/viewer_driver.py.
Writes window screenshots (PNG) and `result.json`.
"""

from __future__ import annotations

import json
import sys
import time
from pathlib import Path

import numpy as np
from pyglet.window import key, mouse
from window_frames import Frames  # tests/ is this script's folder

from rtta.scene.generators.shapes import box
from rtta.scene.loader import load_scene_or_demo
from rtta.scene.model import from_meshes
from viewer import controls, gizmo, panel_view
from viewer.app import Viewer
from viewer.orbit import ZOOM_PER_STEP
from viewer.run import create_window

OUT = Path(sys.argv[1])
wnd = create_window((1280, 720))
demo = load_scene_or_demo(None)
app = Viewer(wnd, demo, views_dir=OUT / "views")  # screenshots: the default folder
frames = Frames(app, wnd, OUT)
send, errors = frames.send, frames.errors
result: dict = {"screenshot_dir": str(app.screenshot_dir)}


def click(x: float, y: float, between: bool = True) -> None:
    """Press and release at window point (x, y) (top-left origin): a frame between them, or
    none (a tap: both before the same frame)."""
    h = wnd.size[1]
    x, y = int(round(x)), int(round(y))
    send("on_mouse_motion", x, h - y, 0, 0)
    frames()
    send("on_mouse_press", x, h - y, mouse.LEFT, 0)
    if between:
        frames()
    send("on_mouse_release", x, h - y, mouse.LEFT, 0)
    frames()


def press_key(symbol: int, modifiers: int = 0) -> None:
    send("on_key_press", symbol, modifiers)
    send("on_key_release", symbol, modifiers)
    frames()


def settle() -> None:
    """Frames until a view turn has arrived."""
    for _ in range(200):
        if app.turn is None:
            break
        frames()
    frames(2)


def forward() -> list[float]:
    cam = app.orbit.camera()
    d = np.asarray(cam.target, float) - np.asarray(cam.eye, float)
    return (d / np.linalg.norm(d)).tolist()


def to_window(points) -> np.ndarray:
    """World points -> window points (top-left origin) in the composite."""
    cx, cy, cw, ch = app.layout.composite
    view, proj = app.renderer.matrices(app.orbit.camera(), app.viewport)
    p = np.c_[np.asarray(points, float) - app.renderer.scene.origin, np.ones(len(points))] @ (proj @ view).T
    ndc = p[:, :2] / p[:, 3:4]
    return np.c_[cx + (ndc[:, 0] + 1) / 2 * cw, cy + ch - (ndc[:, 1] + 1) / 2 * ch]


# 1. first contact: the demo opens solid; a highlight brings the ghosted mode
frames(3, shot="start")
names = demo.names
result["layout"] = {k: list(getattr(app.layout, k)) for k in ("panel", "composite", "atlas")}
result["first_shown"] = app.state.shown_mode()
result["first_mode"] = app.state.mode

# 2. a tap on the caliper's checkbox in the panel (press and release before one frame)
caliper = names.index("caliper")
app.state.reveal(caliper)  # its row scrolled into the tree's view
frames(2)
x0, y0, x1, y1 = app.item_rects[caliper]
click(x0 + 8, (y0 + y1) / 2, between=False)
frames(2, shot="tapped")
result["focus_after_tap"] = sorted(app.state.highlighted)
result["shown_after_tap"] = app.state.shown_mode()

# 3. double-click on a focus part seen through the context: it stays in focus and is fitted
piston = names.index("piston_1")
app.state.select("none")
app.state.toggle(piston)
frames(2)
rx0, ry0, rx1, ry1 = app.records.viewport_rect[piston]
cx, cy, cw, ch = app.layout.composite
px, py = cx + (rx0 + rx1) / 2, cy + ch - 1 - (ry0 + ry1) / 2
result["front_at_piston"] = app.controls.object_at(px, py, front_most=True)
dist_before = app.orbit.dist
controls.DOUBLE_CLICK_S = 30.0  # llvmpipe on a loaded machine: a frame between the clicks may take long
h = wnd.size[1]
send("on_mouse_motion", int(px), h - int(py), 0, 0)
frames()
for _ in range(2):
    send("on_mouse_press", int(px), h - int(py), mouse.LEFT, 0)
    send("on_mouse_release", int(px), h - int(py), mouse.LEFT, 0)
    frames()
frames(2, shot="double_clicked")
controls.DOUBLE_CLICK_S = 0.35
centre = (demo.aabb_min[piston] + demo.aabb_max[piston]) / 2
result["double"] = {
    "piston": piston,
    "focus": sorted(app.state.highlighted),
    "target_error": float(np.linalg.norm(app.orbit.target - centre)),
    "closer": app.orbit.dist < dist_before,
}

# 4. saved views: save, change everything, restore: the same composite
app.state.style.focus.clear()
app.state.toggle(names.index("hub"))
app.orbit.az += 30
frames(3, shot="view_saved")
panel_view.save(app, "my view")
result["views_after_save"] = app.views.names()
app.state.toggle(names.index("rotor"))
app.orbit.az += 50
press_key(key._5)
frames(2, shot="view_changed")
panel_view.restore(app, "my_view")
frames(3, shot="view_restored")
result["restored_message"] = app.message

# 5. screenshots (F12): into the user's pictures folder, none into the current one
press_key(key.F12)
result["screenshot_message"] = app.message
result["pictures"] = sorted(p.name for p in app.screenshot_dir.glob("*.png"))
result["cwd_files"] = sorted(p.name for p in Path.cwd().iterdir())

# 6. the splitter: dragging the panel's edge widens it
edge, y = app.layout.panel[2], 400
send("on_mouse_press", edge, h - y, mouse.LEFT, 0)
for k in range(1, 5):
    send("on_mouse_drag", edge + 25 * k, h - y, 25, 0, mouse.LEFT, 0)
    frames()
send("on_mouse_release", edge + 100, h - y, mouse.LEFT, 0)
frames(2, shot="wide_panel")
result["panel_widths"] = [edge, app.layout.panel[2]]

# 7. a box, Z up, in mm: the view cube's top face, the wheel, the projection, a measurement
cube = box(2.0)
scene = from_meshes([("box", np.asarray(cube.vertices), np.asarray(cube.faces), None)], source="box.obj")
scene.up_axis, scene.unit = "z", "mm"
app.set_scene(scene)
frames(3, shot="box")
top = [q for _, d, q in gizmo.cells(app.layout.composite, app.orbit) if d == (0, 1, 0)]
result["top_face_shown"] = bool(top)
if top:
    click(*top[0].mean(axis=0))
    settle()
result["after_top"] = {"forward": forward(), "az": app.orbit.az, "el": app.orbit.el}
frames(1, shot="top_view")
press_key(key._0)  # iso
settle()
cx, cy, cw, ch = app.layout.composite  # a turn under way (held at its start), then a drag: the drag wins
app.turn = gizmo.Turn(app.orbit.az, app.orbit.el, 0.0, 0.0, time.perf_counter() + 1e3)
send("on_mouse_motion", cx + cw // 2, h - (cy + ch // 2), 0, 0)
frames()
send("on_mouse_press", cx + cw // 2, h - (cy + ch // 2), mouse.LEFT, 0)
for k in range(1, 3):
    send("on_mouse_drag", cx + cw // 2 + 5 * k, h - (cy + ch // 2), 5, 0, mouse.LEFT, 0)
    frames()  # the window's events are handled in the frame
result["turn_after_drag"] = app.turn is None
send("on_mouse_release", cx + cw // 2 + 10, h - (cy + ch // 2), mouse.LEFT, 0)
press_key(key._0)
settle()
cx, cy, cw, ch = app.layout.composite
dist = app.orbit.dist
send("on_mouse_motion", cx + cw // 2, h - (cy + ch // 2), 0, 0)
send("on_mouse_scroll", cx + cw // 2, h - (cy + ch // 2), 0, 1)
frames()
result["wheel_ratio"] = app.orbit.dist / dist
result["zoom_per_step"] = ZOOM_PER_STEP
app.frame_objects()
press_key(key._5)
result["projection"] = app.orbit.projection
frames(2, shot="box_ortho")
press_key(key._5)
frames(2)
corners = np.array([[x, y, z] for x in (-1, 1) for y in (-1, 1) for z in (-1, 1)], float)
eye = -np.asarray(forward())
near = corners[np.argmax(corners @ eye)]
other = near.copy()
other[2] = -other[2]  # the edge along z from the corner nearest the eye
a, b = to_window([near, other])
press_key(key.R)
result["ruler_on"] = app.ruler.on
click(a[0] + 3, a[1] - 2)  # a few pixels off: the vertex snaps
click(b[0] - 2, b[1] + 3)
frames(2, shot="measured")
m = app.ruler.done[-1] if app.ruler.done else None
result["measure"] = {
    "count": len(app.ruler.done),
    "distance": m.distance if m else None,
    "delta": m.delta.tolist() if m else None,
    "a": m.a.tolist() if m else None,
    "expect_a": near.tolist(),
    "message": app.message,
}
send("on_mouse_press", cx + cw // 2, h - (cy + ch // 2), mouse.LEFT, 0)  # orbit: the line stays on the edge
for k in range(1, 6):
    send("on_mouse_drag", cx + cw // 2 + 10 * k, h - (cy + ch // 2), 10, 0, mouse.LEFT, 0)
    frames()
send("on_mouse_release", cx + cw // 2 + 50, h - (cy + ch // 2), mouse.LEFT, 0)
frames(2, shot="measured_orbited")
result["measure_after_orbit"] = len(app.ruler.done)
press_key(key.ESCAPE)  # no first point pending: the tool ends, the measurements stay
result["ruler_after_esc"] = [app.ruler.on, len(app.ruler.done)]
total, stages = app.stats.rendered or (0.0, {})
result["stats"] = {
    "moving_frames": len(app.stats.moving_ms),
    "rest_frames": len(app.stats.rest_ms),
    "rendered_ms": total,
    "stages": stages,
}
result["gl_errors"] = errors
app.release()
(OUT / "result.json").write_text(json.dumps(result, indent=1))
