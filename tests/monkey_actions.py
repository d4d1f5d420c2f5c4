"""The monkey's actions (tests/viewer_monkey.py): each one thing a user does to the viewer's
window, drawn at random by weight (`Actions.WEIGHTS`) with the run's seeded generator."""

from __future__ import annotations

import random
from pathlib import Path
from typing import TYPE_CHECKING

import numpy as np
from pyglet.window import key, mouse

from rtta.errors import RttaError
from rtta.passes.composite import ROLES
from rtta.passes.oit import ORDERS
from rtta.scene.cutaway import CAPS, SECTION_SCOPES
from rtta.scene.explode import EXPLODE_MAX, EXPLODE_SCOPES
from viewer import cutaway, gizmo, panel_view
from viewer.cutaway import AXES
from viewer.state import VIEW_MODES

if TYPE_CHECKING:
    from viewer.app import Viewer

LARGEST = (1900, 1050)  # the largest window a resize makes (the warm-up tour shows every mode there)

KEYS = [  # every key viewer/controls.py binds (Ctrl+Q, which quits, aside)
    *(key.LEFT, key.RIGHT, key.UP, key.DOWN, key.EQUAL, key.MINUS, key.PAGEUP, key.PAGEDOWN),
    *(key.F, key.A, key.M, key.L, key.P, key.C, key.SPACE, key.F12, key.O, key.R, key.ESCAPE, key.X, key.E),
    *(key._5, key.NUM_5, key._1, key._3, key._7, key._0, key.NUM_1, key.NUM_3, key.NUM_7, key.NUM_0),
    *(key.TAB, key.ENTER, key.BACKSPACE, key.DELETE, key.W),  # unbound: ignored, or imgui's
]
MODIFIERS = [0, 0, 0, key.MOD_CTRL, key.MOD_SHIFT]


