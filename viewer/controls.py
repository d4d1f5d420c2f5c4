"""Mouse and keyboard: the orbit camera, picking, and the viewer's shortcuts.

Left-drag rotates, right- or middle-drag pans, the wheel zooms towards the cursor; a click
toggles the highlight of the object under the cursor (in ghosted modes a highlighted
object seen through the context wins; Shift+click takes the front-most); a double-click
orbits around the object and fits it (both clicks picked with the highlights from before
the first). With the lens on (C) it follows the mouse over the composite; Space pins it where
it is or lets it follow again. The view cube (top right) turns the view to a side, an edge or a
corner; keys 1, 3, 7 (Ctrl: the opposite side) and 0 (iso) do the same, 5 switches
perspective/orthographic. R measures (clicks give points; Esc drops a first point, or ends). The
splitter at the panel's edge resizes it. Events imgui wants (over the panel) go to imgui only.
"""

from __future__ import annotations

import time
from typing import TYPE_CHECKING

from imgui_bundle import imgui

from rtta.passes.picking import objects_at, pick
from rtta.scene.framing import STANDARD_VIEWS

from . import cutaway, gizmo
from .orbit import DEGREES_PER_PIXEL
from .state import VIEW_MODES
from .views import contains, panel_clamp

if TYPE_CHECKING:
    from .commands import ControlsHost

CLICK_SLOP_PX = 3
DOUBLE_CLICK_S = 0.35
KEY_ROTATE_DEG = 5.0
KEY_PAN_PX = 20
SPLITTER_PX = 4  # either side of the panel's edge: the splitter


