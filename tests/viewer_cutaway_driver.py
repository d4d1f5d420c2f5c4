"""Drives the real viewer window through cutaways and exploded views (issue 41), for
tests/test_viewer_cutaway.py.

Run as `python tests/viewer_cutaway_driver.py OUT_DIR` with DISPLAY set (Xvfb): a plane placed
on a picked surface, its handle dragged, the plane flipped (key X), the one-button reset, the
explode slider at 1 and back at 0, and a click on a part the explode moved. Events go through
the pyglet window's own dispatch, as in tests/viewer_cad_driver.py. Writes window screenshots
(PNG) and `result.json`.
"""

from __future__ import annotations

import json
import sys
from pathlib import Path

import numpy as np
from pyglet.window import key, mouse
from window_frames import Frames  # tests/ is this script's folder

from rtta.scene.loader import load_scene_or_demo
from viewer import cutaway
from viewer.app import Viewer
from viewer.run import create_window

OUT = Path(sys.argv[1])
wnd = create_window((1280, 720))
demo = load_scene_or_demo(None)
app = Viewer(wnd, demo, views_dir=OUT / "views")
c = app.state.cutaway
frames = Frames(app, wnd, OUT)
send, errors = frames.send, frames.errors
result: dict = {}


def shot(name: str) -> None:
    """A screenshot without the plane's quad (the cut itself, not its overlay)."""
    show, c.show_quad = c.show_quad, False
    frames(2, shot=name)
    c.show_quad = show


def click(x: float, y: float) -> None:
    h = wnd.size[1]
    x, y = int(round(x)), int(round(y))
    send("on_mouse_motion", x, h - y, 0, 0)
    frames()
    send("on_mouse_press", x, h - y, mouse.LEFT, 0)
    frames()
    send("on_mouse_release", x, h - y, mouse.LEFT, 0)
    frames()


def press_key(symbol: int) -> None:
    send("on_key_press", symbol, 0)
    send("on_key_release", symbol, 0)
    frames()


def front_id(x: float, y: float) -> int:
    """The nearest object under window point (x, y), from the std pass."""
    cx, cy, _, ch = app.layout.composite
    target = app.renderer.std(app.orbit.camera(), app.viewport)
    return int(target.texels(np.array([[int(x - cx), int(cy + ch - 1 - y), 0]]), ids=True)["id"][0])


frames(3)
result["layout"] = {k: list(getattr(app.layout, k)) for k in ("composite", "atlas")}
shot("first")

# 1. a plane on the surface under the composite's centre (the pick path), then its quad
cx, cy, cw, ch = app.layout.composite
c.picking = True
click(cx + cw / 2, cy + ch / 2)
result["plane"] = {"normal": c.normal, "offset": c.offset, "picking": c.picking, "focus": sorted(app.state.highlighted)}
shot("plane")
frames(2, shot="plane_quad")

# 2. drag the handle 40 px along the normal's screen direction: the plane moves that way
(hx, hy), per_unit = cutaway.handle(app)
direction = per_unit / np.linalg.norm(per_unit)
h = wnd.size[1]
before = c.offset
send("on_mouse_motion", int(hx), h - int(hy), 0, 0)
frames()
send("on_mouse_press", int(hx), h - int(hy), mouse.LEFT, 0)
frames()
result["grabbed"] = c.dragging
x, y = float(hx), float(hy)
for _ in range(8):
    dx, dy = 5 * direction
    x, y = x + dx, y + dy
    send("on_mouse_drag", int(round(x)), h - int(round(y)), int(round(dx)), -int(round(dy)), mouse.LEFT, 0)
    frames()
send("on_mouse_release", int(round(x)), h - int(round(y)), mouse.LEFT, 0)
frames()
result["drag"] = {"before": before, "after": c.offset, "dragging": c.dragging, "camera_az": app.orbit.az}
shot("dragged")
removed = app.renderer.staging.removed
result["removed_before_flip"] = [] if removed is None else np.flatnonzero(removed).tolist()

