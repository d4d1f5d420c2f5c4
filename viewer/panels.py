"""The imgui side panel: scene, mode, view, the part tree, then the sections in SECTIONS
(measure, saved views, stats, style, projector, lens, atlas).

Each section is one short function of the app reading and writing the viewer's state; the
viewer decides what to re-run from the state afterwards (capture or compositing only). A new
section is a function added to SECTIONS (a module of its own, as viewer.panel_view). The tree
takes the height the sections below it leave.
"""

from __future__ import annotations

from collections.abc import Callable
from typing import TYPE_CHECKING

import numpy as np
from imgui_bundle import imgui, implot

from rtta.gl.context import CapturePath
from rtta.ldi.lens import SHAPES as LENS_SHAPES
from rtta.ldi.lens import LensShape
from rtta.passes.composite import LENS_MODES, ROLES
from rtta.passes.oit import ORDERS
from rtta.scene.bounds import Bounds
from rtta.scene.model import BOUNDS

from . import cutaway, panel_view, tree
from .commands import records_to_read
from .state import ATLAS_MAX_CHOICES, GHOSTED, NAVIGATION_FPS, VIEW_MODES

if TYPE_CHECKING:
    from .commands import PanelsHost

ERROR_COLOR = imgui.ImVec4(1.0, 0.45, 0.4, 1.0)
MESSAGE_COLOR = imgui.ImVec4(0.6, 0.9, 0.6, 1)
STAGES = ("parameterize", "capture", "post", "composite", "std", "ui")
LABEL_WIDTH = "transparency order"  # the widest label of a slider or a combo: its room on the right
_below = {"height": 0.0}  # what the sections below the tree took the last frame


def draw(app: PanelsHost) -> None:
    x, y, w, h = app.layout.panel
    if w <= 0 or h <= 0:
        return
    imgui.set_next_window_pos(imgui.ImVec2(x, y))
    imgui.set_next_window_size(imgui.ImVec2(w, h))
    flags = imgui.WindowFlags_.no_move.value | imgui.WindowFlags_.no_resize.value | imgui.WindowFlags_.no_collapse.value
    flags |= imgui.WindowFlags_.no_title_bar.value
    imgui.begin("rtta", None, flags)
    _scene(app)
    _mode(app)
    panel_view.view(app)
    imgui.push_item_width(-(imgui.calc_text_size(LABEL_WIDTH).x + imgui.get_style().item_inner_spacing.x * 2))
    tree.draw(app, reserve=_below["height"])
    top = imgui.get_cursor_pos_y()
    for section in SECTIONS:
        section(app)
    _below["height"] = imgui.get_cursor_pos_y() - top + imgui.get_style().window_padding.y
    imgui.pop_item_width()
    imgui.end()
    app.files.draw()


def _scene(app: PanelsHost) -> None:
    imgui.text_wrapped(f"{app.scene_label}  ({app.renderer.scene.count} objects)")
    if imgui.button("Open... (O)"):
        app.files.open(app.scene_dir)
    tree.same_line_if(tree.button_width("Screenshot (F12)") + 8)
    if imgui.button("Screenshot (F12)"):
        app.screenshot()
    if imgui.is_item_hovered():
        imgui.set_tooltip(f"into {app.screenshot_dir}")
    if app.message:
        _message(app.message, ERROR_COLOR if app.message_is_error else MESSAGE_COLOR)


def _message(text: str, color: imgui.ImVec4) -> None:
    """The message line: one line, wrapped when it fits in two; longer ones and several
    ('; '-separated: the load's warnings) fold into one line that opens to show them all."""
    parts = [p for p in text.split("; ") if p]
    width = imgui.get_content_region_avail().x
    if len(parts) <= 1 and imgui.calc_text_size(text).x <= 2 * width:
        imgui.push_text_wrap_pos(0.0)
        imgui.text_colored(color, text)
        imgui.pop_text_wrap_pos()
        return
    more = f" (+{len(parts) - 1} more)" if len(parts) > 1 else " ..."
    head = tree.fit_text(parts[0], width - imgui.calc_text_size(more).x - imgui.get_tree_node_to_label_spacing())
    imgui.push_style_color(imgui.Col_.text.value, color)
    opened = imgui.tree_node(f"{head}{more}###message")
    imgui.pop_style_color()
    if imgui.is_item_hovered() and not opened:
        imgui.set_tooltip("click to show all")
    if opened:
        imgui.push_text_wrap_pos(0.0)
        for p in parts:
            imgui.bullet()
            imgui.text_colored(color, p)
        imgui.pop_text_wrap_pos()
        imgui.tree_pop()


