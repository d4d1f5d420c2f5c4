"""The imgui side panel: scene, mode, highlights, style, atlas settings and stats.

Each section is one short function reading and writing the viewer's state; the viewer
decides what to re-run from the state afterwards (capture or compositing only).
"""

from __future__ import annotations

from typing import TYPE_CHECKING

import numpy as np
from imgui_bundle import imgui, implot

from rtta.gl.context import CapturePath
from rtta.ldi.lens import SHAPES as LENS_SHAPES
from rtta.ldi.lens import LensShape
from rtta.passes.composite import LENS_MODES, ROLES
from rtta.passes.oit import ORDERS
from rtta.scene.model import BOUNDS

from . import cutaway, tree
from .state import ATLAS_MAX_CHOICES, NAVIGATION_FPS, VIEW_MODES

if TYPE_CHECKING:
    from .commands import PanelsHost

ERROR_COLOR = imgui.ImVec4(1.0, 0.45, 0.4, 1.0)
STAGES = ("parameterize", "capture", "post", "composite", "std", "ui")


def draw(app: PanelsHost) -> None:
    x, y, w, h = app.layout.panel
    if w <= 0 or h <= 0:
        return
    imgui.set_next_window_pos(imgui.ImVec2(x, y))
    imgui.set_next_window_size(imgui.ImVec2(w, h))
    flags = imgui.WindowFlags_.no_move.value | imgui.WindowFlags_.no_resize.value | imgui.WindowFlags_.no_collapse.value
    imgui.begin("rtta", None, flags)
    _scene(app)
    _mode(app)
    imgui.push_item_width(-120)
    _objects(app)
    _stats(app)
    _style(app)
    _projector(app)
    _lens(app)
    cutaway.panel(app)
    _atlas(app)
    imgui.pop_item_width()
    imgui.end()
    app.files.draw()


def _scene(app: PanelsHost) -> None:
    imgui.text(f"{app.scene_label}  ({app.renderer.scene.count} objects)")
    if imgui.button("Open... (O)"):
        app.files.open(app.scene_dir)
    imgui.same_line()
    if imgui.button("Screenshot (F12)"):
        app.screenshot()
    if app.message:
        imgui.push_text_wrap_pos(0.0)
        imgui.text_colored(ERROR_COLOR if app.message_is_error else imgui.ImVec4(0.6, 0.9, 0.6, 1), app.message)
        imgui.pop_text_wrap_pos()


def _mode(app: PanelsHost) -> None:
    s = app.state
    changed, i = imgui.combo("mode (M)", VIEW_MODES.index(s.mode), list(VIEW_MODES))
    if changed:
        s.mode = VIEW_MODES[i]
    _, s.show_atlas = imgui.checkbox("atlas view (A)", s.show_atlas)
    imgui.same_line()
    if imgui.button("frame all (F)"):
        app.frame_objects()
    if s.mode == "std":
        imgui.text_disabled("STD draws the scene directly: no highlights")


def _objects(app: PanelsHost) -> None:
    tree.draw(app)


def _style(app: PanelsHost) -> None:
    st = app.state.style
    if not imgui.collapsing_header("Style", imgui.TreeNodeFlags_.default_open.value):
        return
    _, st.context_opacity = imgui.slider_float("context opacity", st.context_opacity, 0.0, 1.0)
    _, st.desaturate = imgui.slider_float("desaturate", st.desaturate, 0.0, 1.0)
    _, st.default_opacity = imgui.slider_float("opacity (transp.)", st.default_opacity, 0.0, 1.0)
    _, st.edge_width = imgui.slider_int("edge width", st.edge_width, 1, 4)
    _, st.edge_color = _color("edge colour", st.edge_color)
    _, st.outline_width = imgui.slider_int("outline width", st.outline_width, 1, 4)
    _, st.outline_color = _color("outline colour", st.outline_color)
    _, st.ao_radius = imgui.slider_float("AO radius (px)", st.ao_radius, 1.0, 16.0)
    _, st.ao_strength = imgui.slider_float("AO strength", st.ao_strength, 0.0, 2.0)
    _, st.halo = imgui.slider_int("halo (px)", st.halo, 0, 16)
    for label, attr, choices in (
        ("AO on", "ao_objects", ROLES),
        ("edges on", "edge_objects", ROLES),
        ("transparency order", "order", ORDERS),
    ):
        changed, i = imgui.combo(label, choices.index(getattr(st, attr)), list(choices))
        if changed:
            setattr(st, attr, choices[i])


def _projector(app: PanelsHost) -> None:
    p = app.state.projector
    if not imgui.collapsing_header("projector (P)"):
        return
    _, p.on = imgui.checkbox("project the grid", p.on)
    _, p.attached = imgui.checkbox("attached to the camera", p.attached)
    if not p.attached:
        _, p.az = imgui.slider_float("azimuth (Ctrl+Left/Right)", p.az, 0.0, 360.0)
        _, p.el = imgui.slider_float("elevation (Ctrl+Up/Down)", p.el, -89.0, 89.0)
        _, p.dist = imgui.slider_float("distance (radii)", p.dist, 0.5, 6.0)
    _, p.fov = imgui.slider_float("fov (deg)", p.fov, 5.0, 120.0)
    _, p.strength = imgui.slider_float("strength", p.strength, 0.0, 1.0)
    _, p.shadows = imgui.checkbox("shadows", p.shadows)