# 3. flip (key X): the other side is kept
press_key(key.X)
result["flipped_normal"] = c.normal
shot("flipped")
removed = app.renderer.staging.removed
result["removed_after_flip"] = [] if removed is None else np.flatnonzero(removed).tolist()

# 3b. toggled off: no cut (the first image); on again: the flipped cut
c.enabled = False
shot("toggled_off")
c.enabled = True
shot("toggled_on")

# 4. the active list and the one-button reset (hide a part and open the lens too)
app.state.hide([0])
app.state.lens.on = True
c.explode = 0.5
result["active_before_reset"] = cutaway.active(app)
cutaway.reset(app)
result["active_after_reset"] = cutaway.active(app)
shot("reset")

# 5. the explode slider at 1, then back at 0
c.explode = 1.0
shot("exploded")
c.explode = 0.0
shot("unexploded")

# 5b. key E animates the explode open to 1 and closed again
cutaway.EXPLODE_ANIM_S = 1.5  # a few frames on a loaded llvmpipe
seen = []
for name in ("animated_open", "animated_closed"):
    press_key(key.E)
    for _ in range(300):
        seen.append(c.explode)
        if c.anim is None:
            break
        frames()
    shot(name)
result["animated"] = {"seen": seen, "end": c.explode}


def tied(x: float, y: float) -> bool:
    """Whether the two nearest surfaces under window point (x, y) lie at one depth (coplanar
    caps of two parts cut by one plane): either may be the front one, in STD as in the atlas."""
    from rtta.passes.picking import objects_at

    cx, cy, _, ch = app.layout.composite
    hits = objects_at(app.renderer.atlas, app.records, int(round(x) - cx), int(cy + ch - 1 - round(y)))
    return len(hits) > 1 and hits[1][1] - hits[0][1] < 1e-5


def click_on(flags: np.ndarray) -> dict | None:
    """Click the first of these parts (bool [n]) that a point of its box shows in front, on
    a 5 x 5 grid over its bounds, centre first; what it selected."""
    rec = app.records
    app.state.select("none")
    frames()
    grid = sorted(((i, j) for i in range(1, 6) for j in range(1, 6)), key=lambda p: abs(p[0] - 3) + abs(p[1] - 3))
    for oid in np.flatnonzero(flags):
        x0, y0, x1, y1 = rec.viewport_rect[oid]
        if x1 <= x0 or y1 <= y0:
            continue
        for i, j in grid:
            px, py = cx + x0 + (x1 - x0) * i / 6, cy + ch - 1 - (y0 + (y1 - y0) * j / 6)
            if front_id(px, py) == oid and not tied(px, py):
                click(px, py)
                return {"part": int(oid), "focus": sorted(app.state.highlighted)}
    return None


# 5c. a click on a capped part (an axis plane through the middle, solid caps) selects it
c.axis, c.at, c.caps = "y", 0.5, "solid"
frames(2)
capped = app.renderer.gpu.placement.capped
result["capped"] = click_on(capped)
c.axis = "off"

# 6. a click on a part the explode moved selects it
c.explode = 1.0
frames(2)
offsets = app.renderer.staging.offsets
rec = app.records
chosen = None
for oid in np.argsort(-np.linalg.norm(offsets, axis=1)):
    x0, y0, x1, y1 = rec.viewport_rect[oid]
    if x1 <= x0 or y1 <= y0:
        continue
    px, py = cx + (x0 + x1) / 2, cy + ch - 1 - (y0 + y1) / 2
    if front_id(px, py) == oid:
        chosen = (int(oid), px, py)
        break
app.state.select("none")
frames()
frames(2)
result["moved"] = None
if chosen is not None:
    oid, px, py = chosen
    click(px, py)
    result["moved"] = {
        "part": oid,
        "offset": float(np.linalg.norm(offsets[oid])),
        "focus": sorted(app.state.highlighted),
        "radius": float(demo.radius),
    }

result["gl_errors"] = errors
(OUT / "result.json").write_text(json.dumps(result, default=float))
