"""Panel sections of the CAD basics: the view (projection, standard views), the measure tool
and its measurements, and the saved views. Each is a function of the app, as in
viewer.panels, which lists the sections it draws."""

from __future__ import annotations

from typing import TYPE_CHECKING

from imgui_bundle import imgui

from rtta.errors import RttaError
from rtta.scene.framing import STANDARD_VIEWS

from . import ruler, saved
from .tree import button_width, same_line_if

if TYPE_CHECKING:
    from .commands import PanelsHost

VIEW_KEYS = {"front": "1", "back": "Ctrl+1", "right": "3", "left": "Ctrl+3", "top": "7", "bottom": "Ctrl+7", "iso": "0"}


def view(app: PanelsHost) -> None:
    """Projection and the standard views (relative to the file's up axis)."""
    o = app.orbit
    imgui.text("view")
    for k, name in enumerate(("perspective", "ortho")):
        imgui.same_line()
        if imgui.radio_button(name + (" (5)" if k else ""), o.projection == name):
            o.projection = name
    same_line_if(imgui.calc_text_size("cube").x + 40)
    _, app.state.show_cube = imgui.checkbox("cube", app.state.show_cube)
    for k, name in enumerate(STANDARD_VIEWS):
        if k:
            same_line_if(button_width(name))
        if imgui.small_button(name):
            app.turn_to(*STANDARD_VIEWS[name])
        if imgui.is_item_hovered():
            imgui.set_tooltip(
                f"the {name} view, about the file's {app.renderer.scene.up_axis.upper()} up (key {VIEW_KEYS[name]})"
            )


def measure(app: PanelsHost) -> None:
    """The measure tool: on/off, the measurements (distance, deltas), clear."""
    r, scene = app.ruler, app.renderer.scene
    flags = imgui.TreeNodeFlags_.default_open.value if r.on or r.done else 0
    if not imgui.collapsing_header(f"Measure (R){f'  {len(r.done)}' if r.done else ''}###measure", flags):
        return
    changed, r.on = imgui.checkbox("measure: click two points", r.on)
    if changed:
        r.first = None
    if r.done:
        same_line_if(button_width("clear"))
        if imgui.small_button("clear"):
            r.clear()
    if r.on and r.first is not None:
        imgui.text_disabled(f"from {r.first[1]}: click the second point (Esc: drop it)")
    unit = scene.unit or "(no unit in the file)"
    if r.done:
        imgui.text_disabled(f"unit: {unit}")
    remove = None
    for k, m in enumerate(r.done):
        length, delta = ruler.describe(m, scene.unit, scene.radius)
        imgui.push_id(k)
        if imgui.small_button("x"):
            remove = k
        imgui.same_line()
        imgui.text(f"#{k + 1} {length}")
        imgui.text_disabled(f"    {delta}")
        if imgui.is_item_hovered():
            imgui.set_tooltip(f"{m.parts[0]} -> {m.parts[1]}")
        imgui.pop_id()
    if remove is not None:
        del r.done[remove]


def views(app: PanelsHost) -> None:
    """Saved views: a name and Save, the list (click: restore), and where they are kept."""
    v = app.views
    if not imgui.collapsing_header("Saved views"):
        return
    imgui.set_next_item_width(max(80.0, imgui.get_content_region_avail().x - button_width("save")))
    _, v.name = imgui.input_text_with_hint("##viewname", "view name", v.name)
    imgui.same_line()
    if imgui.small_button("save"):
        save(app, v.name or f"view{len(v.names()) + 1}")
    remove = None
    for name in v.names():
        imgui.push_id(name)
        if imgui.small_button("x"):
            remove = name
        imgui.same_line()
        if imgui.selectable(name, False)[0]:
            restore(app, name)
        imgui.pop_id()
    if remove is not None:
        try:
            v.delete(remove)
        except RttaError as exc:
            app.say(str(exc), error=True)
    imgui.push_text_wrap_pos(0.0)
    imgui.text_disabled(f"in {v.folder}")
    imgui.pop_text_wrap_pos()


def save(app: PanelsHost, name: str) -> None:
    """Save the view shown as `name` (one line in the panel says where, or why not)."""
    try:
        path = app.views.save(name, saved.capture(app.renderer.scene, app.state, app.orbit))
    except (RttaError, OSError) as exc:
        app.say(f"view not saved: {exc}", error=True)
        return
    app.views.name = ""
    app.say(f"saved view {path.stem} ({path})")


def restore(app: PanelsHost, name: str) -> None:
    """Show the saved view `name`."""
    try:
        saved.apply(app.views.load(name), app.renderer.scene, app.state, app.orbit)
    except RttaError as exc:
        app.say(f"view not restored: {exc}", error=True)
        return
    app.say(f"view {name}")
