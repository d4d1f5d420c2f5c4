"""Mouse and keyboard: the orbit camera, picking, and the viewer's shortcuts.

Left-drag rotates, right- or middle-drag pans, the wheel zooms towards the cursor; a click
toggles the highlight of the object under the cursor (in ghosted modes a highlighted
object seen through the context wins; Shift+click takes the front-most); a double-click
orbits around the object. With the lens on (C) it follows the mouse over the composite;
Space pins it where it is or lets it follow again. Events imgui wants (over the panel) go to imgui only.
"""

from __future__ import annotations

import time
from typing import TYPE_CHECKING

from imgui_bundle import imgui

from rtta.passes.picking import objects_at, pick

from .orbit import DEGREES_PER_PIXEL
from .state import VIEW_MODES
from .views import contains

if TYPE_CHECKING:
    from .commands import ControlsHost

CLICK_SLOP_PX = 3
DOUBLE_CLICK_S = 0.35
KEY_ROTATE_DEG = 5.0
KEY_PAN_PX = 20


class Controls:
    def __init__(self, app: ControlsHost) -> None:
        self.app = app
        self.mouse = (0.0, 0.0)
        self._press = None  # (x, y, button, in composite)
        self._moved = 0.0
        self._last_click = (0.0, None)  # (time, object) of the last click, for double-clicks

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

    def on_press(self, x, y, button) -> None:
        self.mouse = (x, y)
        self.app.imgui.mouse_press_event(x, y, button)
        if not imgui.get_io().want_capture_mouse:
            self._press = (x, y, button, contains(self.app.layout.composite, x, y))
            self._moved = 0.0

    def on_drag(self, x, y, dx, dy) -> None:
        self.mouse = (x, y)
        self.app.imgui.mouse_drag_event(x, y, dx, dy)
        if self._press is None or not self._press[3]:
            return
        self._moved += abs(dx) + abs(dy)
        if self._moved <= CLICK_SLOP_PX:
            return
        buttons = self.app.wnd.mouse_states
        if buttons.left:
            self.app.orbit.rotate(dx, dy)
        elif buttons.right or buttons.middle:
            self.app.orbit.pan(dx, dy, self.app.layout.composite[3])

    def on_release(self, x, y, button) -> None:
        self.mouse = (x, y)
        self.app.imgui.mouse_release_event(x, y, button)
        press, self._press = self._press, None
        if press is None or not press[3] or button != self.app.wnd.mouse.left or self._moved > CLICK_SLOP_PX:
            return
        self.click(x, y, shift=self.app.wnd.modifiers.shift)

    def click(self, x: float, y: float, shift: bool = False) -> int | None:
        """Toggle the highlight of the object at window point (x, y); a second click on the
        same object within DOUBLE_CLICK_S undoes that and orbits around it instead."""
        app = self.app
        oid = self.object_at(x, y, front_most=shift)
        now = time.perf_counter()
        last_t, last_oid = self._last_click
        self._last_click = (now, oid)
        if oid is not None and oid == last_oid and now - last_t < DOUBLE_CLICK_S:
            app.state.toggle(oid)  # undo the first click's toggle
            scene = app.renderer.scene
            app.orbit.orbit_around((scene.aabb_min[oid] + scene.aabb_max[oid]) / 2.0)
            app.frame_objects([oid])  # then fit it, as F fits everything
            self._last_click = (0.0, None)
            return oid
        if oid is not None:
            app.state.toggle(oid)
            app.state.reveal(oid)  # its row in the tree: opened, scrolled to, marked
        return oid

    def object_at(self, x: float, y: float, front_most: bool = False) -> int | None:
        app, rec = self.app, self.app.records
        if rec is None:
            return None
        cx, cy, _, ch = app.layout.composite
        px, py = int(x - cx), int(cy + ch - 1 - y)  # viewport pixel, bottom-left origin
        prefer = None if front_most or not app.state.mode.startswith("ghosted") else app.state.highlighted
        return pick(objects_at(app.renderer.atlas, rec, px, py), prefer)  # reads the candidates' texels alone

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
            app.state.mode = VIEW_MODES[(VIEW_MODES.index(app.state.mode) + 1) % len(VIEW_MODES)]
        elif key == keys.L and app.records is not None:
            app.state.atlas_layer = (app.state.atlas_layer + 2) % (app.records.atlas_size[2] + 1) - 1  # -1: all
        elif key == keys.P:
            app.state.projector.on = not app.state.projector.on
        elif key == keys.C:
            app.state.lens.on = not app.state.lens.on
        elif key == keys.SPACE and app.state.lens.on:
            app.state.lens.follow = not app.state.lens.follow
        elif key == keys.F12:
            app.screenshot()
        elif key == keys.O:
            app.files.open(app.scene_dir)
        elif key in (keys.NUMBER_5, keys.NUMPAD_5):  # as in Blender: perspective <-> orthographic
            orbit.projection = "ortho" if orbit.projection == "perspective" else "perspective"
        elif key == keys.Q and modifiers.ctrl:
            app.wnd.close()
