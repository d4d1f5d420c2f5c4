"""The viewer: one window, the rtta renderer, and what is drawn each frame.

Per frame: build the panel, capture again only when the camera, the viewport or the
capture settings changed, composite again only when the mode or style changed, then show
the composite and the atlas layer side by side with the panel on the left.
"""

from __future__ import annotations

import time
from pathlib import Path

import moderngl
import numpy as np
from imgui_bundle import imgui, implot

from rtta.errors import RttaError, printable
from rtta.passes.style import Mode
from rtta.renderer.navigation import FULL, MIN_OBJECTS, FrameBudget, KeepShare
from rtta.renderer.placing import restage
from rtta.renderer.renderer import Renderer
from rtta.scene.model import Scene

from . import overlay, panels, ruler, saved
from .controls import Controls
from .files import FileBrowser, Stats
from .gizmo import Turn
from .imgui_renderer import GrowingImguiRenderer
from .loading import Loading
from .orbit import Orbit
from .painting import Painting
from .pictures import Pictures
from .pictures import default_dir as default_pictures
from .ruler import Ruler
from .state import ViewerState
from .views import ATLAS_BACKGROUND, Layout, ViewPass, layer_tiles

WINDOW_CLEAR = (0.11, 0.11, 0.12)
LABEL_HEIGHT = 22