def _lens(app: PanelsHost) -> None:
    p = app.state.lens
    if not imgui.collapsing_header("lens (C)"):
        return
    _, p.on = imgui.checkbox("cut the context away (ghosted modes)", p.on)
    changed, i = imgui.combo("shape", LENS_SHAPES.index(p.shape), list(LENS_SHAPES))
    if changed:
        p.shape = LensShape(LENS_SHAPES[i])
    _, p.radius = imgui.slider_float("radius (scene radii)", p.radius, 0.02, 1.5)
    _, p.follow = imgui.checkbox("follows the mouse (Space)", p.follow)
    if imgui.button("on the focus"):
        p.center = None
    if p.on and app.state.mode not in LENS_MODES:
        imgui.text_disabled("the lens cuts in ghosted modes")


def _color(label: str, rgba) -> tuple[bool, tuple]:
    changed, col = imgui.color_edit4(label, list(rgba), imgui.ColorEditFlags_.no_inputs.value)
    return changed, tuple(col)


def _atlas(app: PanelsHost) -> None:
    s = app.state
    if not imgui.collapsing_header("Atlas", imgui.TreeNodeFlags_.default_open.value):
        return
    _, s.settings.border = imgui.slider_int("border (px)", s.settings.border, 0, 4)
    changed, i = imgui.combo("max size", ATLAS_MAX_CHOICES.index(s.atlas_max), list(ATLAS_MAX_CHOICES))
    if changed:
        s.set_atlas_max(ATLAS_MAX_CHOICES[i])
    _, s.settings.region_scale = imgui.slider_float("region scale", s.settings.region_scale, 0.25, 2.0, "%.2f")
    _, s.settings.context_scale = imgui.slider_float("context scale", s.settings.context_scale, 0.25, 1.0, "%.2f")
    changed, i = imgui.combo("bounds", BOUNDS.index(s.settings.bounds), list(BOUNDS))
    if changed:
        s.settings.bounds = BOUNDS[i]
    paths = app.capture_paths
    current = app.renderer.caps.capture_path(s.settings.capture_path)
    changed, i = imgui.combo("capture path", paths.index(current), paths)
    if changed:
        s.settings.capture_path = CapturePath(paths[i])
    layers = app.records.atlas_size[2] if app.records is not None else 0
    if layers > 0:
        _, s.atlas_layer = imgui.slider_int(
            "layer (L)", min(s.atlas_layer, layers - 1), -1, layers - 1, "all" if s.atlas_layer < 0 else "%d"
        )


def _navigation(app: PanelsHost) -> None:
    """Fast navigation: the frame rate it keeps while moving, and what it left out."""
    s = app.state
    on = s.navigation_fps > 0
    changed, on = imgui.checkbox("fast navigation", on)
    if imgui.is_item_hovered():
        imgui.set_tooltip(
            "while the camera moves, leave out the parts smallest on screen to keep the frame rate\n"
            "(scenes of 500 parts or more); a view at rest always shows every part"
        )
    if changed:
        s.navigation_fps = NAVIGATION_FPS if on else 0.0
    if on:
        _, s.navigation_fps = imgui.slider_float("target fps", s.navigation_fps, 1.0, 60.0, "%.0f")


def _stats(app: PanelsHost) -> None:
    if not imgui.collapsing_header("Stats", imgui.TreeNodeFlags_.default_open.value):
        return
    st = app.stats
    imgui.text(f"frame {st.mean_ms():6.1f} ms  ({st.fps():5.1f} fps)")
    _, app.state.measure = imgui.checkbox("time stages (syncs the GPU)", app.state.measure)
    _navigation(app)
    for k in STAGES:
        if k in st.last_ms:
            ran = k in st.stage_ms
            imgui.text(f"  {k:<13}{st.last_ms[k]:7.1f} ms" + ("" if ran else "  (reused)"))
    r = app.records
    if r is not None:
        n, vis = len(r.visible), int(r.visible.sum())
        left = app.left_out
        imgui.text(f"visible {vis}  culled {n - vis - left}" + (f"  left out {left}" if left else ""))
        imgui.text(f"atlas {r.atlas_size[0]}x{r.atlas_size[1]} x {r.atlas_size[2]} layers")
        imgui.text(f"utilization {100 * r.utilization:.0f}%")
    history = np.asarray(st.history, np.float32)
    if len(history) and implot.begin_plot("##frametime", imgui.ImVec2(-1, 110)):
        implot.setup_axes("frame", "ms")
        implot.setup_axis_limits(
            implot.ImAxis_.y1.value, 0, max(50.0, float(history.max()) * 1.1), imgui.Cond_.always.value
        )
        implot.setup_axis_limits(
            implot.ImAxis_.x1.value, 0, float(st.history.maxlen or len(history)), imgui.Cond_.always.value
        )
        implot.plot_line("frame ms", history)
        implot.end_plot()
