"""Drives the real viewer window with synthetic input, for tests/test_viewer.py.

Run as `python tests/viewer_driver.py OUT_DIR` with DISPLAY set (Xvfb). Events go through
the pyglet window's own event dispatch (the handlers moderngl-window installed), so the
viewer sees exactly what a user's mouse and keyboard would give. Writes window
screenshots (PNG) and `result.json` with what the test checks.
"""

from __future__ import annotations

import json
import os
import sys
from pathlib import Path

from pyglet.window import key, mouse
from window_frames import Frames  # tests/ is this script's folder

from rtta.scene.loader import load_scene_or_demo
from viewer.app import Viewer
from viewer.run import create_window

OUT = Path(sys.argv[1])
wnd = create_window((1280, 720))
app = Viewer(wnd, load_scene_or_demo(None), screenshot_dir=OUT)
pw = wnd._window  # the pyglet window
frames = Frames(app, wnd, OUT)
send, errors = frames.send, frames.errors


def click(x: int, y: int, button: int = mouse.LEFT, modifiers: int = 0) -> None:
    """Press and release at window point (x, y) (top-left origin), a frame between each."""
    h = wnd.size[1]
    send("on_mouse_motion", x, h - y, 0, 0)
    frames()
    send("on_mouse_press", x, h - y, button, modifiers)
    frames()
    send("on_mouse_release", x, h - y, button, modifiers)
    frames()


