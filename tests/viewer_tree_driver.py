"""Drives the viewer on a part tree (an IFC house the test writes) with synthetic input, for
tests/test_tree_viewer.py: group checkboxes, hide / isolate / show all, hover outlines, a
click revealing its row, and framing at composite aspects 0.5, 1 and 2 (the engine from
../shared/data too when it is there). Run as `python tests/viewer_tree_driver.py OUT_DIR`."""

from __future__ import annotations

import json
import sys
from pathlib import Path

import numpy as np
from assemblies import write_ifc
from pyglet.window import mouse

from rtta.gl import glraw
from rtta.outputs import save_png
from rtta.scene.loader import load_scene
from rtta.scene.model import Scene
from viewer.app import Viewer
from viewer.run import create_window
from viewer.views import PANEL_WIDTH

OUT = Path(sys.argv[1])
ENGINE = Path(__file__).resolve().parents[2] / "shared" / "data" / "engine_2cyl.glb"
write_ifc(OUT / "house.ifc")
house = load_scene(OUT / "house.ifc")
wnd = create_window((1280, 720))
app = Viewer(wnd, house, screenshot_dir=OUT)
pw = wnd._window
errors: list[str] = []
result: dict = {}


def frames(n: int = 1, shot: str | None = None) -> np.ndarray | None:
    img = None
    for i in range(n):
        app.frame()
        if shot and i == n - 1:
            img = glraw.read_window(*wnd.buffer_size)
            save_png(OUT / f"{shot}.png", img)
        wnd.swap_buffers()
        if app.ctx.error != "GL_NO_ERROR":
            errors.append(f"after {shot or 'frame'}")
    return img


def move(x: float, y: float) -> None:
    pw.dispatch_event("on_mouse_motion", int(x), wnd.size[1] - int(y), 0, 0)
    frames()


def click(x: float, y: float, button: int = mouse.LEFT) -> None:
    h = wnd.size[1]
    move(x, y)
    pw.dispatch_event("on_mouse_press", int(x), h - int(y), button, 0)
    frames()
    pw.dispatch_event("on_mouse_release", int(x), h - int(y), button, 0)
    frames()


def centre(rect) -> tuple[float, float]:
    return (rect[0] + 8, (rect[1] + rect[3]) / 2)  # the checkbox's box, left of its label


def node(label: str) -> int:
    return app.state.tree.labels.index(label)


def composite_of(img) -> list:
    x, y, w, h = app.layout.composite
    return img[y : y + h, x : x + w, :3].tolist() if img is not None else []


s = app.state
frames(3, shot="start")
result["rows"] = [s.tree.labels[n] for n in s.tree.rows()]
storey2 = node("Storey 2")
click(*centre(s.tree.rects[storey2]))
frames(2, shot="group")
result["group_focus"] = sorted(s.highlighted)
result["storey2"] = [int(i) for i in s.tree.members(storey2)]
click(*centre(s.tree.rects[storey2]))  # off again
wall = house.index("IfcWall 'Wall 1'")
click(*centre(app.item_rects[wall]))
click(*centre(s.tree.buttons["hide highlighted"]))
frames(2, shot="hidden")
result["hidden"] = sorted(s.hidden)
result["hidden_has_region"] = bool(app.records.visible[wall])
result["atlas_ids_hidden"] = sorted({int(i) for i in np.flatnonzero(app.records.visible)})
click(*centre(s.tree.buttons["isolate"]))
frames(2, shot="isolated")
result["isolated_visible"] = [int(i) for i in np.flatnonzero(app.records.visible)]
click(*centre(s.tree.buttons["show all"]))
click(*centre(app.item_rects[wall]))  # highlight off
frames(2, shot="shown")
result["focus_after_shown"] = sorted(s.highlighted)
result["shown_visible"] = int(app.records.visible.sum())

door = house.index("IfcDoor 'Front door'")
x0, y0, x1, y1 = app.item_rects[door]
move(x1 - 4, (y0 + y1) / 2)  # over the row's label: hover
img = frames(2, shot="hover")
result["hover"] = s.hover
result["hover_node"] = int(s.tree.row_of[door])
result["hover_rect"] = [int(v) for v in app.records.viewport_rect[door]]
result["layout_hover"] = list(app.layout.composite)

s.tree.open.clear()  # every group closed: no object row is shown
move(5, 5)
frames(2)
cx, cy, cw, ch = app.layout.composite
vx0, vy0, vx1, vy1 = app.records.viewport_rect[door]
px, py = cx + (vx0 + vx1) / 2, cy + ch - 1 - (vy0 + vy1) / 2
expected = app.controls.object_at(px, py)  # what the click picks (ghosted: maybe the wall)
result["rows_before_reveal"] = [int(n) for n in s.tree.rows()]
click(px, py)
frames(2, shot="revealed")
result["picked_expected"] = expected
result["picked_selected"] = s.selected
result["picked_row"] = int(s.tree.row_of[expected]) if expected is not None else None
result["picked_row_shown"] = bool(np.isin(result["picked_row"], s.tree.rows()))