class Controls:
    def __init__(self, app: ControlsHost) -> None:
        self.app = app
        self.mouse = (0.0, 0.0)
        self._press = None  # (x, y, button, in composite)
        self._moved = 0.0
        # (time, object, highlights before it) of the last click, for double-clicks
        self._last_click: tuple[float, int | None, set[int] | None] = (0.0, None, None)
        self.splitting = False  # the splitter is being dragged

    def attach(self, wnd) -> None:
        wnd.exit_key = None  # Esc closes popups; Ctrl+Q quits
        wnd.mouse_position_event_func = self.on_move
        wnd.mouse_drag_event_func = self.on_drag
        wnd.mouse_press_event_func = self.on_press
        wnd.mouse_release_event_func = self.on_release
        wnd.mouse_scroll_event_func = self.on_scroll
        wnd.key_event_func = self.on_key
        wnd.unicode_char_entered_func = self.app.imgui.unicode_char_entered
        wnd.resize_func = self.app.imgui.resize
        wnd.files_dropped_event_func = self.on_drop

    def on_move(self, x, y, dx, dy) -> None:
        self.mouse = (x, y)
        self.app.imgui.mouse_position_event(x, y, dx, dy)
        lens = self.app.state.lens
        if (
            lens.on
            and lens.follow
            and not imgui.get_io().want_capture_mouse
            and contains(self.app.layout.composite, x, y)
        ):
            self.app.move_lens(x, y)

    def on_splitter(self, x: float, y: float) -> bool:
        _, py, pw, ph = self.app.layout.panel
        return pw > 0 and abs(x - pw) <= SPLITTER_PX and py <= y < py + ph and not self.app.files.visible

    def on_press(self, x, y, button) -> None:
        self.mouse = (x, y)
        if button == self.app.wnd.mouse.left and self.on_splitter(x, y):
            self.splitting = True  # imgui never sees it: the panel's edge is no widget
            return
        self.app.imgui.mouse_press_event(x, y, button)
        if not imgui.get_io().want_capture_mouse:
            self._press = (x, y, button, contains(self.app.layout.composite, x, y))
            self._moved = 0.0
            if button == self.app.wnd.mouse.left and self._press[3]:
                cutaway.grab(self.app, x, y)  # the section plane's handle

    def on_drag(self, x, y, dx, dy) -> None:
        self.mouse = (x, y)
        if self.splitting:
            self.app.state.panel_width = panel_clamp(x, self.app.wnd.buffer_size[0])
            return
        self.app.imgui.mouse_drag_event(x, y, dx, dy)
        if self._press is None or not self._press[3]:
            return
        self._moved += abs(dx) + abs(dy)
        if self.app.state.cutaway.dragging:
            cutaway.drag(self.app, dx, dy)
            return
        if self._moved <= CLICK_SLOP_PX:
            return
        self.app.stop_turn()  # a drag takes the camera from a view turn under way
        buttons = self.app.wnd.mouse_states
        if buttons.left:
            self.app.orbit.rotate(dx, dy)
        elif buttons.right or buttons.middle:
            self.app.orbit.pan(dx, dy, self.app.layout.composite[3])

    def on_release(self, x, y, button) -> None:
        self.mouse = (x, y)
        if self.splitting:
            self.splitting = False
            return
        self.app.imgui.mouse_release_event(x, y, button)
        press, self._press = self._press, None
        if self.app.state.cutaway.dragging:
            self.app.state.cutaway.dragging = False
            return
        if press is None or not press[3] or button != self.app.wnd.mouse.left or self._moved > CLICK_SLOP_PX:
            return
        self.click(x, y, shift=self.app.wnd.modifiers.shift)

    def click(self, x: float, y: float, shift: bool = False) -> int | None:
        """Toggle the highlight of the object at window point (x, y); a second click on the
        same object within DOUBLE_CLICK_S undoes that and orbits around it instead, fitted.
        The second click is picked with the highlights from before the first changed them
        (a focus part seen through the context stays the one clicked). On the view cube: its
        view; with the measure tool on: a point."""
        app = self.app
        found = gizmo.hit(app.layout.composite, app.orbit, x, y) if app.state.show_cube else None
        if found is not None:
            part, direction = found
            if part == "projection":
                self.toggle_projection()
            elif direction is not None:
                app.turn_to(*gizmo.view_angles(direction))
            return None
        if app.state.cutaway.picking:  # the section plane goes on the surface clicked
            cutaway.place_at(app, x, y)
            return None
        if app.ruler.on:
            app.measure_at(x, y)
            return None
        now = time.perf_counter()
        last_t, last_oid, before = self._last_click
        double = last_oid is not None and now - last_t < DOUBLE_CLICK_S
        prefer = before if double else set(app.state.highlighted)
        oid = self.object_at(x, y, front_most=shift, prefer=prefer)
        self._last_click = (now, oid, prefer)
        if double and oid is not None and oid == last_oid:
            app.state.toggle(oid)  # undo the first click's toggle
            scene = app.renderer.scene
            app.orbit.orbit_around((scene.aabb_min[oid] + scene.aabb_max[oid]) / 2.0)
            app.frame_objects([oid])  # then fit it, as F fits everything
            self._last_click = (0.0, None, None)
            return oid
        if oid is not None:
            app.state.toggle(oid)
            app.state.reveal(oid)  # its row in the tree: opened, scrolled to, marked
        return oid

    def object_at(self, x: float, y: float, front_most: bool = False, prefer: set[int] | None = None) -> int | None:
        """The object a click at (x, y) means: in ghosted modes the nearest of `prefer`
        (default: the highlighted objects) under it, else (and with `front_most`) the nearest."""
        app, rec = self.app, self.app.records
        if rec is None:
            return None
        cx, cy, _, ch = app.layout.composite
        px, py = int(x - cx), int(cy + ch - 1 - y)  # viewport pixel, bottom-left origin
        ghosted = app.state.shown_mode().startswith("ghosted")
        prefer = None if front_most or not ghosted else (app.state.highlighted if prefer is None else prefer)
        return pick(objects_at(app.renderer.atlas, rec, px, py), prefer)  # reads the candidates' texels alone

    def toggle_projection(self) -> None:
        """Perspective <-> orthographic (key 5, the switch under the view cube)."""
        orbit = self.app.orbit
        orbit.projection = "ortho" if orbit.projection == "perspective" else "perspective"

    def on_scroll(self, x_offset, y_offset) -> None:
        self.app.imgui.mouse_scroll_event(x_offset, y_offset)
        x, y = self.mouse
        rect = self.app.layout.composite
        if imgui.get_io().want_capture_mouse or not contains(rect, x, y):
            return
        rx, ry, rw, rh = rect
        ndc = (2.0 * (x - rx) / rw - 1.0, 1.0 - 2.0 * (y - ry) / rh)
        self.app.orbit.zoom(y_offset, ndc, rw / rh)

    def on_drop(self, x, y, paths) -> None:
        if paths:
            self.app.open_scene_later(paths[0])

    @staticmethod
    def _views(keys) -> dict:
        """Key -> (standard view, with Ctrl)."""
        pairs = {1: ("front", "back"), 3: ("right", "left"), 7: ("top", "bottom"), 0: ("iso", "iso")}
        out = {}
        for n, views in pairs.items():
            out[getattr(keys, f"NUMBER_{n}")] = out[getattr(keys, f"NUMPAD_{n}")] = views
        return out

    def on_key(self, key, action, modifiers) -> None:
        app, keys = self.app, self.app.wnd.keys
        app.imgui.key_event(key, action, modifiers)
        if action != keys.ACTION_PRESS or imgui.get_io().want_capture_keyboard:
            return
        orbit = app.orbit
        arrows = {keys.LEFT: (-1, 0), keys.RIGHT: (1, 0), keys.UP: (0, -1), keys.DOWN: (0, 1)}
        if key in arrows:
            dx, dy = arrows[key]
            if modifiers.ctrl:  # the placed projector orbits (attached: it detaches there)
                app.state.projector.attached = False
                app.state.projector.nudge(dx * KEY_ROTATE_DEG, -dy * KEY_ROTATE_DEG)
            elif modifiers.shift:
                orbit.pan(dx * KEY_PAN_PX, dy * KEY_PAN_PX, app.layout.composite[3])
            else:
                orbit.rotate(dx * KEY_ROTATE_DEG / DEGREES_PER_PIXEL, dy * KEY_ROTATE_DEG / DEGREES_PER_PIXEL)
        elif key in (keys.EQUAL, keys.PAGE_UP):
            orbit.zoom(1)
        elif key in (keys.MINUS, keys.PAGE_DOWN):
            orbit.zoom(-1)
        elif key == keys.F:
            app.frame_objects()
        elif key == keys.A:
            app.state.show_atlas = not app.state.show_atlas
        elif key == keys.M:
            app.state.choose_mode(VIEW_MODES[(VIEW_MODES.index(app.state.mode) + 1) % len(VIEW_MODES)])
        elif key == keys.L and app.records is not None:
            app.state.atlas_layer = (app.state.atlas_layer + 2) % (app.records.atlas_size[2] + 1) - 1  # -1: all
        elif key == keys.P:
            app.state.projector.on = not app.state.projector.on
        elif key == keys.C:
            app.state.lens.on = not app.state.lens.on
        elif key == keys.SPACE and app.state.lens.on:
            app.state.lens.follow = not app.state.lens.follow
        elif key == keys.X:  # the section plane keeps its other side
            app.state.cutaway.flip()
        elif key == keys.E:  # the explode opens (or closes), animated
            app.state.cutaway.animate_explode()
        elif key == keys.F12:
            app.screenshot()
        elif key == keys.O:
            app.files.open(app.scene_dir)
        elif key in (keys.NUMBER_5, keys.NUMPAD_5):  # as in Blender: perspective <-> orthographic
            self.toggle_projection()
        elif key in self._views(keys):  # as in Blender: 1 front, 3 right, 7 top; Ctrl: the opposite
            app.turn_to(*STANDARD_VIEWS[self._views(keys)[key][1 if modifiers.ctrl else 0]])
        elif key == keys.R:
            app.ruler.on, app.ruler.first = not app.ruler.on, None
            app.say("measure: click two points (a vertex within a few pixels snaps)" if app.ruler.on else "")
        elif key == keys.ESCAPE and app.ruler.on:  # drop a first point; without one, leave the tool
            app.ruler.on = app.ruler.first is not None
            app.ruler.first = None
        elif key == keys.Q and modifiers.ctrl:
            app.wnd.close()
