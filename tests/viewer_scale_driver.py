"""Drives the real viewer on a large generated assembly, for tests/test_viewer.py.

Run as `python tests/viewer_scale_driver.py OUT_DIR PARTS` with DISPLAY set (Xvfb). Writes
a PARTS-part GLB (rtta.scene.generators.assembly), opens it, then drags, turns the wheel, types into
the filter box, presses all / none / invert, click-picks an object on the composite and
draws one frame with an unclipped list far past moderngl-window's 65,536-vertex buffers.
Writes `result.json` (what happened, frame times, GL errors) and window screenshots.
"""

from __future__ import annotations

import json
import sys
import time
from pathlib import Path

import numpy as np
from imgui_bundle import imgui
from pyglet.window import key, mouse

from rtta.gl import glraw
from rtta.outputs import save_png
from rtta.scene.generators.assembly import write_assembly
from rtta.scene.loader import load_scene
from viewer import panels
from viewer.app import Viewer
from viewer.run import create_window

OUT, PARTS = Path(sys.argv[1]), int(sys.argv[2])
t0 = time.perf_counter()
scene = load_scene(write_assembly(OUT / "assembly.glb", PARTS))
result: dict = {"load_s": time.perf_counter() - t0, "objects": scene.count}
wnd = create_window((1280, 720))
app = Viewer(wnd, scene, screenshot_dir=OUT)
pw = wnd._window
errors: list[str] = []
frame_ms: dict[str, float] = {}


def frames(n: int = 1, label: str = "frame", shot: str | None = None) -> None:
    for i in range(n):
        t = time.perf_counter()
        app.frame()
        if shot and i == n - 1:
            save_png(OUT / f"{shot}.png", glraw.read_window(*wnd.buffer_size))
        wnd.swap_buffers()
        frame_ms[label] = max(frame_ms.get(label, 0.0), 1e3 * (time.perf_counter() - t))
        if app.ctx.error != "GL_NO_ERROR":
            errors.append(label)


def send(event: str, *args) -> None:
    pw.dispatch_event(event, *args)


def click(x: float, y: float, label: str) -> None:
    h = wnd.size[1]
    x, y = int(x), int(y)
    send("on_mouse_motion", x, h - y, 0, 0)
    frames(1, label)
    send("on_mouse_press", x, h - y, mouse.LEFT, 0)
    frames(1, label)
    send("on_mouse_release", x, h - y, mouse.LEFT, 0)
    frames(2, label)  # imgui takes queued input events a frame at a time


def press(symbol: int, label: str) -> None:
    send("on_key_press", symbol, 0)
    frames(1, label)
    send("on_key_release", symbol, 0)
    frames(1, label)


def centre(rect) -> tuple[float, float]:
    x0, y0, x1, y1 = rect
    return (x0 + x1) / 2, (y0 + y1) / 2


frames(3, "start", shot="start")
result["layout"] = {"panel": app.layout.panel, "composite": app.layout.composite, "atlas": app.layout.atlas}
result["visible"] = int(app.records.visible.sum())
cx, cy, cw, ch = app.layout.composite
az0 = app.orbit.az
app.state.navigation_fps = 240.0  # fast navigation over budget on any machine: parts are left out
send("on_mouse_press", cx + cw // 2, wnd.size[1] - (cy + ch // 2), mouse.LEFT, 0)
left, focus = [], set(range(0, PARTS, 97))
app.state.style.focus.update(focus)
for i in range(1, 6):
    send("on_mouse_drag", cx + cw // 2 + 20 * i, wnd.size[1] - (cy + ch // 2), 20, 0, mouse.LEFT, 0)
    frames(1, "drag")
    left.append(app.left_out)
in_view = app.renderer.parameterize(app.orbit.camera(), app.viewport).visible
result["moving_focus_packed"] = all(bool(app.records.visible[o]) for o in focus if in_view[o])
send("on_mouse_release", cx + cw // 2 + 100, wnd.size[1] - (cy + ch // 2), mouse.LEFT, 0)
frames(2, "drag", shot="dragged")  # the camera rests (the release frame may still move it): every part
result["drag_left_out"] = left
result["rest_left_out"] = app.left_out
full = app.renderer.parameterize(app.orbit.camera(), app.viewport)
result["rest_whole"] = bool((app.records.visible == full.visible).all())
app.state.style.focus.difference_update(focus)
app.state.navigation_fps = 10.0
result["dragged"] = app.orbit.az != az0
dist = app.orbit.dist
send("on_mouse_motion", cx + cw // 2, wnd.size[1] - (cy + ch // 2), 0, 0)
send("on_mouse_scroll", cx + cw // 2, wnd.size[1] - (cy + ch // 2), 0, 2)
frames(2, "wheel")
result["zoomed"] = app.orbit.dist < dist

click(*centre(app.item_rects[-1]), "filter")  # the filter box, then type into it
for ch_ in "part0001":
    send("on_text", ch_)
    frames(1, "typing")
press(key.ENTER, "typing")  # Enter: the filter box lets go of the keyboard
result["filter"] = app.state.filter
result["filtered"] = len(app.state.filtered())
click(*centre(app.item_rects[-2]), "all")
result["after_all"] = len(app.state.highlighted)
click(*centre(app.item_rects[-4]), "invert")
result["after_invert"] = len(app.state.highlighted)
click(*centre(app.item_rects[-1]), "filter")
for _ in "part0001":
    press(key.BACKSPACE, "typing")  # the filter empties: the list is everything again
press(key.ENTER, "typing")
result["filter_cleared"] = app.state.filter
click(*centre(app.item_rects[-2]), "all")
result["all_everything"] = len(app.state.highlighted)
frames(2, "all", shot="all")
click(*centre(app.item_rects[-3]), "none")
result["after_none"] = len(app.state.highlighted)

rec = app.records  # a click pick: the largest visible object's centre
area = np.prod(rec.viewport_rect[:, 2:] - rec.viewport_rect[:, :2], axis=1) * rec.visible
oid = int(np.argmax(area))
x0, y0, x1, y1 = rec.viewport_rect[oid]
px, py = cx + (x0 + x1) / 2, cy + ch - 1 - (y0 + y1) / 2
under = app.controls.object_at(px, py)
t = time.perf_counter()
click(px, py, "pick")
result["pick_ms"] = 1e3 * (time.perf_counter() - t)
result["picked"] = under
result["after_pick"] = sorted(app.state.highlighted)
frames(2, "picked", shot="picked")


def many_rects() -> None:
    """20,000 rectangles in one draw list: far more vertices than 65,536."""
    dl = imgui.get_foreground_draw_list()
    for i in range(20000):
        x, y = 300 + (i % 200) * 3, 100 + (i // 200) * 3
        dl.add_rect(imgui.ImVec2(x, y), imgui.ImVec2(x + 2, y + 2), 0xFF00FFFF, 0.0, 0, 1.0)


capacity = app.imgui.vertex_capacity
draw = panels.draw
panels.draw = lambda a: (draw(a), many_rects())
frames(2, "many_rects", shot="many_rects")
panels.draw = draw
result["capacity"] = [capacity, app.imgui.vertex_capacity]
frames(1, "end")
result["frame_ms"] = frame_ms
result["stages_ms"] = dict(app.stats.last_ms)
result["rects"] = {k: v for k, v in app.item_rects.items() if k < 0}
result["gl_errors"] = errors
app.release()
(OUT / "result.json").write_text(json.dumps(result, indent=1))