def _mode(app: PanelsHost) -> None:
    s = app.state
    changed, i = imgui.combo("mode (M)", VIEW_MODES.index(s.mode), list(VIEW_MODES))
    if changed:
        s.choose_mode(VIEW_MODES[i])
    _, s.show_atlas = imgui.checkbox("atlas view (A)", s.show_atlas)
    imgui.same_line()
    if imgui.button("frame all (F)"):
        app.frame_objects()
    if s.mode == "std":
        imgui.text_disabled("STD draws the scene directly: no highlights")
    elif s.mode in GHOSTED and s.shown_mode() == "std":
        imgui.push_text_wrap_pos(0.0)
        imgui.text_disabled(f"solid until a part is highlighted (click one), then {s.mode}")
        imgui.pop_text_wrap_pos()


def _style(app: PanelsHost) -> None:
    st = app.state.style
    if not imgui.collapsing_header("Style"):
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
    _, p.radius = imgui.slider_float("radius (radii)", p.radius, 0.02, 1.5)
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
    if not imgui.collapsing_header("Atlas"):
        return
    _, s.settings.border = imgui.slider_int("border (px)", s.settings.border, 0, 4)
    changed, i = imgui.combo("max size", ATLAS_MAX_CHOICES.index(s.atlas_max), list(ATLAS_MAX_CHOICES))
    if changed:
        s.set_atlas_max(ATLAS_MAX_CHOICES[i])
    _, s.settings.region_scale = imgui.slider_float("region scale", s.settings.region_scale, 0.25, 2.0, "%.2f")
    _, s.settings.context_scale = imgui.slider_float("context scale", s.settings.context_scale, 0.25, 1.0, "%.2f")
    changed, i = imgui.combo("bounds", BOUNDS.index(s.settings.bounds), list(BOUNDS))
    if changed:
        s.settings.bounds = Bounds(BOUNDS[i])
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
    if not imgui.collapsing_header("Stats"):
        return
    st = app.stats
    if st.moving_ms:
        imgui.text(f"moving  {st.fps('moving'):5.1f} fps  ({st.mean_ms(which='moving'):6.1f} ms a frame)")
    else:
        imgui.text_disabled("moving  - (orbit, pan or zoom to measure)")
    if imgui.is_item_hovered():
        imgui.set_tooltip("the frame rate while the view moves (the last 30 such frames)")
    imgui.text_disabled(f"at rest {st.fps('rest'):5.1f} fps  (redraws of the panel alone)")
    _, app.state.measure = imgui.checkbox("time stages (syncs the GPU)", app.state.measure)
    _navigation(app)
    if st.rendered is not None and app.state.measure:
        total, stages = st.rendered
        imgui.text(f"last rendered frame {total:6.1f} ms:")
        for k in STAGES:
            if k in stages:
                imgui.text(f"  {k:<13}{stages[k]:7.1f} ms")
        imgui.text_disabled(f"  {'other':<13}{max(0.0, total - sum(stages.values())):7.1f} ms")
    r = records_to_read(app)
    if r is not None:
        n, vis = len(r.visible), int(r.visible.sum())
        left = app.left_out
        imgui.text(f"visible {vis}  culled {n - vis - left}" + (f"  left out {left}" if left else ""))
        imgui.text(f"atlas {r.atlas_size[0]}x{r.atlas_size[1]} x {r.atlas_size[2]} layers")
        imgui.text(f"utilization {100 * r.utilization:.0f}%")
    elif app.records is not None:  # moving: R stays on the GPU (commands.records_to_read)
        size = app.records.atlas_size
        imgui.text(f"atlas {size[0]}x{size[1]} x {size[2]} layers")
        imgui.text_disabled("parts and utilization counted when the view rests")
    history = np.asarray(st.history, np.float32)
    if len(history) and implot.begin_plot("##frametime", imgui.ImVec2(-1, 110), implot.Flags_.no_legend.value):
        implot.setup_axes("frame", "ms")
        implot.setup_axis_limits(
            implot.ImAxis_.y1.value, 0, max(50.0, float(history.max()) * 1.1), imgui.Cond_.always.value
        )
        implot.setup_axis_limits(
            implot.ImAxis_.x1.value, 0, float(st.history.maxlen or len(history)), imgui.Cond_.always.value
        )
        implot.plot_line("frame ms", history)
        implot.end_plot()


SECTIONS: list[Callable[[PanelsHost], None]] = [
    panel_view.measure,
    panel_view.views,
    _stats,
    _style,
    _projector,
    _lens,
    cutaway.panel,
    _atlas,
]  # drawn in this order below the part tree