class Viewer(Pictures, Loading, Painting):
    def __init__(
        self,
        wnd,
        scene: Scene,
        *,
        screenshot_dir: Path | None = None,
        mode: str = "ghosted-ao",
        load: dict | None = None,
        views_dir: Path | None = None,
    ) -> None:
        """`screenshot_dir` None: the user's pictures folder (pictures.default_dir); `views_dir`
        None: the saved views' folder (saved.default_dir)."""
        self.wnd = wnd
        self.load_options = dict(load or {})  # smoothing for scenes opened from the panel
        self.ctx: moderngl.Context = wnd.ctx
        imgui.create_context()
        implot.create_context()
        imgui.get_io().set_ini_filename("")  # never write imgui.ini into the user's folder
        self.imgui = GrowingImguiRenderer(wnd)
        self.view_pass = ViewPass(self.ctx)
        self.files = FileBrowser(self.open_scene_later)
        self.loading: tuple | None = None  # (path, worker thread, result box) while a file loads
        self.controls = Controls(self)
        self.stats = Stats()
        self.screenshot_dir = Path(screenshot_dir) if screenshot_dir is not None else default_pictures()
        self.screenshot_dir_default = screenshot_dir is None
        self.views_dir = Path(views_dir) if views_dir is not None else saved.default_dir()
        self.turn: Turn | None = None  # the camera turning to a view (view cube, keys)
        self.message, self.message_is_error = "", False
        self._projector_image = None
        self._lens_cache = None
        self.item_rects: dict[int, tuple] = {}  # object list checkboxes on screen (tests click them)
        self.renderer: Renderer  # set_scene makes it (and the state), and makes it again per scene
        self.layout = Layout.of(wnd.buffer_size, True)
        self._camera_key: tuple | None = None  # the last frame's camera: did the view move
        self.camera_still = False  # it did not, in the last frame
        self.set_scene(scene, mode=mode)
        notes = [*self.renderer.caps.notes, *scene.warnings]
        if notes:
            self.say("; ".join(notes))
        self.controls.attach(wnd)

    # ---- scene -------------------------------------------------------------------------
    def set_scene(self, scene: Scene, mode: str | None = None) -> None:
        old: ViewerState | None = getattr(self, "state", None)  # none before the first scene
        state = ViewerState(scene.names, mode=mode or (old.mode if old else "ghosted-ao"), paths=scene.paths)
        if old is not None:
            state.settings, state.atlas_max, state.show_atlas = old.settings, old.atlas_max, old.show_atlas
            state.measure, state.navigation_fps = old.measure, old.navigation_fps
            state.panel_width, state.show_cube = old.panel_width, old.show_cube
            self.renderer.release()
        self.state = state
        self.renderer = Renderer(self.ctx, scene, state.settings)
        self.renderer.measure = state.measure
        self.renderer.atlas_sizing = "ahead"  # no frame waits for the GPU to size the atlas (rtta.passes.atlas_gpu)
        self.renderer.python_warnings = False  # what it degrades is said in the panel (frame())
        projection = self.orbit.projection if old is not None else "perspective"
        self.orbit = Orbit.default(scene.center, scene.radius, up_axis=scene.up_axis)
        self.orbit.projection = projection
        self.ruler = Ruler()
        self.views = saved.Views(self.views_dir, scene)
        self.records = None
        self.scene_label = printable(Path(scene.source).name)  # a file name of any bytes: imgui takes UTF-8
        self.scene_dir = Path(scene.source).parent if Path(scene.source).exists() else Path.cwd()
        self._capture_key = self._composite_key = self._std_key = None
        self.budget = FrameBudget()  # its target follows state.navigation_fps when used
        self._triangles = scene.index_ranges[:, 1] // 3  # per object
        self._thinning: KeepShare | None = None  # fast navigation's, kept while the focus is
        self.left_out = 0  # parts left out of the last capture (fast navigation; a frame late on the GPU)
        self._thinned = False  # the last capture was asked to leave parts out
        self._moved = False  # the last frame captured while the camera moved
        self.frame_objects()

    def frame_objects(self, ids=None) -> None:
        """Fit these objects (default: every one not hidden) in the composite, with a margin
        on all four sides at the composite's aspect; the view direction is kept."""
        scene = self.renderer.scene
        if ids is None:
            ids = [i for i in range(scene.count) if i not in self.state.hidden] or range(scene.count)
        ids = np.asarray(list(ids), np.int64)
        moved = self.renderer.staging.offsets  # exploded: where the parts are drawn
        corners = (scene.box_corners("aabb")[ids] + (0.0 if moved is None else moved[ids, None, :])).reshape(-1, 3)
        corners = corners + scene.origin
        _, _, w, h = self.layout.composite
        self.orbit.frame(corners=corners, aspect=w / h if w > 0 and h > 0 else 1.0)

    def say(self, text: str, error: bool = False) -> bool:
        self.message, self.message_is_error = printable(text), error
        return not error

    @property
    def capture_paths(self) -> list[str]:
        caps = self.renderer.caps
        return ["vs", "gs"] if caps.vertex_layer else ["gs"]

    # ---- frame -------------------------------------------------------------------------
    def frame(self) -> None:
        """One frame into the window's framebuffer (call swap_buffers after it)."""
        t_frame = time.perf_counter()
        self.stats.tick()
        if self.turn is not None and self.turn.step(self.orbit):
            self.turn = None
        if self._moved and self.stats.history:  # the last frame's time steers fast navigation
            self.budget.update(self.stats.history[-1])
        self._moved = False
        self._take_loaded()
        minimized = self.wnd.width <= 0 or self.wnd.height <= 0
        size = (0, 0) if minimized else self.wnd.buffer_size
        self.layout = Layout.of(size, self.state.show_atlas, self.state.panel_width)
        self.imgui.io.display_size = imgui.ImVec2(*self.wnd.size)
        t0 = time.perf_counter()
        imgui.new_frame()
        panels.draw(self)
        ui_ms = (time.perf_counter() - t0) * 1e3
        self.wnd.fbo.viewport = (0, 0, *size)
        self.wnd.use()
        self.ctx.clear(*WINDOW_CLEAR, 1.0)
        self._rendered = False
        if size[0] > 0 and size[1] > 0:
            self.renderer.timings.clear()
            said = len(self.renderer.warnings)
            try:
                self._draw_composite()
                self._draw_atlas()
            except RttaError as exc:  # e.g. targets too large for a huge window: say so, keep going
                self.say(str(exc), error=True)
            if len(self.renderer.warnings) > said:  # what was degraded (each said once per scene)
                self.say("warning: " + "; ".join(self.renderer.warnings[said:]))
            self.stats.stage_ms = dict(self.renderer.timings)  # what ran this frame
            self.stats.last_ms.update(self.renderer.timings)  # for the panel: the last run of each
        overlay.draw(self)
        t1 = time.perf_counter()
        imgui.render()
        self.wnd.fbo.viewport = (0, 0, *size)
        self.imgui.render(imgui.get_draw_data())
        self.renderer.measure = self.state.measure
        if self.state.measure:
            self.ctx.finish()
            self.stats.stage_ms["ui"] = self.stats.last_ms["ui"] = ui_ms + (time.perf_counter() - t1) * 1e3
        cam = self.orbit.camera()
        key = (tuple(cam.eye), tuple(cam.target), cam.kind, size)
        moving, self._camera_key = key != self._camera_key, key
        self.camera_still = not moving
        frame_ms = (time.perf_counter() - t_frame) * 1e3
        self.stats.done(moving, frame_ms, dict(self.stats.stage_ms) if self._rendered else None)

    def turn_to(self, az: float, el: float) -> None:
        """Turn the camera to (az, el) over a moment (the view cube, the view keys)."""
        self.turn = Turn.to(self.orbit, az, el)

    def stop_turn(self) -> None:
        """Leave the camera where a view turn under way has taken it."""
        self.turn = None

    def measure_at(self, x: float, y: float) -> None:
        """The measure tool's click at window point (x, y): a point of a measurement."""
        cx, cy, _, ch = self.layout.composite
        vp = self.viewport
        self.renderer.hidden = self.state.hidden
        found = ruler.point_at(self.renderer, self.orbit.camera(), vp, int(x - cx), int(cy + ch - 1 - y))
        self._std_key = None  # the direct drawing it made is not the one shown
        if found is None:
            self.say("measure: nothing there (click on a part)")
            return
        point, oid, snapped = found
        m = self.ruler.add(point, self.renderer.scene.names[oid])
        if m is None:
            self.say(f"measure: from {self.renderer.scene.names[oid]}" + (" (vertex)" if snapped else ""))
        else:
            length, delta = ruler.describe(m, self.renderer.scene.unit, self.renderer.scene.radius)
            self.say(f"measured {length} ({delta})")

    @property
    def viewport(self) -> tuple[int, int]:
        """Composite viewport size, capped at the largest texture the GL allows."""
        cap = self.renderer.caps.max_texture
        _, _, w, h = self.layout.composite
        return min(w, cap), min(h, cap)

    def _capture(self, camera) -> None:
        vp = self.viewport
        focus = self.renderer.scaled_for(self.state.style.focus)  # empty unless a context scale
        normals = self.renderer.needs_normals(self.state.shown_mode())  # ghosted-ao, the projector
        key = (tuple(camera.eye), tuple(camera.target), vp, camera.kind, self.state.capture_key(), focus, normals)
        if key != self._capture_key or self._thinned:  # a view at rest is captured whole
            moving = self._capture_key is not None and key[:2] != self._capture_key[:2]
            self.renderer.hidden = self.state.hidden
            thin = self._navigation_thinning() if moving else None
            # no id image: compositing never reads it, picking reads depths (rtta.passes.picking)
            self.records = None  # else R of the last frame, still held, is read back first (GpuScene.keep_held)
            self.records = self.renderer.capture(camera, vp, focus=focus, normals=normals, ids=False, thin=thin)
            self._thinned, self.left_out = thin is not None, 0 if thin is None else thin.left
            self._capture_key, self._composite_key = key, None
            self._moved = moving
            self._rendered = True

    def _navigation_thinning(self):
        """While the camera moves: what picks the smallest parts on screen in the frame's own
        projection, as many as the frame budget asks (rtta.renderer.navigation), and counts
        them in `left_out`; None with fast navigation off."""
        fps = self.state.navigation_fps
        if fps <= 0:
            return None
        self.budget.target_ms = 1e3 / fps
        keep = self.budget.keep
        if keep >= FULL or self.renderer.scene.count < MIN_OBJECTS:  # none left out
            return None
        focus = self.state.focus_mask()  # the same array until the focus changes
        if self._thinning is None or self._thinning.protect is not focus:  # weights uploaded once per focus
            self._thinning = KeepShare(keep, self._triangles, focus, key=object())
        self._thinning.keep = keep  # on the GPU where Algorithm 1 is (rtta.passes.thin_gpu)
        return self._thinning

    def _draw_composite(self) -> None:
        vp, s, r = self.viewport, self.state, self.renderer
        mode = s.shown_mode()
        if vp[0] < 1 or vp[1] < 1:
            return  # minimized or no room: nothing to draw, nothing to capture
        camera = self.orbit.camera()
        r.projector = self._projector(camera)
        r.lens = self._lens()
        restage(r, s.cutaway.staging(r.scene))  # sections and explode (viewer.cutaway)
        painted = (
            s.projector.key(),
            tuple(camera.eye) if s.projector.on and s.projector.attached else None,
            s.lens.key(),
            s.cutaway.key(),
        )
        atlas_visible = s.show_atlas and self.layout.atlas[2] > 0
        if mode != "std" or atlas_visible:
            self._capture(camera)
        if mode == "std":
            key = (tuple(camera.eye), tuple(camera.target), camera.kind, vp, painted, s.hidden_rev)
            if key != self._std_key:  # a static view is not drawn again
                r.hidden = s.hidden
                r.std(camera, vp, s.style.focus)
                self._std_key = key
                self._rendered = True
            target = r.single_target
            extent = (vp[0] / target.size[0], vp[1] / target.size[1])
            self.view_pass.render(
                texture=target.color,
                layer=0,
                depth=target.depth,
                extent=extent,
                rect=self._rect(vp),
                window_height=self.wnd.buffer_size[1],
                target=self.wnd.fbo,
            )
            return
        key = (self._capture_key, s.style_key(), painted)
        if key != self._composite_key:
            r.composite(Mode(mode), s.style)  # (not std here)
            self.records = r.last[0] if r.last is not None else self.records  # a re-capture (focus, normals)
            self._composite_key = key
            self._rendered = True
        self.view_pass.render(
            texture=r.target.color,
            extent=r.target.extent,
            rect=self._rect(vp),
            window_height=self.wnd.buffer_size[1],
            target=self.wnd.fbo,
        )

    @property
    def mouse(self) -> tuple[float, float]:
        """The last mouse position in window pixels (the overlay's tooltip follows it)."""
        return self.controls.mouse

    @property
    def splitting(self) -> bool:
        return self.controls.splitting

    def _rect(self, vp: tuple[int, int]) -> tuple[int, int, int, int]:
        x, y, _, _ = self.layout.composite
        return (x, y, vp[0], vp[1])

    def atlas_tiles(self) -> list[tuple[int, tuple]]:
        """(layer, screen rect) of each atlas layer shown, below the atlas view's label."""
        x, y, w, h = self.layout.atlas
        rec = self.records
        if not self.state.show_atlas or rec is None:
            return []
        return layer_tiles(
            (x, y + LABEL_HEIGHT, w, h - LABEL_HEIGHT), rec.atlas_size[:2], rec.atlas_size[2], self.state.atlas_layer
        )

    def _draw_atlas(self) -> None:
        atlas, rec = self.renderer.atlas, self.records
        if rec is None or atlas is None:
            return  # nothing captured yet
        for layer, rect in self.atlas_tiles():
            self.view_pass.render(
                texture=atlas.color,
                layer=layer,
                depth=atlas.depth,
                rect=rect,
                extent=(rec.atlas_size[0] / atlas.size[0], rec.atlas_size[1] / atlas.size[1]),
                background=ATLAS_BACKGROUND,
                window_height=self.wnd.buffer_size[1],
                target=self.wnd.fbo,
            )

    def release(self) -> None:
        self.renderer.release()
        self.view_pass.release()
        self.imgui.shutdown()