class Actions:
    """What the monkey does; the events and frames (send, frames, click, drag, press, point,
    anywhere, h) come from the class it is mixed into (viewer_monkey.Monkey)."""

    app: Viewer
    rng: random.Random
    files: Path
    bad: list[Path]
    good: list[Path]

    def a_orbit(self) -> None:
        self.drag(self.app.layout.composite, mouse.LEFT)

    def a_pan(self) -> None:
        self.drag(self.app.layout.composite, self.rng.choice((mouse.RIGHT, mouse.MIDDLE)))

    def a_wheel(self) -> None:
        x, y = self.point(self.app.layout.composite) if self.rng.random() < 0.7 else self.anywhere()
        self.send("on_mouse_motion", x, self.h() - y, 0, 0)
        for _ in range(self.rng.randint(1, 4)):
            self.send("on_mouse_scroll", x, self.h() - y, 0, self.rng.choice((-3, -1, 1, 2, 5)))
            self.frames()

    def a_key(self) -> None:
        symbol = self.rng.choice(KEYS)
        if symbol == key.O:
            self.app.scene_dir = self.files  # the browser opens on the monkey's folder
        self.press(symbol, self.rng.choice(MODIFIERS))

    def a_click_composite(self) -> None:
        x, y = self.point(self.app.layout.composite)
        self.click(x, y, modifiers=self.rng.choice(MODIFIERS))

    def a_double_click(self) -> None:
        x, y = self.point(self.app.layout.composite)
        self.click(x, y, tap=True)
        self.click(x, y, tap=True)

    def a_click_atlas(self) -> None:
        if self.app.layout.atlas[2] > 0:
            self.click(*self.point(self.app.layout.atlas), button=self.rng.choice((mouse.LEFT, mouse.RIGHT)))

    def a_click_panel(self) -> None:
        button = mouse.LEFT if self.rng.random() < 0.85 else mouse.RIGHT
        self.click(*self.point(self.app.layout.panel), button=button)

    def a_drag_panel(self) -> None:  # sliders, the tree's scroll bar
        self.drag(self.app.layout.panel, mouse.LEFT)

    def a_tree(self) -> None:
        rects = self.app.state.tree.rects
        if rects:
            x0, y0, x1, y1 = rects[self.rng.choice(list(rects))]
            button = mouse.LEFT if self.rng.random() < 0.8 else mouse.RIGHT  # right: the row's menu
            self.click(x0 + 8, (y0 + y1) / 2, button=button)
            if button == mouse.RIGHT:  # an entry of the menu, or outside it
                self.click(x0 + 30, (y0 + y1) / 2 + self.rng.randint(10, 90))

    def a_filter(self) -> None:
        rect = self.app.item_rects.get(-1)
        if rect is None:
            return
        self.click((rect[0] + rect[2]) / 2, (rect[1] + rect[3]) / 2)
        for _ in range(self.rng.randint(0, 3)):
            self.press(key.BACKSPACE)
        for ch in self.rng.choice(["part", "0", "1", "caliper", "pis", "*", "[", "zz", "é", "part00", "  "]):
            self.send("on_text", ch)
            self.frames()
        self.press(key.ENTER)

    def a_open(self) -> None:  # the browser: O, then clicks in its popup
        self.app.scene_dir = self.files
        self.press(key.O)
        w, h = self.wnd.size
        for _ in range(self.rng.randint(1, 4)):
            self.click(*self.point((w // 2 - 260, h // 2 - 210, 520, 420)))
        if self.app.files.visible and self.rng.random() < 0.5:
            self.press(key.ESCAPE)

    def a_drop(self) -> None:
        path = self.rng.choice(self.bad if self.rng.random() < 0.7 else self.good)
        self.send("on_file_drop", *self.anywhere(), [str(path)])
        self.frames(2)

    def a_resize(self) -> None:
        r = self.rng.random()
        if r < 0.15:
            self.send("on_resize", 0, 0)  # minimized
            self.frames(2)
        w, h = (self.rng.randint(1, 40), self.rng.randint(1, 40)) if r < 0.3 else (0, 0)
        if not w:
            w, h = self.rng.randint(300, LARGEST[0]), self.rng.randint(200, LARGEST[1])
        self.pw.set_size(w, h)
        self.pw.dispatch_events()
        self.frames(2)

    def a_splitter(self) -> None:
        x, y = self.app.layout.panel[2], self.app.layout.panel[3] // 2
        dx = self.rng.randint(-300, 500)
        self.send("on_mouse_press", x, self.h() - y, mouse.LEFT, 0)
        for k in range(1, 4):
            self.send("on_mouse_drag", x + dx * k // 3, self.h() - y, dx // 3, 0, mouse.LEFT, 0)
            self.frames()
        self.send("on_mouse_release", x + dx, self.h() - y, mouse.LEFT, 0)
        self.frames()

    def a_mode_style(self) -> None:  # what the mode combo and the Style section set
        s, r = self.app.state, self.rng
        s.choose_mode(r.choice(VIEW_MODES))
        st = s.style
        st.context_opacity, st.desaturate, st.default_opacity = r.random(), r.random(), r.random()
        st.edge_width, st.outline_width, st.halo = r.randint(1, 4), r.randint(1, 4), r.randint(0, 16)
        st.ao_radius, st.ao_strength = r.uniform(1, 16), r.uniform(0, 2)
        st.ao_objects, st.edge_objects, st.order = r.choice(ROLES), r.choice(ROLES), r.choice(ORDERS)
        s.settings.region_scale, s.settings.context_scale = r.uniform(0.25, 2.0), r.uniform(0.25, 1.0)
        self.frames(2)

    def a_cutaway(self) -> None:  # what the 'cutaway and explode' section sets
        c, r = self.app.state.cutaway, self.rng
        c.axis, c.at, c.caps, c.scope = r.choice(AXES), r.random(), r.choice(CAPS), r.choice(SECTION_SCOPES)
        c.explode, c.explode_scope = r.choice((0.0, 0.0, r.uniform(0, EXPLODE_MAX))), r.choice(EXPLODE_SCOPES)
        self.frames(2)

    def a_cube(self) -> None:  # a face, edge or corner of the view cube, or the projection switch below it
        cells = gizmo.cells(self.app.layout.composite, self.app.orbit) if self.app.state.show_cube else []
        if cells and self.rng.random() < 0.2:
            x0, y0, x1, y1 = gizmo.projection_rect(self.app.layout.composite)
            self.click((x0 + x1) / 2, (y0 + y1) / 2)
        elif cells:
            quad = self.rng.choice(cells)[2]
            self.click(*quad.mean(axis=0))
            self.frames(self.rng.randint(0, 6))  # sometimes a drag or a key meets the turn

    def a_section_surface(self) -> None:  # the panel's 'on a surface', then a click (or a second press)
        c = self.app.state.cutaway
        c.picking = not c.picking if self.rng.random() < 0.15 else True
        self.frames()
        r, scene = self.rng.random(), self.app.renderer.scene
        x, y = self.point(self.app.layout.composite) if r < 0.9 else self.anywhere()
        if r < 0.6:  # a part's box centre: the part, what is in front of it, or the background
            oid = self.rng.randrange(scene.count)
            xy, front = cutaway._screen(self.app, [(scene.aabb_min[oid] + scene.aabb_max[oid]) / 2])
            if front and np.isfinite(xy).all():
                w, h = self.wnd.size
                x, y = int(np.clip(xy[0, 0], 0, w - 1)), int(np.clip(xy[0, 1], 0, h - 1))
        self.click(x, y, modifiers=self.rng.choice(MODIFIERS))

    def a_section_handle(self) -> None:  # the plane's handle dragged along its normal (a plane first)
        c, r = self.app.state.cutaway, self.rng
        if not c.has_plane or not c.enabled or not c.show_quad or r.random() < 0.1:
            c.axis, c.normal, c.enabled, c.show_quad = r.choice(AXES[1:]), None, True, True
            self.frames()
        found = cutaway.handle(self.app)
        if found is None:
            return
        (x, y), _ = found
        x, y = int(x + r.randint(-3, 3)), int(y + r.randint(-3, 3))
        dx, dy, steps = r.randint(-250, 250), r.randint(-250, 250), r.randint(1, 6)
        self.send("on_mouse_motion", x, self.h() - y, 0, 0)
        self.frames()
        self.send("on_mouse_press", x, self.h() - y, mouse.LEFT, 0)
        for i in range(1, steps + 1):
            self.send(
                "on_mouse_drag",
                x + dx * i // steps,
                self.h() - (y + dy * i // steps),
                dx // steps,
                -dy // steps,
                mouse.LEFT,
                0,
            )
            self.frames()
        self.send("on_mouse_release", x + dx, self.h() - (y + dy), mouse.LEFT, 0)
        self.frames()

    def a_section_panel(self) -> None:  # the plane's buttons: flip, on, show the plane, offset, reset, animate
        app, c, r = self.app, self.app.state.cutaway, self.rng
        choice = r.randrange(7)
        if choice == 0:
            c.flip()
        elif choice == 1:
            c.enabled = not c.enabled
        elif choice == 2:
            c.show_quad = not c.show_quad
        elif choice == 3 and c.normal is not None:
            c.offset += r.uniform(-1, 1) * float(app.renderer.scene.radius)
        elif choice == 4:
            cutaway.reset(app)
        elif choice == 5:
            c.animate_explode()
            self.frames(r.randint(1, 8))  # sometimes closed again before it is open
        else:
            c.axis, c.normal, c.enabled = r.choice(AXES), None, True  # the combo: a plane along an axis again
        self.frames(2)

    def a_views(self) -> None:
        app, r = self.app, self.rng
        names = app.views.names()
        if not names or r.random() < 0.4:
            panel_view.save(app, r.choice(["a", "b", "c", "view/../x", "", " "]) or f"v{len(names)}")
        elif r.random() < 0.75:
            panel_view.restore(app, r.choice(names))
        else:
            try:
                app.views.delete(r.choice(names))
            except RttaError as exc:  # as the panel's 'x' says it
                app.say(str(exc), error=True)
        self.frames(2)

    def a_measure(self) -> None:  # R, one to three clicks; sometimes Esc, 'clear' or a measurement's 'x'
        ruler, r = self.app.ruler, self.rng
        if not ruler.on:
            self.press(key.R)
        for _ in range(r.randint(1, 3)):
            self.click(*self.point(self.app.layout.composite))
        k = r.random()
        if k < 0.15:
            self.press(key.ESCAPE)
        elif k < 0.25:
            ruler.clear()
        elif k < 0.35 and ruler.done:
            del ruler.done[r.randrange(len(ruler.done))]

    def a_idle(self) -> None:
        self.frames(self.rng.randint(1, 5))

    def a_home(self) -> None:  # the main scene again (as after opening others)
        if self.app.renderer.scene is not self.main:
            self.app.set_scene(self.main)
        self.frames()

    WEIGHTS = {
        "orbit": 12, "pan": 5, "wheel": 8, "key": 16, "click_composite": 9, "double_click": 3,
        "click_atlas": 3, "click_panel": 12, "drag_panel": 5, "tree": 6, "filter": 3, "open": 2,
        "drop": 2, "resize": 3, "splitter": 1, "mode_style": 4, "cutaway": 5, "cube": 3, "views": 3,
        "measure": 3, "idle": 2, "home": 1, "section_surface": 3, "section_handle": 3, "section_panel": 3,
    }  # fmt: skip