s.mode = "transparent"  # a group's opacity slider sets its subtree's
frames(2)
storey1 = node("Storey 1")
sx0, sy0, sx1, sy1 = s.tree.sliders[storey1]
click(sx0 + 2, (sy0 + sy1) / 2)  # the slider's left end: opacity 0
frames(2, shot="group_opacity")
result["storey1"] = [int(i) for i in s.tree.members(storey1)]
result["opacities"] = {str(k): v for k, v in s.style.opacity.items()}
s.mode = "ghosted-ao"

window = house.index("IfcWindow 'Window 2'")  # double-click: orbit around it and fit it
frames(2)
wx0, wy0, wx1, wy1 = app.records.viewport_rect[window]
point = (cx + (wx0 + wx1) / 2, cy + ch - 1 - (wy0 + wy1) / 2)
window = app.controls.object_at(*point)  # the object the double-click lands on
move(*point)
for _ in range(2):
    h = wnd.size[1]
    pw.dispatch_event("on_mouse_press", int(point[0]), h - int(point[1]), mouse.LEFT, 0)
    pw.dispatch_event("on_mouse_release", int(point[0]), h - int(point[1]), mouse.LEFT, 0)
frames(3, shot="double_click")
result["double_click_target"] = app.orbit.target.tolist()
result["window_center"] = ((house.aabb_min[window] + house.aabb_max[window]) / 2).tolist()
result["window_rect"] = [int(v) for v in app.records.viewport_rect[window]]
result["window_viewport"] = list(app.records.viewport)


def many(n: int) -> Scene:
    """n one-triangle objects on a grid, built as arrays (from_meshes loops per object)."""
    corner = np.array([[0, 0, 0], [0.8, 0, 0], [0, 0.8, 0]], np.float32)
    k = np.arange(n)
    offset = np.stack([k % 400, k // 400, np.zeros(n)], 1).astype(np.float32)
    pos = (offset[:, None, :] + corner[None]).reshape(-1, 3)
    lo, hi = offset.astype(np.float64), offset + np.array([0.8, 0.8, 0.0])
    origin = (lo.min(0) + hi.max(0)) / 2
    scene = Scene(
        names=[f"part {i}" for i in range(n)],
        positions=pos - origin.astype(np.float32),
        normals=np.tile([0, 0, 1], (3 * n, 1)).astype(np.float32),
        object_ids=np.repeat(k, 3).astype(np.uint32),
        indices=np.arange(3 * n, dtype=np.uint32),
        index_ranges=np.stack([3 * k, np.full(n, 3)], 1),
        colors=np.tile([0.6, 0.6, 0.6, 1.0], (n, 1)),
        aabb_min=lo,
        aabb_max=hi,
        origin=origin,
        source="many",
    )
    scene.paths = [("assembly", f"sub {i // 5000}", f"group {i // 100}") for i in range(n)]
    return scene


app.set_scene(many(100_000), mode="std")  # the panel on 100,000 objects
app.state.show_atlas = False  # (the atlas overlay outlines every region)
tree = app.state.tree
tree.open.update(np.flatnonzero(tree.obj < 0).tolist())  # every group open: 101,021 rows
frames(3)
ui = []
for _ in range(5):
    frames(1)
    ui.append(app.stats.last_ms.get("ui", 0.0))
result["many_rows"] = len(tree.rows())
result["many_emitted"] = len(tree.rects)
result["many_ui_ms"] = float(np.median(ui))
move(*centre(next(iter(tree.rects.values()))))
frames(2)

s.show_atlas = False
s.mode = "std"
result["framing"] = {}
for name, scene in (("house", house), *((("engine", load_scene(ENGINE)),) if ENGINE.exists() else ())):
    app.set_scene(scene, mode="std")
    app.state.show_atlas = False
    app.state.show_cube = False  # the view cube is drawn over the composite's corner
    for aspect in (0.5, 1.0, 2.0):
        size = (PANEL_WIDTH + int(600 * aspect), 600)  # the composite: the rest of the window
        pw.set_size(*size)
        pw.dispatch_events()
        frames(2)
        app.frame_objects()  # F
        img = frames(2, shot=f"frame_{name}_{aspect}")
        x, y, w, h = app.layout.composite
        result["framing"][f"{name} {aspect}"] = {"rect": [x, y, w, h], "png": f"frame_{name}_{aspect}.png"}
result["gl_errors"] = errors
app.release()
(OUT / "result.json").write_text(json.dumps(result, indent=1))