def drag(x: int, y: int, dx: int, dy: int, button: int = mouse.LEFT, steps: int = 10) -> None:
    h = wnd.size[1]
    send("on_mouse_press", x, h - y, button, 0)
    for i in range(1, steps + 1):
        send("on_mouse_drag", x + dx * i // steps, h - (y + dy * i // steps), dx // steps, -(dy // steps), button, 0)
        frames()
    send("on_mouse_release", x + dx, h - (y + dy), button, 0)
    frames()


def composite_point(oid: int) -> tuple[int, int]:
    """Window point at the centre of an object's projected bounds."""
    x0, y0, x1, y1 = app.records.viewport_rect[oid]
    cx, cy, _, ch = app.layout.composite
    return int(cx + (x0 + x1) / 2), int(cy + ch - 1 - (y0 + y1) / 2)


result: dict = {"renderer": app.ctx.info["GL_RENDERER"]}
frames(3, shot="start")
result["layout"] = {"panel": app.layout.panel, "composite": app.layout.composite, "atlas": app.layout.atlas}
result["az0"] = app.orbit.az

cx, cy, cw, ch = app.layout.composite
drag(cx + cw // 2, cy + ch // 2, 120, 40)
frames(2, shot="dragged")
result["az1"], result["el1"] = app.orbit.az, app.orbit.el

names = app.renderer.scene.names
target = names.index("caliper_body") if "caliper_body" in names else 0
x0, y0, x1, y1 = app.item_rects[target]
click(int(x0 + 8), int((y0 + y1) / 2))  # the object's checkbox in the panel
frames(2, shot="highlight")
result["focus_after_checkbox"] = sorted(app.state.highlighted)
result["checkbox_target"] = target

# picking: the hidden piston behind the caliper, in ghosted-ao, seen through the context
piston = names.index("piston_1")
app.state.select("none")
app.state.toggle(piston)
frames(2)
px, py = composite_point(piston)
result["front_most_at_piston"] = app.controls.object_at(px, py, front_most=True)
click(px, py)  # prefers the highlighted piston -> off
result["focus_after_pick"] = sorted(app.state.highlighted)
result["picked"] = piston
wheel_dist = app.orbit.dist
send("on_mouse_motion", px, wnd.size[1] - py, 0, 0)
send("on_mouse_scroll", px, wnd.size[1] - py, 0, 2)
frames(2)
result["zoomed"] = app.orbit.dist < wheel_dist

keys_seen = {}
for name, symbol in (("right", key.RIGHT), ("zoom_in", key.EQUAL), ("frame", key.F), ("atlas", key.A), ("mode", key.M)):
    before = (app.orbit.az, app.orbit.dist, app.state.show_atlas, app.state.mode)
    send("on_key_press", symbol, 0)
    send("on_key_release", symbol, 0)
    frames()
    keys_seen[name] = before != (app.orbit.az, app.orbit.dist, app.state.show_atlas, app.state.mode)
result["keys_changed"] = keys_seen
frames(2, shot="keys")
send("on_key_press", key.A, 0)
send("on_key_press", key.M, 0)
send("on_key_press", key.M, 0)
send("on_key_press", key.M, 0)
send("on_key_press", key.M, 0)  # five modes: back to ghosted-ao, atlas shown again
frames()
result["mode_after_cycle"] = app.state.mode
send("on_key_press", key.F12, 0)
send("on_key_press", key.F12, 0)  # a second screenshot: new names, nothing overwritten
frames()
result["screenshots"] = sorted(p.name for p in OUT.glob("rtta-*.png"))

frames(2, shot="unpainted")  # the projector: P on, then Ctrl+Right moves it
send("on_key_press", key.P, 0)
frames(2, shot="painted")
send("on_key_press", key.RIGHT, key.MOD_CTRL)
frames(2, shot="projector_moved")
result["projector"] = {
    "on": app.state.projector.on,
    "attached": app.state.projector.attached,
    "az": app.state.projector.az,
}
send("on_key_press", key.P, 0)
frames(1)

app.state.style.context_opacity = 0.7  # the lens: C on (ghosted-ao), then it follows the mouse
frames(2, shot="no_lens")
send("on_key_press", key.C, 0)
cx, cy, cw, ch = app.layout.composite
send("on_mouse_motion", cx + cw // 2, wnd.size[1] - (cy + ch // 2), 0, 0)
frames(2, shot="lens")
result["lens_center_1"] = app.state.lens.center
send("on_mouse_motion", cx + cw // 4, wnd.size[1] - (cy + ch // 3), 0, 0)
frames(2, shot="lens_moved")
result["lens_center_2"] = app.state.lens.center
send("on_key_press", key.C, 0)
app.state.style.context_opacity = 0.3
frames(1)

bad = OUT / "broken.glb"
bad.write_bytes(b"glTF\x02\x00\x00\x00garbage")
before = app.renderer.scene
result["open_bad"] = app.open_scene(bad)
result["scene_kept"] = app.renderer.scene is before
result["message"] = app.message
frames(2, shot="error")

# a large file opened the way the file browser and drag-and-drop open it: on a worker
# thread, the window drawing meanwhile; then a broken one the same way
import time  # noqa: E402

from rtta.scene.generators.assembly import write_assembly  # noqa: E402

big = write_assembly(OUT / "later.glb", 10_000)
later = {}
send("on_file_drop", 10, 10, [str(big)])
frames(1)  # the window's events are handled in the frame
later["message_at_start"] = app.message
app.open_scene_later(bad)  # a second file while the first loads: refused
later["second_refused"] = app.message_is_error and "still loading" in app.message
drawn, t0 = 0, time.perf_counter()
while app.loading is not None and time.perf_counter() - t0 < 300:
    frames(1, shot="loading" if drawn == 3 else None)
    drawn += 1
frames(1)
later.update(
    frames_while_loading=drawn, count=app.renderer.scene.count, message=app.message, error=app.message_is_error
)
loaded = app.renderer.scene
app.open_scene_later(bad)
while app.loading is not None and time.perf_counter() - t0 < 300:
    frames(1)
frames(1)
later.update(bad_error=app.message_is_error, bad_message=app.message, bad_kept=app.renderer.scene is loaded)
result["later"] = later
app.set_scene(before)
frames(1)

from bad_inputs import make_corpus  # noqa: E402  (tests/ is this script's folder)

corpus = OUT / "corpus"
corpus.mkdir()
os.environ["RTTA_MEMORY_LIMIT_MB"] = "1"  # the too-large cases exceed it
result["corpus"] = {}
for case in make_corpus(corpus):
    opened = app.open_scene(case.path)
    result["corpus"][case.name] = {
        "opened": opened,
        "error": app.message_is_error,
        "message": app.message,
        "kept": app.renderer.scene is before,
        "expect_error": case.error,
        "says": case.says,
        "path": str(case.path),
    }
    if opened:  # a case that loads replaces the scene: put the demo back
        app.set_scene(before)
    frames(1)

from rtta.passes import oit  # noqa: E402

kept, oit.MAX_NODES = oit.MAX_NODES, 10  # a view whose pixel order falls back: said in the panel
mode, app.state.mode = app.state.mode, "transparent"
frames(2)
result["fallback"] = {"message": app.message, "error": app.message_is_error, "warnings": app.renderer.warnings}
oit.MAX_NODES, app.state.mode = kept, mode
frames(1)

app.screenshot_dir = OUT / "no" / "such" / "folder"  # a screenshot that cannot be written: one line
result["screenshot_bad_dir"] = {
    "written": [str(p) for p in app.screenshot()],
    "message": app.message,
    "error": app.message_is_error,
}
app.screenshot_dir = OUT

for size in ((640, 400), (0, 0), (1, 1), (2600, 1500), (1280, 720)):
    if 0 in size:
        send("on_resize", *size)  # minimized: what the window system reports
    else:
        pw.set_size(*size)  # a real resize, seen through the event queue
        pw.dispatch_events()
    frames(2)
result["after_resize"] = list(wnd.buffer_size)
frames(2, shot="end")
result["gl_errors"] = errors
app.release()
(OUT / "result.json").write_text(json.dumps(result, indent=1))
